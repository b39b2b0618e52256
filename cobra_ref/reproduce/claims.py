"""The paper's claims, each tested by a number computed from our simulations, per ensemble member.

The claims report of ``cobra-ref figures`` (``claims.json`` and ``claims.md``).

[COBRA] gives no numbers, only plots and sentences (sec. "Results", figs. 6-9; assumption A21).
Each claim below is a statistic of ``analysis.summary`` and a condition on it, with its
threshold fixed here, before any result (assumption A30):

* E  "the S and J shape lateral rolling gaits perform more efficiently than other gaits": the
  efficiency slope dW_loc / dW_box (``efficiency_slope``, fig. 6; lower = more efficient) of S
  and of J is below that of C and of sidewinding (per scenario: max(S, J) < min(C, sidewinding)).
  The slope is an inefficiency only where it is positive: 1 / slope is the efficiency, and a
  slope <= 0 (the box's work falls as the locomotion work grows over the push: the robot takes
  energy from the box) has an efficiency <= 0, below every positive one, so it ranks as +inf,
  as a run that never does work on the box does (``inefficiency``).
  The verdict is "ties" (holds None) when the ensemble spread [min, max] of S or of J, over
  the scenarios evaluated, overlaps that of C or of sidewinding: the ensemble does not resolve
  the ranking, whatever the per-scenario count. (Without overlap every scenario ranks alike.)
* WB "Sidewinding doing the most work on the box": ``box_work`` of sidewinding is larger than
  every other gait's.
* EN "... but consuming the most energy to do it": ``locomotion_work`` of sidewinding is the
  largest.
* PP "the large peaks in instantaneous power from sidewinding": ``peak_abs_power`` (max |P|_loc,
  fig. 7) of sidewinding is the largest.
* SP "as compared to the more steady power consumption by other gaits": ``power_cv`` (the
  coefficient of variation of |P|_loc after the ramp) of every rolling gait is below
  sidewinding's.
* SL "a slower but more energy efficient loco-manipulation": ``box_distance`` of every other
  gait is below sidewinding's (the same time, fig. 9).
* MJ "The J-shaped lateral rolling gait is asymmetrical and can be mirrored to execute control
  on the direction in which the object is moved", judged on what is not true by construction: J
  pushes the box sideways. Per scenario the angle of J's box displacement from the robot's start
  heading (+x) exceeds h_J + 5 degrees, with h_J the angular half-spread of J's displacement
  directions over the ensemble (half of max - min of their deviations from the mean direction:
  how far one scenario's push direction is from another's) and 5 degrees a margin a reader of
  fig. 3 could see; a box moved by 1 mm or less has no direction and fails. The details give
  J's lateral and forward displacement [m] and the angle between J's and C's mean directions.
  J-mirror is not tested here: it is J reflected by construction (check MJ-sym).
* MJ-C the same sentence, direction control: J steers the box in a direction different from
  C's: the angle between J's and C's displacements exceeds h_J + h_C + 5 degrees (h_g as in MJ);
  a box moved by 1 mm or less fails. Kept beside MJ: MJ says J's push is not straight ahead, MJ-C
  that it is not the push another gait already gives.
* NI the premise "non-impulsive": each run's ``impact_impulse_per_second`` (the impacts'
  impulse per second, ``analysis.impacts``, a mean force) is at most 1 % of the robot's weight
  m g (``robot_weight``: 12 links x 0.5 kg from ``CobraParameters``, the box excluded). The
  ground carries m g on average; impacts that supply under 1 % of it leave the load to forces
  that grow continuously.
* PS fig. 8's "Other joints show similar profiles offset by a phase angle based on the executed
  gait": every joint's torque (after the ramp) has a peak normalized cross-correlation with
  J0's (``joint_phase_correlation``, lags within +-1/2 period) of at least 0.7 (the shifted
  profile explains about half of the other's variance, r^2 >= 0.49), and the lags
  (``joint_phase_lags``) are not all zero: at least one beyond 0.05 period (18 degrees, a shift
  a plot like fig. 8 shows). A joint without torque variance counts as correlation 0; a run
  without any correlation (no gait period, or under two periods after the ramp) is left out.
* GT "the goal is to move the box on the flat ground towards a specified point", on goals set
  independently of where the gaits push: the direction optima (``optima.DIRECTIONS``: J ahead
  to (0.3, 0), J-mirror to (0.25, 0.15), C to (0.2, -0.15) m from the box's start), each
  optimum's box path as its optimization recorded it (or its cached replay). Each optimum's
  final distance to its goal is at most 20 % of the start distance |goal|: the box ends within a
  fifth of the way it was sent. The angle between the box's displacement and the goal is given
  beside it (with its own sensitivity). The per-gait optima's goals are not a test of this
  claim: each was set where the unoptimized gait already pushed (check GT-own). Not tested
  without direction optima. The planner's independent goal set (``planning.benchmark.GOALS``,
  16 goals) would need the receding planner per goal (``cobra-ref push --benchmark``), minutes
  each: too slow for the figures.

Checks of the model, not claims of the paper (``kind`` "check"; true by construction or a test
of our own machinery, listed apart in ``claims.md``):

* TL eq. (6) constraint (3), |tau| <= tau_max: ``steps_over_torque_limit`` == 0. The servo of
  assumption A7 clamps the torque at tau_max, so this checks the clamp, not the paper.
* MJ-sym J-mirror moves the box as J reflected in x: |x_J - x_M| <= s_x + 1 mm and |y_J + y_M|
  <= s_y + 1 mm with (s_x, s_y) the spread (max - min) of J's displacements over the ensemble
  plus 1 mm, y_J and y_M of opposite signs, each beyond 1 mm. J-mirror's members are J's
  mirrored (``ensemble.members``), so this checks the model's symmetry.
* GT-own the optimizer reached its own goal: the angle between each figure run's box
  displacement and its optimum's ``goal_direction`` is at most 30 degrees (a box moved 1 mm or
  less fails); runs without a ``goal_direction`` are not evaluated.

Pooled verdicts count distinct gaits only: J-mirror, a mirrored copy of J
(``ensemble.MIRRORED``), is left out of every comparison of gaits (E, WB, EN, PP, SP, SL) and of
every pooled per-run verdict (NI, PS, TL, GT-own); its numbers and its own per-gait line are
shown, marked as a copy. (GT's J-mirror optimum is an optimization of its own, not a copy.)

Sensitivity: each claim with a threshold gives, in ``details["sensitivity"]`` {label: {"threshold",
"holds", "n", "verdict"}}, its verdict by the same rule at each of a fixed list of thresholds,
the one above among them: NI the share of m g at 0.5, 1, 2 and 3 %; PS the correlation at 0.5,
0.6, 0.7, 0.8 and 0.9; MJ and MJ-C the margin at 2, 5 and 10 degrees; GT the distance share at
10, 20, 30 and 50 % (and ``details["sensitivity_angle"]``: the angle at 15, 30 and 45 degrees).
The rules are fixed in the code before a regeneration: ``rules.fingerprint`` (SHA-256 of this
module, ``steering`` and ``verdicts`` without docstrings and comments) is recorded in the
report's settings, and a changed fingerprint is named with its reason in CHANGELOG.md.

Ensembles. ``ensemble[gait][i]`` is member i's summary; member i of every gait is scenario i.
A claim comparing gaits (E, WB, EN, PP, SP, SL, MJ, MJ-C, MJ-sym) is evaluated per scenario i over
the scenarios every gait it needs has; a claim about each run (NI, TL, PS, GT-own) per member of
every distinct gait; GT per direction optimum. A member whose run has an error, or lacks the
statistic (absent or nan), is left out;
runs with an error are named. Of the n members (or scenarios) evaluated, the claim **holds**
when it holds for >= 80 %, **does not hold** when for <= 20 %, and is **undecided** between;
it is **not tested** when a gait or statistic it needs is missing or every member was left out.
The 80/20 bands accept one member in five going against the majority: an ensemble perturbs
the start, and a claim about a gait should survive most starts, not every one.

Each claim is a dict {"id", "kind", "claim", "values", "holds", "verdict", "ensemble", "details"}:
``values`` is {gait: {"mean", "spread": [min, max]}} of the claim's statistic over the members
evaluated, ``holds`` True / False / None (undecided, ties, not tested), ``ensemble`` {"n",
"holds", "fraction", "left_out"}, ``details`` the thresholds and resolutions used. The MuJoCo
comparison adds its own entries (``mujoco_check.claims``).
"""

