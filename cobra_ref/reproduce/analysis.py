"""Energy, work and contact analysis of a simulated trajectory (figures 4-9 of [COBRA]).

Implements: the work and power definitions of assumption A18 (the paper plots them, it does not
define them). For the N steps k of a trajectory with midpoint velocities
u_mid,k = (u_k + u_k+1) / 2 (the velocity at which the stepper's energy ledger closes exactly)::

    P_loc,k      = sum_j tau_j,k qdot_j,k                  locomotion power [W]      (fig. 7)
    |P|_loc,k    = sum_j |tau_j,k qdot_j,k|                absolute power: motors cannot recover
                                                           the energy they brake, so this is the
                                                           energy the actuators must supply
    W_loc(t_k)   = sum_{i<k} |P|_loc,i dt                  locomotion work [J]       (fig. 6, vertical)
    W_box(t_k)   = sum_{i<k} sum_c f_c . v_box(p_c) dt     work done ON the box by the robot's
                                                           contacts c (robot-box) [J] (fig. 6, horizontal)
    v_box(p)     = v_box + omega_box x (p - x_box)         the box's velocity at the point p
    d_box(t)     = |x_box(t) - x_box(0)|  (horizontal)     distance the box moved [m] (fig. 9)

f_c is the force ON the box; the contact log stores the force on body A (the robot link) by B
(the box), so f_c = -contact_force. Inefficiency (fig. 6) is the slope dW_loc / dW_box: the
locomotion work spent per joule done on the box; ``efficiency_fit`` fits a line over the push
(from the first robot-box contact on).

Convention: the box is the last free body (its 7 coordinates are the last of q and its 6
velocities, world linear then body angular, the last of qd), as in ``robots.cobra_model``.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..contact import BOX_GROUND, ROBOT_BOX, ROBOT_GROUND
from ..gaits import N_JOINTS
from ..params import CobraParameters
from ..quaternion import quat_to_rot

JOINT_VELOCITIES = slice(6, 6 + N_JOINTS)  # the joint rates in qd (after the head's 6 base velocities)
ROBUST_PERCENTILE = 99.0  # the percentile reported beside each maximum [%]
PHASE_REFERENCE_JOINT = 0  # J0, the head's joint (the paper's joint 1, numbering from 1 at the head)


def joint_rates(traj) -> np.ndarray:
    """(N, 11) joint velocities at each step's midpoint, (u_k + u_k+1) / 2.
    """
    qd = traj.qd[:, JOINT_VELOCITIES]
    return 0.5 * (qd[:-1] + qd[1:])


def locomotion_power(traj) -> tuple[np.ndarray, np.ndarray]:
    """(P_loc, |P|_loc), each (N,) [W]: sum_j tau_j qdot_j and sum_j |tau_j qdot_j|.

    Implements: assumption A18, locomotion power (paper fig. 7).
    """
    per_joint = traj.tau * joint_rates(traj)
    return per_joint.sum(axis=1), np.abs(per_joint).sum(axis=1)


def locomotion_work(traj) -> np.ndarray:
    """(N+1,) cumulative locomotion work W_loc(t) = integral sum_j |tau_j qdot_j| dt [J], W_loc(0) = 0.

    Implements: assumption A18, locomotion work (paper fig. 6, vertical axis).
    """
    return np.concatenate([[0.0], np.cumsum(locomotion_power(traj)[1] * traj.dt)])


def box_point_velocity(traj, steps: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(n, 3) world velocity of the box at world points ``points`` at the midpoints of ``steps``.

    V_box(p) = v + R omega_body x (p - x_box), with the box pose at the step's start.
    """
    qd_box = 0.5 * (traj.qd[steps, -6:] + traj.qd[steps + 1, -6:])
    pose = traj.box_pose[steps]
    R = np.array([quat_to_rot(quat) for quat in pose[:, 3:]]).reshape(-1, 3, 3)
    omega = np.einsum("kij,kj->ki", R, qd_box[:, 3:])
    return qd_box[:, :3] + np.cross(omega, points - pose[:, :3])


