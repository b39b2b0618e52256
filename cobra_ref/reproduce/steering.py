"""The claims about where the box goes: MJ (J pushes sideways), MJ-C (J steers unlike C), GT (the
direction optima reach goals set independently of the gaits), and the check MJ-sym (J-mirror is
J reflected, true by construction).

The rules are stated in the ``claims`` module docstring; the constants are here.
"""

from __future__ import annotations

import math

import numpy as np

from .verdicts import claim_entry, failed_runs, own_values, scenarios, sensitivity, stats

RESOLUTION = 1e-3  # a box displacement resolved [m]
DIRECTION_MARGIN_DEG = 5.0  # MJ, MJ-C: the margin beyond the ensemble's angular half-spreads
MARGINS_DEG = (2.0, 5.0, 10.0)  # MJ, MJ-C: the margins of the sensitivity
GOAL_DISTANCE_SHARE = 0.2  # GT: final distance to the goal / start distance
GOAL_DISTANCE_SHARES = (0.1, 0.2, 0.3, 0.5)  # GT: the shares of the sensitivity
GOAL_ANGLES_DEG = (15.0, 30.0, 45.0)  # GT: the angles of the angle's sensitivity


def angle_deg(a, b) -> float:
    """The angle between two plane vectors [deg]; nan when either is zero."""
    na, nb = math.hypot(*a), math.hypot(*b)
    if na == 0 or nb == 0:
        return float("nan")
    c = (a[0] * b[0] + a[1] * b[1]) / (na * nb)
    return math.degrees(math.acos(max(-1.0, min(1.0, c))))


def directions(displacements) -> tuple:
    """(mean direction [deg], deviations [deg], half-spread [deg]) of plane displacements longer
    than ``RESOLUTION``: the mean direction is that of the sum of their unit vectors, each
    deviation the signed angle from it in (-180, 180], the half-spread (max - min) / 2 of the
    deviations. (nan, [], nan) when none is longer.

    The angular spread of an ensemble's box pushes (claims MJ and MJ-C).
    """
    d = np.array([x for x in displacements if math.hypot(*x) > RESOLUTION], dtype=float).reshape(-1, 2)
    if not len(d):
        return float("nan"), [], float("nan")
    u = d / np.linalg.norm(d, axis=1)[:, None]
    mean = math.atan2(u[:, 1].sum(), u[:, 0].sum())
    dev = np.degrees((np.arctan2(u[:, 1], u[:, 0]) - mean + np.pi) % (2 * np.pi) - np.pi)
    return math.degrees(mean), [float(x) for x in dev], float(np.ptp(dev) / 2)


def _margins() -> dict:
    return {f"{m:g} deg": m for m in MARGINS_DEG}


def _zero_if_nan(x: float) -> float:
    return 0.0 if x != x else x


def _moved(d) -> bool:
    return math.hypot(*d) > RESOLUTION


def mirror_check(ensemble: dict) -> dict:
    """Check MJ-sym: J-mirror's box displacement is J's reflected in x, per scenario within J's
    spread + ``RESOLUTION``, and sideways to opposite sides (``claims`` module docstring)."""
    text = (f"J-mirror moves the box as J reflected in x (true by construction: its members are J's mirrored): per "
            f"scenario |x_J - x_M| <= s_x + {1e3 * RESOLUTION:g} mm, |y_J + y_M| <= s_y + {1e3 * RESOLUTION:g} mm "
            f"(s: spread of J's displacements), y_J, y_M of opposite signs, each beyond {1e3 * RESOLUTION:g} mm "
            f"(sideways box displacement y [m])")
    gaits = ("J", "J-mirror")
    failed = failed_runs(ensemble, gaits)
    idx = scenarios(ensemble, gaits, ["box_displacement"])
    dJ = np.array([ensemble["J"][i]["box_displacement"] for i in idx], dtype=float).reshape(-1, 2)
    dM = np.array([ensemble["J-mirror"][i]["box_displacement"] for i in idx], dtype=float).reshape(-1, 2)
    values = {g: stats(d[:, 1]) for g, d in (("J", dJ), ("J-mirror", dM))} if idx \
        else own_values(ensemble, gaits, "box_displacement", lambda s: s["box_displacement"][1])
    results, details = [], {}
    if idx:
        tol = np.ptp(dJ, axis=0) + RESOLUTION
        details = {"tolerance_x_m": float(tol[0]), "tolerance_y_m": float(tol[1])}
        for (xJ, yJ), (xM, yM) in zip(dJ, dM):
            results.append(bool(abs(xJ - xM) <= tol[0] and abs(yJ + yM) <= tol[1] and yJ * yM < 0
                                and min(abs(yJ), abs(yM)) > RESOLUTION))
    return claim_entry("MJ-sym", text, values, results, failed, details, reason="needs J and J-mirror", kind="check")


