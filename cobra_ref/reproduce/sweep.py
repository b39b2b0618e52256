"""``cobra-ref sweep``: how reliable is the contact solve? Randomized scenarios, each checked.

A reliability sweep of the step over the conditions the package meets. ``scenarios`` draws N
scenarios from one seed, each independently:

* a gait (C, S, J, J-mirror, sidewinding) with its parameters uniform within the optimizer's
  bounds (``planning.problem.DECISION``);
* mu (robot-ground and box-ground) uniform in [0.3, 1.5], mu_robot_box in [0.3, mu];
* the box's mass log-uniform in [0.1, 2] kg;
* dt log-uniform in [0.5, 2] ms;
* the servo: position or prescribed, one each in turn; the contact law: ``laws`` in turn.

``run_scenario`` simulates one for ``duration`` seconds and measures, each a condition of
[COBRA] eq. (2)-(6) or of the energy ledger: the share of steps whose friction fixed point
converged, the largest friction outside Coulomb's circle (relative to mu p_N), the largest
natural residual of Coulomb's law, complementarity, penetration, the ledger's residual
|W_act + W_contact - Delta(KE + PE)| relative to the actuators' work (the bodies' work-energy
balance; the contacts' work splits into the springs' stored energy and what the dampers and
friction dissipate, ``contact_dissipation`` = -W_contact - Delta E_elastic >= 0), the box's
largest tilt, and the wall time.

Penetration is judged as the solver's error, ``penetration_error``: a compliant contact is a
spring, pressed by its normal force F_N to the deflection F_N / k, so the error is the largest
penetration - F_N / k over the loaded contacts of the contact log (penetration = -``contact_gap``);
with the rigid law, the penetration itself. The 1 mm line of ``CHECKS`` applies to that error.

A scenario that left physics (A32: prescribed joints that need torques beyond tau_max, or a
contact's normal force beyond ``simulate.contact_force_bound``; ``Trajectory.beyond_limits``) is
recorded with its reasons (``left_physics``), the share of steps and the worst values, and its run's
``LeftPhysicsWarning`` is not printed. ``summarize`` gives each measure's worst, median and 90th
percentile over the physical scenarios and, apart, over those that left physics, and the scenarios
that fail the thresholds of ``CHECKS``: ``failing`` among the physical ones (what the command's exit
status counts), ``failing_left_physics`` among the others.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import asdict, dataclass

import numpy as np

from . import analysis
from ..gaits import gait
from ..params import CobraParameters
from ..planning.problem import DECISION
from ..robots import cobra_model
from ..simulate import LeftPhysicsWarning, simulate
from ..step import SimulationError, StepSettings

GAITS = ("C", "S", "J", "J-mirror", "sidewinding")
# measure -> (threshold, "max" or "min"): what each scenario must meet
CHECKS = {"converged": (0.999, "min"), "cone_residual": (1e-3, "max"), "penetration_error": (1e-3, "max"),
          "ledger_residual": (1e-2, "max")}


@dataclass(frozen=True)
class Scenario:
    """One randomized run (module docstring)."""

    index: int
    gait: str
    params: dict
    mu: float
    mu_robot_box: float
    box_mass: float
    dt: float
    servo: str
    contact: str


def scenarios(n: int, seed: int = 0, laws=("compliant",)) -> list[Scenario]:
    """N scenarios drawn from ``seed`` (module docstring); the same seed gives the same scenarios.
    """
    rng = np.random.default_rng(seed)
    out = []
    for k in range(n):
        name = GAITS[int(rng.integers(len(GAITS)))]
        params = {p: float(rng.uniform(lo, hi)) for p, lo, hi in DECISION[name]}
        mu = float(rng.uniform(0.3, 1.5))
        out.append(Scenario(k, name, params, mu, float(rng.uniform(0.3, mu)), float(np.exp(rng.uniform(np.log(0.1), np.log(2.0)))),
                            float(np.exp(rng.uniform(np.log(5e-4), np.log(2e-3)))), ("position", "prescribed")[k % 2],
                            laws[(k // 2) % len(laws)]))
    return out


def run_scenario(scenario: Scenario, duration: float = 2.0) -> dict:
    """The measures of one scenario's run (module docstring), as a JSON-ready record.

    What the sweep's executor runs (a module-level function: picklable).
    """
    params = CobraParameters(mu=scenario.mu, mu_robot_box=scenario.mu_robot_box, box_mass=scenario.box_mass)
    settings = StepSettings(dt=scenario.dt, servo=scenario.servo, contact=scenario.contact)
    start = time.perf_counter()
    record = {"scenario": asdict(scenario), "error": None}
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", LeftPhysicsWarning)  # recorded in the measures instead
            traj = simulate(cobra_model(params), gait(scenario.gait, **scenario.params), duration, settings)
    except SimulationError as exc:
        traj, record["error"] = exc.trajectory, str(exc)
    record["seconds"] = time.perf_counter() - start
    if traj is not None and len(traj.tau):
        record.update(measures(traj, params.contact_stiffness))
    return record


def penetration_error(traj, stiffness: float) -> float:
    """The solver's error in penetration [m] (module docstring): with the compliant law, the largest
    -``contact_gap`` - F_N / k over the contact log (F_N = ``contact_force`` . ``contact_normal``,
    k = ``stiffness`` [N/m]), at least 0; with the rigid law, the largest penetration."""
    if traj.meta.get("settings", {}).get("contact") != "compliant":
        return float(np.max(traj.steps["max_penetration"], initial=0.0))
    return float(np.max(-traj.contacts["contact_gap"] - traj.contact_normal_force() / stiffness, initial=0.0))


def physics_measures(traj) -> dict:
    """Whether the run left physics (``Trajectory.beyond_limits``, A32): ``left_physics`` (the
    reasons: "tau", "contact_force"; empty within physics), the share of steps and worst value of each."""
    limits = traj.beyond_limits()
    tau, force = limits["tau_beyond_limit"], limits["contact_force_beyond_bound"]
    return {"left_physics": [name for name, v in (("tau", tau), ("contact_force", force)) if v["share_of_steps"]],
            "tau_beyond_share": tau["share_of_steps"], "worst_tau_N_m": tau["worst_N_m"],
            "force_beyond_share": force["share_of_steps"], "worst_normal_force_N": force["worst_N"]}


def measures(traj, stiffness: float) -> dict:
    """The reliability measures of one trajectory (module docstring); ``stiffness``: the compliant
    contact's k [N/m] (``penetration_error``).
    """
    s = traj.steps
    W_contact = float(s["work_contacts"][:-1].sum())
    ledger = analysis.ledger_residual(traj)
    dissipation = -W_contact - float(s["elastic"][-1] - s["elastic"][0])
    qx, qy = traj.box_pose[:, 4], traj.box_pose[:, 5]
    tilt = np.degrees(np.arccos(np.clip(1 - 2 * (qx**2 + qy**2), -1.0, 1.0)))
    return {"steps": int(len(traj.tau)), "converged": float(np.mean(s["fp_converged"])),
            "cone_residual": float(np.max(s["cone_residual"])), "coulomb_residual": float(np.max(s["coulomb_residual"])),
            "complementarity": float(np.max(s["complementarity"])), "max_penetration": float(np.max(s["max_penetration"])),
            "penetration_error": penetration_error(traj, stiffness),
            "ledger_residual": float(ledger), "contact_dissipation": dissipation, "max_box_tilt_deg": float(tilt.max()),
            "us_per_step": 1e6 * traj.wall_time / len(traj.tau), **physics_measures(traj)}


MEASURES = ("converged", "cone_residual", "coulomb_residual", "complementarity", "max_penetration",
            "penetration_error", "ledger_residual", "max_box_tilt_deg", "worst_tau_N_m", "worst_normal_force_N",
            "us_per_step")


def measure_table(records: list[dict]) -> dict:
    """{measure: {"worst", "median", "p90"}} over ``records`` (``MEASURES`` each has; empty for none)."""
    table = {}
    for key in (k for k in MEASURES if records and all(k in r for r in records)):
        values = np.array([r[key] for r in records])
        worst = values.min() if key == "converged" else values.max()
        table[key] = {"worst": float(worst), "median": float(np.median(values)), "p90": float(np.percentile(values, 90))}
    return table


def failing(records: list[dict]) -> dict:
    """{check: the scenarios of ``records`` that fail it} (``CHECKS``)."""
    return {key: [r["scenario"]["index"] for r in records if (r[key] < limit if kind == "min" else r[key] > limit)]
            for key, (limit, kind) in CHECKS.items()}


def summarize(records: list[dict]) -> dict:
    """Worst, median and 90th percentile of each measure over the physical scenarios and, apart, over
    those that left physics; the scenarios that fail ``CHECKS``, physical ones and the others apart.
    """
    done = [r for r in records if "converged" in r]
    physical = [r for r in done if not r.get("left_physics")]
    left = [r for r in done if r.get("left_physics")]
    fail_physical, fail_left = failing(physical), failing(left)
    checks = {k: {"threshold": v[0], "failing": fail_physical[k], "failing_left_physics": fail_left[k]}
              for k, v in CHECKS.items()}
    return {"scenarios": len(records), "completed": len(done), "errors": [r["scenario"]["index"] for r in records if r["error"]],
            "physical": len(physical), "left_physics": [r["scenario"]["index"] for r in left],
            "measures": measure_table(physical), "measures_left_physics": measure_table(left), "checks": checks,
            "steps_converged": float(sum(r["converged"] * r["steps"] for r in done) / max(sum(r["steps"] for r in done), 1))}


def format_summary(summary: dict) -> str:
    """The summary as text: a table per group of scenarios (physical, left physics), one line per
    measure, then the checks.
    """
    left = summary["left_physics"]
    lines = [f"{summary['completed']} of {summary['scenarios']} scenarios completed, {summary['physical']} physical, "
             f"{len(left)} left physics (A32){f' {left}' if left else ''}; friction fixed point converged on "
             f"{100 * summary['steps_converged']:.3f} % of all steps"]
    for title, table in (("physical scenarios", summary["measures"]),
                         ("scenarios that left physics", summary["measures_left_physics"])):
        if table:
            lines.append(f"{title + ':':<28}{'worst':>12}{'median':>12}{'90th pct':>12}")
            lines += [f"  {key:<26}{v['worst']:>12.4g}{v['median']:>12.4g}{v['p90']:>12.4g}" for key, v in table.items()]
    for key, check in summary["checks"].items():
        text = "every physical scenario" if not check["failing"] else f"fails in scenarios {check['failing']}"
        if check["failing_left_physics"]:
            text += f"; of those that left physics, fails in {check['failing_left_physics']}"
        lines.append(f"check {key} ({'>=' if CHECKS[key][1] == 'min' else '<='} {check['threshold']:g}): {text}")
    if summary["errors"]:
        lines.append(f"errors in scenarios {summary['errors']}")
    return "\n".join(lines)