def contact_power_on_box(traj, kind: int) -> np.ndarray:
    """(N,) power [W] of the contacts of ``kind`` on the box, sum_c f_c . v_box(p_c).

    For robot-box contacts the force on the box is minus the logged force (which acts on the robot
    link); for box-ground contacts the box is body A and the logged force acts on it.
    """
    c = traj.contacts
    rows = np.flatnonzero(c["contact_kind"] == kind)
    steps = c["contact_step"][rows].astype(int)
    force = c["contact_force"][rows] * (-1.0 if kind == ROBOT_BOX else 1.0)
    v = box_point_velocity(traj, steps, c["contact_point"][rows])
    return np.bincount(steps, weights=np.einsum("ki,ki->k", force, v), minlength=len(traj.tau))


def box_work(traj) -> np.ndarray:
    """(N+1,) cumulative work W_box(t) done on the box by the robot's contacts [J], W_box(0) = 0.

    Implements: assumption A18, work on the box (paper fig. 6, horizontal axis).
    """
    return np.concatenate([[0.0], np.cumsum(contact_power_on_box(traj, ROBOT_BOX) * traj.dt)])


def box_distance(traj) -> np.ndarray:
    """(N+1,) horizontal distance of the box from its start, |x_box(t) - x_box(0)| [m].

    Implements: the box distance of [COBRA] fig. 9.
    """
    d = traj.box_pose[:, :2] - traj.box_pose[0, :2]
    return np.linalg.norm(d, axis=1)


def percentile_99(values, empty: float = 0.0) -> float:
    """The 99th percentile of ``values`` (flattened), or ``empty`` when there are none.

    The robust peak reported beside each maximum (``summary``; the annotations of figs. 7 and 8).
    For the n values sorted, s_0 <= ... <= s_{n-1}, the rank r = 0.99 (n - 1) and::

        p99 = s_i + (r - i) (s_{i+1} - s_i),   i = floor(r)

    (linear interpolation between order statistics, numpy's default), so p99 <= max and the top
    1 % of the samples (a landing impact, a contact switch) cannot set it.
    """
    v = np.asarray(values, dtype=float).ravel()
    return float(np.percentile(v, ROBUST_PERCENTILE)) if len(v) else float(empty)


def efficiency_fit(traj) -> tuple[float, float]:
    """(slope, intercept) of the least-squares line W_loc = slope W_box + intercept over the push,
    the samples from the first robot-box contact on; (inf, nan) when the robot does no work on
    the box.

    The number behind the paper's "more efficient gaits need less work in locomotion to do more work
    on the box" (fig. 6): the slope is the locomotion work spent per joule done on the box while
    pushing [J/J], lower = more efficient. The intercept absorbs the locomotion work spent before
    the robot reaches the box, which is not the push's cost.
    """
    w_loc, w_box = locomotion_work(traj), box_work(traj)
    touching = np.flatnonzero(traj.contacts["contact_kind"] == ROBOT_BOX)
    if not len(touching):
        return float("inf"), float("nan")
    k0 = int(traj.contacts["contact_step"][touching].min())
    x, y = w_box[k0:], w_loc[k0:]
    var = float(np.var(x))
    if var <= 1e-18:
        return float("inf"), float("nan")
    slope = float(np.mean((x - x.mean()) * (y - y.mean())) / var)
    return slope, float(y.mean() - slope * x.mean())


def efficiency_slope(traj) -> float:
    """The slope of ``efficiency_fit`` [J/J]: locomotion work per joule done on the box.

    Fig. 6's inefficiency, one number per gait.
    """
    return efficiency_fit(traj)[0]


