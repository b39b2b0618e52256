"""``cobra-ref convergence``: do the results hold when dt halves? One gait at dt = 2, 1, 0.5, 0.25 ms.

The time-step convergence study of the paper's non-impulsive premise. For one gait and each setting
(contact law and servo), ``study`` simulates ``duration`` seconds at each dt and ``metrics``
measures what the paper's figures show:

* contact force of each body (the vector sum of its contacts' forces, [N]): the raw per-step
  peak, the peak of its ``WINDOW`` (2 ms) moving mean, and the 99th percentile of the loaded
  steps. A touchdown on the paper's damper (d = 1e3 N s/m) lasts about m / d, under a
  millisecond for one link, so a per-step peak at these dt is an average over the step, and
  the 2 ms mean is the quantity that can converge;
* joint torque: the peak of |tau| and of its 2 ms mean [N m];
* locomotion power sum_j |tau_j qd_j|: the peak and the peak of its 2 ms mean [W];
* the box's displacement after ``duration`` [m] and the impacts per second (assumption A26).

An impulsive model shows itself here: its peaks grow like 1 / dt (a velocity jump takes one
step whatever its length), a non-impulsive one's converge. ``changes`` reports each metric's
relative change between successive dt, ``richardson`` its observed order of convergence and the
limit it tends to.

``restart`` = T > 0 separates what the steps after T do from the error carried to T: every dt
starts at T from the one state the finest dt reached there (local convergence, against the
global convergence of runs that each start at t = 0), and the metrics cover T .. ``duration``.
A quantity that converges from a common state but not from t = 0 is sensitive to the error
accumulated before T, not resolved differently after it.
"""

from __future__ import annotations

import time

import numpy as np

from .analysis import impacts, locomotion_power
from ..contact import ROBOT_BOX
from ..gaits import gait
from ..placement import travel_placement
from ..robots import cobra_model
from ..simulate import simulate
from ..start import BoxPlacement, initial_state
from ..step import StepSettings
from ..infra.validation import ValidationError

DTS = (2e-3, 1e-3, 5e-4, 2.5e-4)
WINDOW = 2e-3  # [s] the moving mean of forces, torques and power
SETTINGS = {"high-fidelity": ("compliant", "position"), "rigid": ("rigid", "prescribed")}


def moving_mean(y: np.ndarray, dt: float, window: float = WINDOW) -> np.ndarray:
    """Means of y over every run of window / dt consecutive steps (along axis 0).

    The 2 ms mean of the convergence metrics.
    """
    n = max(1, int(round(window / dt)))
    if len(y) < n:
        return y.mean(axis=0, keepdims=True)
    c = np.cumsum(np.concatenate([np.zeros((1,) + y.shape[1:]), y]), axis=0)
    return (c[n:] - c[:-n]) / n


def body_forces(traj, model) -> np.ndarray:
    """(N, nb) norm of the sum of the contact forces on each body per step [N].

    The contact log's forces act on body A (the robot link, or the box on the ground); the box also
    feels minus the robot-box rows.
    """
    c = traj.contacts
    F = np.zeros((len(traj.tau), model.nb, 3))
    steps, bodies, force = c["contact_step"].astype(int), c["contact_body"].astype(int), c["contact_force"]
    np.add.at(F, (steps, bodies), force)
    robot_box = np.flatnonzero(c["contact_kind"] == ROBOT_BOX)
    if len(robot_box) and model.boxes:
        np.add.at(F, (steps[robot_box], model.boxes[0].body), -force[robot_box])
    return np.linalg.norm(F, axis=2)


def metrics(traj, model) -> dict:
    """The convergence metrics of one run (module docstring).
    """
    dt = traj.dt
    F = body_forces(traj, model)
    tau = np.abs(traj.tau).max(axis=1) if traj.tau.size else np.zeros(len(traj.tau))
    power = locomotion_power(traj)[1]
    return {"force_peak": float(F.max()), "force_peak_2ms": float(moving_mean(F, dt).max()),
            "force_p99": float(np.percentile(F[F > 0], 99)) if np.any(F > 0) else 0.0,
            "torque_peak": float(tau.max()), "torque_peak_2ms": float(moving_mean(tau, dt).max()),
            "power_peak": float(power.max()), "power_peak_2ms": float(moving_mean(power, dt).max()),
            "box_displacement": float(np.linalg.norm(traj.box_pose[-1, :2] - traj.box_pose[0, :2])),
            "impacts_per_second": impacts(traj)["impacts_per_second"],
            "fixed_point_converged": float(np.mean(traj.steps["fp_converged"]))}


class Shifted:
    """The joint reference of a run that starts at time ``t0`` of the gait: ``Shifted(ref, t0)(t) = ref(t0 + t)``.

    The runs of a study restarted at T (``study``).
    """

    def __init__(self, reference, t0: float):
        self.reference, self.t0 = reference, t0

    def __call__(self, t: float):
        return self.reference(self.t0 + t)