def sideways(ensemble: dict) -> dict:
    """Claim MJ: J's box displacement points away from the start heading +x by more than J's
    angular half-spread + ``DIRECTION_MARGIN_DEG``, per scenario (``claims`` module docstring)."""
    text = (f"J pushes the box sideways: per scenario the angle of J's box displacement from the robot's start heading "
            f"(+x) exceeds h_J + {DIRECTION_MARGIN_DEG:g} deg (h_J: the angular half-spread of J's pushes over the "
            f"ensemble), the box moved beyond {1e3 * RESOLUTION:g} mm (angle from +x [deg])")
    failed = failed_runs(ensemble, ("J",))
    idx = scenarios(ensemble, ("J",), ["box_displacement"])
    d = [ensemble["J"][i]["box_displacement"] for i in idx]
    angles = [angle_deg(x, (1.0, 0.0)) for x in d]
    values = {"J": stats(angles)} if idx else {}
    results, details = [], {}
    if idx:
        mean, _, half = directions(d)
        half = _zero_if_nan(half)
        c = [s["box_displacement"] for s in ensemble.get("C", []) if not s.get("error") and s.get("box_displacement")]
        mean_c = directions(c)[0]
        details = {"half_spread_J_deg": half, "threshold_deg": half + DIRECTION_MARGIN_DEG,
                   "lateral_displacement_J_m": stats([x[1] for x in d]),
                   "forward_displacement_J_m": stats([x[0] for x in d]),
                   "angle_from_C_mean_deg": abs((mean - mean_c + 180.0) % 360.0 - 180.0)}

        def held(margin):
            return [_moved(x) and a > half + margin for x, a in zip(d, angles)]
        results = held(DIRECTION_MARGIN_DEG)
        details["sensitivity"] = sensitivity(_margins(), held)
    return claim_entry("MJ", text, values, results, failed, details, reason="needs J's box displacement")


def steering(ensemble: dict) -> dict:
    """Claim MJ-C: the angle between J's and C's box displacements exceeds h_J + h_C +
    ``DIRECTION_MARGIN_DEG``, per scenario (``claims`` module docstring)."""
    text = (f"J steers the box in a direction different from C's: per scenario the angle between their box "
            f"displacements exceeds h_J + h_C + {DIRECTION_MARGIN_DEG:g} deg (h: each ensemble's angular "
            f"half-spread; box direction [deg])")
    gaits = ("J", "C")
    failed = failed_runs(ensemble, gaits)
    idx = scenarios(ensemble, gaits, ["box_displacement"])
    d = {g: [ensemble[g][i]["box_displacement"] for i in idx] for g in gaits}
    results, details = [], {}
    values = own_values(ensemble, gaits, "box_displacement",
                        lambda s: math.degrees(math.atan2(s["box_displacement"][1], s["box_displacement"][0])))
    if idx:
        dirs = {g: directions(d[g]) for g in gaits}
        values = {g: stats([dirs[g][0] + x for x in dirs[g][1]]) for g in gaits}
        half = {g: _zero_if_nan(dirs[g][2]) for g in gaits}
        mean_angle = abs((dirs["J"][0] - dirs["C"][0] + 180.0) % 360.0 - 180.0)
        details = {"half_spread_J_deg": half["J"], "half_spread_C_deg": half["C"],
                   "threshold_deg": half["J"] + half["C"] + DIRECTION_MARGIN_DEG,
                   "angle_between_mean_directions_deg": mean_angle}

        def held(margin):
            return [_moved(a) and _moved(b) and angle_deg(a, b) > half["J"] + half["C"] + margin
                    for a, b in zip(d["J"], d["C"])]
        results = held(DIRECTION_MARGIN_DEG)
        details["sensitivity"] = sensitivity(_margins(), held)
    return claim_entry("MJ-C", text, values, results, failed, details, reason="needs J and C")


def goal_reached(outcomes) -> dict:
    """Claim GT on the direction optima's outcomes ({"name", "gait", "goal", "displacement"}, the
    goal and the box's final displacement relative to the box's start, world axes [m]): each final
    distance to the goal is at most ``GOAL_DISTANCE_SHARE`` of the start distance |goal|
    (``claims`` module docstring)."""
    text = (f"the box is moved to a specified point (goals set independently of the gaits: the direction optima, "
            f"optima.DIRECTIONS): each optimum's final distance to its goal is at most "
            f"{100 * GOAL_DISTANCE_SHARE:g} % of the start distance (final distance / start distance)")
    runs = [o for o in outcomes or [] if math.hypot(*o["goal"]) > 0]
    share = [math.dist(o["displacement"], o["goal"]) / math.hypot(*o["goal"]) for o in runs]
    angle = [angle_deg(o["displacement"], o["goal"]) for o in runs]
    values = {f"{o['name']} ({o['gait']})": stats([x]) for o, x in zip(runs, share)}
    details = {}
    if runs:
        details = {"goal_m": {o["name"]: list(o["goal"]) for o in runs},
                   "final_distance_m": {o["name"]: math.dist(o["displacement"], o["goal"]) for o in runs},
                   "angle_to_goal_deg": {o["name"]: a for o, a in zip(runs, angle)},
                   "sensitivity": sensitivity({f"{100 * x:g} %": x for x in GOAL_DISTANCE_SHARES},
                                              lambda t: [x <= t for x in share]),
                   "sensitivity_angle": sensitivity({f"{x:g} deg": x for x in GOAL_ANGLES_DEG},
                                                    lambda t: [_moved(o["displacement"]) and a <= t
                                                               for o, a in zip(runs, angle)])}
    results = [x <= GOAL_DISTANCE_SHARE for x in share]
    return claim_entry("GT", text, values, results, {}, details,
                       reason="no direction optimum (optima.DIRECTIONS) with a goal was given")