def impacts(traj) -> dict:
    """The run's impacts: contacts that start carrying load while approaching (assumption A26).

    Implements: the paper's non-impulsive condition as numbers. A contact's onset is its first
    step with a normal impulse; its approach speed v_a = max(0, -g') is the gap's closing rate
    just before (eq. (4) on the normal row), and it is an impact when v_a > 1 cm/s. Per impact,
    the impulse that stops the approach is m v_a and the energy it takes out 1/2 m v_a^2, with
    m = 1 / G_NN the mass the contact sees (the Delassus matrix, eq. (5)). Returns impacts per
    second, the total impact impulse [N s] and energy [J], the largest approach speed [m/s] and
    the 99th percentile of the onsets' approach speeds (``percentile_99`` over the onsets with
    v_a > 0; 0 without any).
    """
    s, duration = traj.steps, max(float(traj.t[-1] - traj.t[0]), 1e-300) if len(traj.t) else 1e-300
    speed = traj.contacts["contact_onset_speed"]
    return {"impacts_per_second": float(np.sum(s["impact_count"])) / duration,
            "impact_impulse": float(np.sum(s["impact_impulse"])),
            "impact_energy": float(np.sum(s["impact_energy"])),
            "max_approach_speed": float(np.max(speed, initial=0.0)),
            "p99_approach_speed": percentile_99(speed[speed > 0])}


def robot_weight(params: CobraParameters | None = None) -> float:
    """The robot's weight m g [N], the box excluded.

    The scale of the non-impulsive claim. m is the robot's total mass from ``CobraParameters``
    (head, the ``n_body_links`` links and tail: 12 x 0.5 kg = 6 kg by default, the paper's "each
    link ... weighing 0.5 kg"), g its ``gravity`` (assumption A20).
    """
    p = params or CobraParameters()
    return float((p.mass_head + p.n_body_links * p.mass_link + p.mass_tail) * p.gravity)


def gait_period(traj) -> float:
    """The gait's period 1 / f [s] from ``traj.meta["gait_params"]["frequency"]``; nan without it.

    The lag window of ``joint_phase_correlation`` (assumption A10's f).
    """
    f = (traj.meta or {}).get("gait_params", {}).get("frequency")
    return 1.0 / float(f) if f else float("nan")


def steady_start(traj) -> float:
    """The time [s] from which the gait runs at its steady phase rate: the end of the phase-rate
    ramp, ``ramp_time`` of the trajectory's gait parameters, or one period when it is None (the
    gait library's default); nan when the trajectory carries no gait parameters.

    The window of ``power_cv`` and ``joint_phase_correlation`` (``gaits`` module docstring).
    """
    gp = (traj.meta or {}).get("gait_params", {})
    if gp.get("ramp_time") is not None:
        return float(gp["ramp_time"])
    return gait_period(traj)


def coefficient_of_variation(values) -> float:
    """CV = std / mean of ``values`` (population std, ddof = 0); nan when there are none or the
    mean is not positive.

    Implements: the steadiness measure of the claim "more steady power consumption by other
    gaits" ([COBRA] sec. "Results", fig. 7): 0 for a constant power, larger for spikier power.
    """
    v = np.asarray(values, dtype=float).ravel()
    if not len(v) or not np.mean(v) > 0:
        return float("nan")
    return float(np.std(v) / np.mean(v))


def power_cv(traj) -> float:
    """The coefficient of variation of |P|_loc over the steps from ``steady_start`` on; nan when the
    start is unknown or no step is left.

    Implements: the steadiness of fig. 7's power consumption. |P|_loc (the power the actuators
    must supply, assumption A18) is used, not the signed P_loc: the paper speaks of power
    *consumption*, and the signed power's mean, the CV's denominator, can be near zero when the
    joints brake about as much as they drive. The ramp is left out because every gait starts
    from rest (the ramp's growing power is not the gait's steadiness).
    """
    t0 = steady_start(traj)
    if not np.isfinite(t0) or not len(traj.tau):
        return float("nan")
    keep = traj.t[:-1] >= t0 - 1e-12
    return coefficient_of_variation(locomotion_power(traj)[1][keep])