def check_restart(restart: float, duration: float, dts) -> None:
    """A ``ValidationError`` unless 0 <= restart < duration and restart is a whole number of steps
    of the finest dt (the state every run starts from is the finest run's at that step).
    """
    n = restart / min(dts)
    if not 0.0 <= restart < duration or abs(n - round(n)) > 1e-9 * max(n, 1.0):
        raise ValidationError(f"restart must be in [0, duration = {duration:g}) s and a whole number of "
                              f"dt = {min(dts) * 1e3:g} ms steps; got restart = {restart:g} s")


def study(gait_name: str = "J", duration: float = 2.0, dts=DTS, settings=tuple(SETTINGS), progress=None,
          restart: float = 0.0) -> dict:
    """{setting: {dt: metrics}} of one gait (module docstring); ``restart`` = T > 0: every dt runs
    from T to ``duration``, starting from the state the finest dt reached at T.
    """
    check_restart(restart, duration, dts)
    model, ref = cobra_model(), gait(gait_name)
    # the box where the figures put it: a travelling gait's ahead of its wave (placed once, at 1 ms)
    where = BoxPlacement()
    if gait_name == "sidewinding":
        where = travel_placement(cobra_model(with_box=False), ref).box
    out = {}
    for name in settings:
        contact, servo = SETTINGS[name]
        out[name] = {}
        common = None  # restart: the finest dt's state at T, where every dt starts
        if restart > 0:
            finest = StepSettings(dt=min(dts), contact=contact, servo=servo)
            head = simulate(model, ref, restart, finest, *initial_state(model, ref, finest, where))
            common = (head.q[-1], head.qd[-1])
        for dt in dts:
            start = time.perf_counter()
            step_settings = StepSettings(dt=dt, contact=contact, servo=servo)
            if common is None:
                q0, qd0 = initial_state(model, ref, step_settings, where)
                traj = simulate(model, ref, duration, step_settings, q0, qd0)
            else:
                traj = simulate(model, Shifted(ref, restart), duration - restart, step_settings, *common)
            out[name][dt] = {**metrics(traj, model), "seconds": time.perf_counter() - start}
            if progress:
                progress(f"{gait_name} {name} dt = {dt * 1e3:g} ms: {time.perf_counter() - start:.0f} s")
    return out


def changes(rows: dict) -> dict:
    """{metric: [relative change from each dt to the next smaller one]} of one setting's rows.

    The convergence verdicts (|change| <= 10 %, 25 %, 5 % in the README's table).
    """
    dts = sorted(rows, reverse=True)
    keys = [k for k in rows[dts[0]] if k not in ("seconds", "fixed_point_converged")]
    return {k: [(rows[b][k] - rows[a][k]) / rows[a][k] if rows[a][k] else float("nan") for a, b in zip(dts, dts[1:])]
            for k in keys}


def richardson(rows: dict) -> dict:
    """{metric: (p, limit)} of one setting's rows from its three finest dt, each half the last: the
    observed order p = log2((x_1 - x_2) / (x_2 - x_3)) and the Richardson limit
    x_3 + (x_3 - x_2) / (2^p - 1) of x(dt) = limit - C dt^p; (nan, nan) where the three do not
    change monotonically towards a limit (p <= 0, or differences of opposite sign or zero).
    """
    dts, keys = sorted(rows, reverse=True)[-3:], list(changes(rows))
    if len(dts) < 3 or not (dts[0] == 2 * dts[1] == 4 * dts[2]):
        return {k: (float("nan"), float("nan")) for k in keys}
    out = {}
    for k in keys:
        x1, x2, x3 = (rows[dt][k] for dt in dts)
        d12, d23 = x2 - x1, x3 - x2
        p = float(np.log2(d12 / d23)) if d12 * d23 > 0 else float("nan")
        out[k] = (p, x3 + d23 / (2.0**p - 1.0)) if p > 0 else (p, float("nan"))
    return out


def format_table(result: dict, gait_name: str, restart: float = 0.0) -> str:
    """The study as a text table: one block per setting, one column per dt, then each metric's
    observed order and Richardson limit from the three finest dt (``richardson``; "-" where none).
    """
    lines = []
    for name, rows in result.items():
        dts = sorted(rows, reverse=True)
        since = f", every dt from the dt = {min(dts) * 1e3:g} ms state at t = {restart:g} s" if restart > 0 else ""
        lines.append(f"{gait_name}, {name} ({' + '.join(SETTINGS[name])}){since}")
        lines.append(f"  {'dt [ms]':<24}" + "".join(f"{dt * 1e3:>10g}" for dt in dts) + f"{'order':>8}{'limit':>10}")
        fits = richardson(rows)
        for key in rows[dts[0]]:
            if key != "seconds":
                p, limit = fits.get(key, (float("nan"), float("nan")))
                lines.append(f"  {key:<24}" + "".join(f"{rows[dt][key]:>10.4g}" for dt in dts)
                             + (f"{p:>8.2f}" if np.isfinite(p) else f"{'-':>8}")
                             + (f"{limit:>10.4g}" if np.isfinite(limit) else f"{'-':>10}"))
    return "\n".join(lines)