from __future__ import annotations

import math

import numpy as np

from . import analysis
from .claims_report import to_markdown
from .ensemble import MIRRORED
from .steering import RESOLUTION, angle_deg, directions, goal_reached, mirror_check, sideways, steering
from .verdicts import (claim_entry, copies, distinct, failed_runs, ok, own_values, scenarios, sensitivity, stats,
                       verdict)

__all__ = ["directions", "ensemble_claims", "ensemble_summaries", "gait_summaries", "inefficiency", "paper_claims",
           "to_markdown", "verdict"]

ROLLING = ("C", "S", "J", "J-mirror")
SIDEWINDING = "sidewinding"
IMPULSE_SHARE = 0.01  # NI: impacts' mean force / m g
IMPULSE_SHARES = (0.005, 0.01, 0.02, 0.03)  # NI: the shares of the sensitivity
MIN_PHASE_CORRELATION = 0.7  # PS
PHASE_CORRELATIONS = (0.5, 0.6, 0.7, 0.8, 0.9)  # PS: the correlations of the sensitivity
MIN_PHASE_LAG = 0.05  # PS: a nonzero lag [periods]
GOAL_ANGLE_DEG = 30.0  # GT-own


# --- the claims ------------------------------------------------------------------------------------------------


def _rank(ensemble, cid, text, key, winner=SIDEWINDING, largest=True):
    """``winner``'s ``key`` is larger (smaller) than every other distinct gait's, per scenario; a
    mirrored copy is shown, not counted."""
    gaits = distinct(ensemble)
    failed = failed_runs(ensemble, gaits)
    shown = own_values(ensemble, list(copies(ensemble)), key)
    details = {"copies": copies(ensemble)}
    if winner not in ensemble or len(gaits) < 2:
        return claim_entry(cid, text, {**own_values(ensemble, gaits, key), **shown}, [], failed, details,
                           reason=f"needs {winner} and another gait")
    idx = scenarios(ensemble, gaits, [key])
    values = {g: stats([ensemble[g][i][key] for i in idx]) for g in gaits} if idx else own_values(ensemble, gaits, key)
    results = []
    for i in idx:
        w = ensemble[winner][i][key]
        others = [ensemble[g][i][key] for g in gaits if g != winner]
        results.append(w > max(others) if largest else w < min(others))
    return claim_entry(cid, text, {**values, **shown}, results, failed, details,
                       reason=f"no scenario with every gait's {key}")


