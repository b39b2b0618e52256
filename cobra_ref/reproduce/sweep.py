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
largest tilt, and the wall time. ``summarize`` gives each measure's worst and median over the
sweep, and how many scenarios meet the thresholds of ``CHECKS``.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass

import numpy as np

from . import analysis
from ..gaits import gait
from ..params import CobraParameters
from ..planning.problem import DECISION
from ..robots import cobra_model
from ..simulate import simulate
from ..step import SimulationError, StepSettings

GAITS = ("C", "S", "J", "J-mirror", "sidewinding")
# measure -> (threshold, "max" or "min"): what each scenario must meet
CHECKS = {"converged": (0.999, "min"), "cone_residual": (1e-3, "max"), "max_penetration": (1e-3, "max"),
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
        traj = simulate(cobra_model(params), gait(scenario.gait, **scenario.params), duration, settings)
    except SimulationError as exc:
        traj, record["error"] = exc.trajectory, str(exc)
    record["seconds"] = time.perf_counter() - start
    if traj is not None and len(traj.tau):
        record.update(measures(traj))
    return record


def measures(traj) -> dict:
    """The reliability measures of one trajectory (module docstring).
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
            "ledger_residual": float(ledger), "contact_dissipation": dissipation, "max_box_tilt_deg": float(tilt.max()),
            "us_per_step": 1e6 * traj.wall_time / len(traj.tau)}


def summarize(records: list[dict]) -> dict:
    """Worst and median of each measure over the sweep, and the scenarios that fail ``CHECKS``.
    """
    done = [r for r in records if "converged" in r]
    table = {}
    for key in ("converged", "cone_residual", "coulomb_residual", "complementarity", "max_penetration",
                "ledger_residual", "max_box_tilt_deg", "us_per_step"):
        values = np.array([r[key] for r in done])
        worst = values.min() if key == "converged" else values.max()
        table[key] = {"worst": float(worst), "median": float(np.median(values)), "p90": float(np.percentile(values, 90))}
    failing = {key: [r["scenario"]["index"] for r in done if (r[key] < limit if kind == "min" else r[key] > limit)]
               for key, (limit, kind) in CHECKS.items()}
    return {"scenarios": len(records), "completed": len(done), "errors": [r["scenario"]["index"] for r in records if r["error"]],
            "measures": table, "checks": {k: {"threshold": v[0], "failing": failing[k]} for k, v in CHECKS.items()},
            "steps_converged": float(sum(r["converged"] * r["steps"] for r in done) / max(sum(r["steps"] for r in done), 1))}


def format_summary(summary: dict) -> str:
    """The summary as a text table (one line per measure).
    """
    lines = [f"{summary['completed']} of {summary['scenarios']} scenarios completed; friction fixed point converged on "
             f"{100 * summary['steps_converged']:.3f} % of all steps",
             f"{'measure':<20}{'worst':>12}{'median':>12}{'90th pct':>12}"]
    for key, v in summary["measures"].items():
        lines.append(f"{key:<20}{v['worst']:>12.4g}{v['median']:>12.4g}{v['p90']:>12.4g}")
    for key, check in summary["checks"].items():
        lines.append(f"check {key} ({'>=' if CHECKS[key][1] == 'min' else '<='} {check['threshold']:g}): "
                     + ("every scenario" if not check["failing"] else f"fails in scenarios {check['failing']}"))
    if summary["errors"]:
        lines.append(f"errors in scenarios {summary['errors']}")
    return "\n".join(lines)