def phase_correlation(signals, dt: float, period: float, reference: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """(peak, lag): for each column j of ``signals`` (n samples, m columns), the largest normalized
    cross-correlation with column ``reference`` over the lags |L| <= period / 2, and the lag at
    which it is reached [periods, in [-1/2, 1/2]]. nan for a column (or all of them) that has no
    variance, and for every column when the signals span less than two periods.

    Implements: the Pearson correlation at lag L of the overlapping samples::

        r_j(L) = corr(x_ref[k], x_j[k + L]),  k over the n - |L| samples where both exist

    so r_j = 1 at L = l exactly when x_j is x_ref delayed by l (positive lag: column j follows
    the reference) up to an offset and a positive scale (the normalization). Lags up to half a
    period each way cover every phase shift of a periodic signal once. The sums over the overlap
    are cumulative sums, and sum_k x_ref[k] x_j[k + L] for all L one FFT product.
    """
    x = np.asarray(signals, dtype=float)
    n, m = x.shape
    peak, lag = np.full(m, np.nan), np.full(m, np.nan)
    if not (period > 0) or n * dt < 2 * period:
        return peak, lag
    x = x - x.mean(axis=0)
    max_lag = int(np.floor(0.5 * period / dt + 1e-9))
    lags = np.arange(-max_lag, max_lag + 1)
    n_fft = 1 << int(np.ceil(np.log2(2 * n)))
    a = x[:, reference]
    A = np.fft.rfft(a, n_fft)
    zero = np.zeros((1, m))
    c1, c2 = np.concatenate([zero, np.cumsum(x, axis=0)]), np.concatenate([zero, np.cumsum(x**2, axis=0)])
    over = n - np.abs(lags)
    # overlap of the reference: a[0:n-L] for L >= 0, a[-L:n] for L < 0; of column j: b[L:n] or b[0:n+L]
    a_lo, a_hi = np.where(lags >= 0, 0, -lags), np.where(lags >= 0, n - lags, n)
    b_lo, b_hi = np.where(lags >= 0, lags, 0), np.where(lags >= 0, n, n + lags)
    sa, saa = c1[a_hi, reference] - c1[a_lo, reference], c2[a_hi, reference] - c2[a_lo, reference]
    var_a = saa - sa**2 / over
    scale = np.max(np.abs(x), axis=0)
    for j in range(m):
        if not scale[j] > 0 or not scale[reference] > 0:
            continue
        sab = np.fft.irfft(np.conj(A) * np.fft.rfft(x[:, j], n_fft), n_fft)[lags % n_fft]
        sb, sbb = c1[b_hi, j] - c1[b_lo, j], c2[b_hi, j] - c2[b_lo, j]
        var_b = sbb - sb**2 / over
        ok = (var_a > 1e-12 * over * scale[reference] ** 2) & (var_b > 1e-12 * over * scale[j] ** 2)
        if not np.any(ok):
            continue
        r = np.full(len(lags), -np.inf)
        r[ok] = (sab[ok] - sa[ok] * sb[ok] / over[ok]) / np.sqrt(var_a[ok] * var_b[ok])
        best = int(np.argmax(r))
        peak[j], lag[j] = float(min(r[best], 1.0)), float(lags[best] * dt / period)
    return peak, lag


def joint_phase_correlation(traj) -> tuple[list, list]:
    """(peaks, lags [periods]) of ``phase_correlation`` of the joint torques tau_j,k over the steps
    from ``steady_start`` on, against joint J0 (``PHASE_REFERENCE_JOINT``), with the gait's period;
    lists of nan when the period or the ramp is unknown or fewer than two periods remain.

    Implements: the numbers behind fig. 8's "Other joints show similar profiles offset by a phase
    angle based on the executed gait" ([COBRA]).
    """
    period, t0 = gait_period(traj), steady_start(traj)
    if not (np.isfinite(period) and np.isfinite(t0)) or not len(traj.tau):
        nan = [float("nan")] * N_JOINTS
        return nan, list(nan)
    keep = traj.t[:-1] >= t0 - 1e-12
    peak, lag = phase_correlation(traj.tau[keep], traj.dt, period, PHASE_REFERENCE_JOINT)
    return [float(v) for v in peak], [float(v) for v in lag]


class ContactForces(NamedTuple):
    """Per step and per body, the summed normal and tangential contact force magnitudes [N]."""

    normal: np.ndarray  # (N, n_bodies)
    tangential: np.ndarray  # (N, n_bodies)
    in_contact: np.ndarray  # (N, n_bodies) bool


def contact_forces(traj, kind: int, n_bodies: int) -> ContactForces:
    """Normal f_N = f . n and tangential |f_T| = |f - f_N n| contact forces of ``kind``, summed per
    body A and step.

    Implements: the contact-force decomposition of [COBRA] figs. 4 and 5 (f_N, f_T; eq. (2)).
    """
    c = traj.contacts
    rows = np.flatnonzero(c["contact_kind"] == kind)
    f, n = c["contact_force"][rows], c["contact_normal"][rows]
    f_N = np.einsum("ki,ki->k", f, n)
    f_T = np.linalg.norm(f - f_N[:, None] * n, axis=1)
    normal, tangential = np.zeros((len(traj.tau), n_bodies)), np.zeros((len(traj.tau), n_bodies))
    steps, bodies = c["contact_step"][rows].astype(int), c["contact_body"][rows].astype(int)
    np.add.at(normal, (steps, bodies), f_N)
    np.add.at(tangential, (steps, bodies), f_T)
    return ContactForces(normal, tangential, normal > 0)


def summary(traj) -> dict:
    """The numbers the claims report needs, from one trajectory (JSON-ready floats).

    W_loc(T), W_box(T), the efficiency slope, peak and mean |P_loc|, the box's displacement and
    distance, and the run's health (robot-box steps, torque excess, the share of steps whose
    friction fixed point converged), plus ``impacts``.

    Beside each maximum, the 99th percentile of the same samples (``percentile_99``), which a
    single spike does not move:

    * ``peak_abs_power`` / ``p99_abs_power``: of |P|_loc,k over the N steps [W];
    * ``peak_abs_tau`` / ``p99_abs_tau``: of max_j |tau_j,k|, the largest joint torque of each
      step [N m];
    * ``max_tau_excess`` / ``p99_tau_excess``: of the steps' ``tau_excess`` = max_j |tau_j| -
      tau_max [N m] (-inf for a run without steps);
    * ``max_approach_speed`` / ``p99_approach_speed``: of the contact onsets' approach speeds
      [m/s] (``impacts``).

    For the claims beyond the rankings:

    * ``impact_impulse_per_second``: ``impact_impulse`` / duration [N] (a mean force), beside
      ``robot_weight`` = m g [N] (``robot_weight``);
    * ``power_cv``: ``power_cv``, the steadiness of |P|_loc after the ramp (nan if unknown);
    * ``joint_phase_correlation`` / ``joint_phase_lags``: ``joint_phase_correlation``, per joint
      J0..J10 against J0, the lags in gait periods;
    * ``gait_period`` and ``steady_start`` [s], the window these use (nan if unknown).
    """
    p, p_abs = locomotion_power(traj)
    tau_step = np.abs(traj.tau).max(axis=1) if traj.tau.size else np.zeros(0)
    w_loc, w_box = locomotion_work(traj), box_work(traj)
    d = traj.box_pose[-1, :2] - traj.box_pose[0, :2]
    peaks, lags = joint_phase_correlation(traj)
    out = {
        "duration": float(traj.t[-1] - traj.t[0]),
        "locomotion_work": float(w_loc[-1]),
        "box_work": float(w_box[-1]),
        "efficiency_slope": efficiency_slope(traj),
        "peak_abs_power": float(p_abs.max(initial=0.0)),
        "p99_abs_power": percentile_99(p_abs),
        "peak_abs_tau": float(tau_step.max(initial=0.0)),
        "p99_abs_tau": percentile_99(tau_step),
        "mean_abs_power": float(p_abs.mean()) if len(p_abs) else 0.0,
        "box_displacement": [float(d[0]), float(d[1])],
        "box_distance": float(np.linalg.norm(d)),
        "robot_box_steps": int(len(np.unique(traj.contacts["contact_step"][traj.contacts["contact_kind"] == ROBOT_BOX]))),
        "max_tau_excess": float(traj.steps["tau_excess"].max(initial=-np.inf)),
        "p99_tau_excess": percentile_99(traj.steps["tau_excess"], empty=-np.inf),
        "fixed_point_converged": float(np.mean(traj.steps["fp_converged"])) if len(traj.tau) else 1.0,
        **impacts(traj),
        "robot_weight": robot_weight(),
        "power_cv": power_cv(traj),
        "joint_phase_correlation": peaks,
        "joint_phase_lags": lags,
        "gait_period": gait_period(traj),
        "steady_start": steady_start(traj),
    }
    out["impact_impulse_per_second"] = out["impact_impulse"] / max(out["duration"], 1e-300)
    return out


__all__ = ["joint_rates", "locomotion_power", "locomotion_work", "box_point_velocity", "contact_power_on_box",
           "box_work", "box_distance", "efficiency_fit", "efficiency_slope", "impacts", "ContactForces", "contact_forces",
           "summary", "percentile_99", "robot_weight", "gait_period", "steady_start", "coefficient_of_variation",
           "power_cv", "phase_correlation", "joint_phase_correlation",
           "ROBOT_GROUND", "ROBOT_BOX", "BOX_GROUND"]


def tracking_errors(traj) -> dict:
    """The position servo's joint tracking error: ``max_tracking_error`` and ``rms_tracking_error``
    [rad], the largest and the RMS over the steps of max_j |q_j - q_ref,j| at each step's end.

    Reported per gait (the servo of assumption A7 lags its reference).
    """
    e = np.asarray(traj.steps["tracking_error"], dtype=float)
    if not len(e):
        return {"max_tracking_error": 0.0, "rms_tracking_error": 0.0}
    return {"max_tracking_error": float(e.max()), "rms_tracking_error": float(np.sqrt(np.mean(e**2)))}


def ledger_residual(traj) -> float:
    """abs(W_act + W_contact - Delta(KE + PE)) / abs(W_act): the share of the actuators' work that the
    bodies' work-energy balance misses over the run.

    Implements: the energy ledger of ``step.energies`` summed over the run; what remains is the
    integrator's energy error (second order in dt on smooth motion, with the velocity-product terms
    at the step's midpoint velocity, ``step.midpoint_velocity``; first order across impacts).
    """
    s = traj.steps
    if not len(traj.tau):
        return 0.0
    W_act, W_contact = float(s["work_actuators"][:-1].sum()), float(s["work_contacts"][:-1].sum())
    E = s["kinetic"] + s["potential"]
    return abs(W_act + W_contact - float(E[-1] - E[0])) / max(abs(W_act), 1e-9)


GAP_TOL = 1e-7  # [m] a gap at a step's end below this is closed (the solver's tolerance on a gap)


def force_across_gap(traj) -> float:
    """The largest normal force [N] a contact carries in a step whose gap stays positive through it
    (g > 0 at the start and g + dt g' > GAP_TOL at the end): 0 for the compliant law (A12), which
    has no force across a gap. Read from the contact log (``contact_gap``, ``contact_gap_end``);
    NaN for a run recorded without them."""
    c = traj.contacts
    if "contact_gap_end" not in c or "contact_gap" not in c:
        return float("nan")
    apart = (c["contact_gap"] > 0.0) & (c["contact_gap_end"] > GAP_TOL)
    return float(np.max(traj.contact_normal_force()[apart], initial=0.0))