def inefficiency(slope: float) -> float:
    """The E claim's ranking number of an efficiency slope [J/J]: the slope where it is positive,
    +inf where it is not (an efficiency 1 / slope <= 0, module docstring); nan stays nan.

    Claim E's per-member comparison and its spreads.
    """
    return slope if not slope <= 0 else float("inf")


def _efficiency(ensemble):
    text = ("S and J rolling are more efficient than C and sidewinding: per scenario, max(slope S, J) < "
            "min(slope C, sidewinding), slope = W_loc / W_box over the push [J/J] (fig. 6; a slope <= 0, the box's "
            "work falling as the robot works, ranks as +inf); 'ties' when the ensemble spreads of S or J and of C "
            "or sidewinding overlap")
    better, worse = ("S", "J"), ("C", SIDEWINDING)
    gaits = better + worse
    failed = failed_runs(ensemble, gaits)
    idx = scenarios(ensemble, gaits, ["efficiency_slope"])
    slope = {g: [inefficiency(ensemble[g][i]["efficiency_slope"]) for i in idx] for g in gaits if g in ensemble}
    values = {g: stats(v) for g, v in slope.items()} if idx else \
        own_values(ensemble, gaits, "efficiency_slope", lambda s: inefficiency(s["efficiency_slope"]))
    results = [max(slope["S"][k], slope["J"][k]) < min(slope["C"][k], slope[SIDEWINDING][k])
               for k in range(len(idx))]
    entry = claim_entry("E", text, values, results, failed, reason="needs S, J, C and sidewinding")
    if idx:
        overlap = [(b, w) for b in better for w in worse
                   if min(slope[b]) <= max(slope[w]) and min(slope[w]) <= max(slope[b])]
        entry["details"]["overlapping spreads"] = [f"{b} / {w}" for b, w in overlap]
        if overlap:
            entry["holds"], entry["verdict"] = None, "ties"
    return entry


def _per_run(ensemble, cid, text, keys, statistic, condition, details=None, kind="claim"):
    """A claim about each run: ``condition(summary)`` per member of every distinct gait,
    ``statistic(summary)`` its number. The verdict is over those runs; ``details["per gait"]``
    gives each gait's own verdict by the same rule ("C: holds (8 of 8)"), a mirrored copy's
    marked as not counted."""
    counted, copied = distinct(ensemble), copies(ensemble)
    failed = failed_runs(ensemble, counted)
    values, results, per_gait = {}, [], {}
    for g in ensemble:
        members = [s for s in ensemble[g] if ok(s, keys)]
        if members:
            values[g] = stats([statistic(s) for s in members])
            held = [bool(condition(s)) for s in members]
            results += held if g in counted else []
            note = f", a copy of {MIRRORED[g]}, not counted" if g in copied else ""
            per_gait[g] = f"{verdict(len(held), sum(held))[1]} ({sum(held)} of {len(held)}{note})"
    details = {**(details or {}), **({"per gait": per_gait} if per_gait else {})}
    return claim_entry(cid, text, values, results, failed, details, reason=f"no run with {', '.join(keys)}",
                       kind=kind)


def _counted(ensemble, keys) -> list:
    """The summaries a per-run claim counts: the usable members of the distinct gaits."""
    return [s for g in distinct(ensemble) for s in ensemble[g] if ok(s, keys)]


def _phase_ok(s, min_correlation=MIN_PHASE_CORRELATION) -> bool:
    corr = np.nan_to_num(np.asarray(s["joint_phase_correlation"], dtype=float), nan=0.0)
    lags = np.nan_to_num(np.asarray(s["joint_phase_lags"], dtype=float), nan=0.0)
    return bool(np.all(corr >= min_correlation) and np.any(np.abs(lags) >= MIN_PHASE_LAG))


def _phase_stat(s) -> float:
    return float(np.min(np.nan_to_num(np.asarray(s["joint_phase_correlation"], dtype=float), nan=0.0)))


def _has_phase(s) -> bool:
    return not all(isinstance(c, float) and math.isnan(c) for c in s.get("joint_phase_correlation") or [float("nan")])


def _goal_angle(s) -> float:
    return angle_deg(s["box_displacement"], s["goal_direction"])


def _impacts(ensemble) -> dict:
    """Claim NI, with the sensitivity of its share of m g."""
    keys = ["impact_impulse_per_second", "robot_weight"]
    entry = _per_run(
        ensemble, "NI", f"non-impulsive contact: each run's impact impulse per second is at most "
                        f"{100 * IMPULSE_SHARE:g} % of the robot's weight m g (impulse rate / m g)",
        keys, lambda s: s["impact_impulse_per_second"] / s["robot_weight"],
        lambda s: s["impact_impulse_per_second"] <= IMPULSE_SHARE * s["robot_weight"],
        {"share_of_weight": IMPULSE_SHARE})
    runs = _counted(ensemble, keys)
    entry["details"]["sensitivity"] = sensitivity(
        {f"{100 * x:g} %": x for x in IMPULSE_SHARES},
        lambda t: [s["impact_impulse_per_second"] <= t * s["robot_weight"] for s in runs])
    return entry


def _phases(ensemble) -> dict:
    """Claim PS, with the sensitivity of its correlation (runs without any correlation left out)."""
    keys = ["joint_phase_correlation", "joint_phase_lags"]
    ensemble = {g: [dict(s, joint_phase_correlation=None) if not _has_phase(s) else s for s in v]
                for g, v in ensemble.items()}
    entry = _per_run(
        ensemble, "PS", f"the joints' torques are one profile shifted in phase (fig. 8): each run's every joint "
                        f"correlates with J0 at some lag within +-1/2 period with a peak normalized cross-correlation "
                        f">= {MIN_PHASE_CORRELATION:g}, and some lag is beyond {MIN_PHASE_LAG:g} period (smallest "
                        f"peak correlation)",
        keys, _phase_stat, _phase_ok, {"min_correlation": MIN_PHASE_CORRELATION, "min_lag_periods": MIN_PHASE_LAG})
    runs = _counted(ensemble, keys)
    entry["details"]["sensitivity"] = sensitivity({f"{x:g}": x for x in PHASE_CORRELATIONS},
                                                  lambda t: [_phase_ok(s, t) for s in runs])
    return entry


def _own_goals(ensemble) -> dict:
    """Check GT-own: each figure run's box within ``GOAL_ANGLE_DEG`` of its own optimum's goal."""
    goal_ensemble = {g: [s for s in v if s.get("goal_direction") is not None or s.get("error")]
                     for g, v in ensemble.items()}
    goal_ensemble = {g: v for g, v in goal_ensemble.items() if any(s.get("goal_direction") is not None for s in v)}
    entry = _per_run(
        goal_ensemble, "GT-own", f"the optimizer reached its own goal (set where the unoptimized gait pushed, so not "
                                 f"a test of GT): the angle between each run's box displacement and its optimum's "
                                 f"goal direction is at most {GOAL_ANGLE_DEG:g} deg, the box moved beyond "
                                 f"{1e3 * RESOLUTION:g} mm (angle [deg])",
        ["box_displacement", "goal_direction"], _goal_angle,
        lambda s: math.hypot(*s["box_displacement"]) > RESOLUTION and _goal_angle(s) <= GOAL_ANGLE_DEG,
        {"max_angle_deg": GOAL_ANGLE_DEG}, kind="check")
    if not goal_ensemble:
        entry["details"]["not tested because"] = "no run has a goal_direction"
    return entry


def ensemble_claims(ensemble: dict, goals=None) -> list[dict]:
    """The claims, then the checks, of the module docstring, each evaluated per member of
    ``ensemble`` {gait: [summary, ...]}; ``goals``: the direction optima's outcomes for GT
    ({"name", "gait", "goal", "displacement"}, ``optima.direction_outcomes``; None: GT not tested).

    ``ensemble[gait][i]`` is member (scenario) i's ``analysis.summary`` plus the fields of
    ``gait_summaries`` and optionally ``goal_direction``; the verdicts follow the 80/20 rule.
    """
    ensemble = {g: list(v) for g, v in ensemble.items()}
    return [_efficiency(ensemble),
            _rank(ensemble, "WB", "sidewinding does the most work on the box: per scenario its W_box [J] is "
                                  "larger than every other gait's", "box_work"),
            _rank(ensemble, "EN", "sidewinding uses the most energy for locomotion: per scenario its W_loc [J] is "
                                  "the largest", "locomotion_work"),
            _rank(ensemble, "PP", "sidewinding has the largest peaks of locomotion power: per scenario its "
                                  "max |P_loc| [W] is the largest (fig. 7)", "peak_abs_power"),
            _rank({g: v for g, v in ensemble.items() if g in ROLLING or g == SIDEWINDING}, "SP",
                  "the rolling gaits consume power more steadily than sidewinding: per scenario each one's "
                  "coefficient of variation of |P_loc| after the ramp is below sidewinding's (fig. 7)", "power_cv"),
            _rank(ensemble, "SL", "the steady rolling gaits are slower: per scenario each moves the box less far "
                                  "than sidewinding in the same time (box distance [m], fig. 9)", "box_distance"),
            sideways(ensemble), steering(ensemble), _impacts(ensemble), _phases(ensemble), goal_reached(goals),
            _per_run(ensemble, "TL", "the torque limit |tau| <= tau_max (eq. (6), constraint (3)) holds at every step "
                                     "of each run (share of steps over tau_max); the servo clamps the torque at "
                                     "tau_max (A7), so this checks the clamp",
                     ["steps_over_torque_limit"], lambda s: s["steps_over_torque_limit"],
                     lambda s: s["steps_over_torque_limit"] == 0, kind="check"),
            mirror_check(ensemble), _own_goals(ensemble)]


def paper_claims(summaries: dict, goals=None) -> list[dict]:
    """The claims of ``ensemble_claims`` for one member per gait, from {gait: analysis.summary(traj)}
    (``goals``: as ``ensemble_claims``').

    Each claim's number is a field of ``analysis.summary``; nothing is typed in.
    """
    return ensemble_claims({g: [s] for g, s in summaries.items()}, goals)


def gait_summaries(results: dict) -> dict:
    """{gait: analysis.summary(traj)} plus each run's error (empty if it completed), largest
    penetration and friction-cone residual, the share of steps over tau_max, and the goal
    direction when the trajectory's ``meta`` has one.

    The numbers behind ``paper_claims`` and the model-health table of ``claims.md``.
    """
    out = {}
    for g, traj in results.items():
        out[g] = analysis.summary(traj)
        out[g]["error"] = traj.error
        out[g]["max_penetration"] = float(np.max(traj.steps["max_penetration"], initial=0.0))
        out[g]["max_cone_residual"] = float(np.max(traj.steps["cone_residual"], initial=0.0))
        out[g]["max_force_across_gap"] = analysis.force_across_gap(traj)
        out[g]["steps_over_torque_limit"] = float(np.mean(traj.steps["tau_excess"] > 0)) if len(traj.tau) else 0.0
        out[g].update(analysis.tracking_errors(traj))
        out[g]["ledger_residual"] = analysis.ledger_residual(traj)
        goal = (traj.meta or {}).get("goal_direction")
        if goal is not None:
            out[g]["goal_direction"] = [float(x) for x in goal]
    return out


def ensemble_summaries(members: list[dict]) -> dict:
    """{gait: [summary of member 0, member 1, ...]} from a list of {gait: trajectory}, one dict per
    scenario; a gait missing from a member gets the summary {"error": "no run"} so that index i
    stays scenario i.

    The input of ``ensemble_claims`` (``gait_summaries`` per member; a trajectory's
    ``meta["goal_direction"]``, when set, becomes the summary's ``goal_direction``).
    """
    per_member = [gait_summaries(m) for m in members]
    gaits = list(dict.fromkeys(g for m in per_member for g in m))
    return {g: [m.get(g, {"error": "no run"}) for m in per_member] for g in gaits}
