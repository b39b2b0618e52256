"""The paper's claims, each tested by a number computed from our simulations.

Helper: the claims report of ``cobra-ref figures`` (``claims.json`` and ``claims.md``).

[COBRA] gives no numbers, only plots and these sentences (sec. "Results"):

* E  "the S and J shape lateral rolling gaits perform more efficiently than other gaits": the
  efficiency slope dW_loc / dW_box (``analysis.efficiency_slope``, fig. 6; lower = more
  efficient) of S and of J is below that of C and of sidewinding.
* WB "Sidewinding doing the most work on the box": W_box(T) of sidewinding is the largest.
* EN "... but consuming the most energy to do it": W_loc(T) of sidewinding is the largest.
* PP "the large peaks in instantaneous power from sidewinding": max |P_loc| of sidewinding is
  the largest (fig. 7).
* SL "a slower but more energy efficient loco-manipulation" (the steady gaits against
  sidewinding): every rolling gait moved the box less far than sidewinding in the same time
  (fig. 9).
* MJ "The J-shaped lateral rolling gait is asymmetrical and can be mirrored to execute control
  on the direction in which the object is moved": the box's sideways displacement (y, the
  robot's start heading is +x) has opposite signs for J and J-mirror, each more than 1 mm.

Each claim is a dict {id, claim, values, holds}; ``holds`` is None when a gait it needs is
missing or its run failed (the values say why). The MuJoCo comparison adds its own entries
(``mujoco_check.claims``).
"""

from __future__ import annotations

import numpy as np

from .. import analysis

ROLLING = ("C", "S", "J", "J-mirror")


def _rank_claim(cid, text, numbers, winner, largest=True):
    """``winner`` has the largest (or smallest) of ``numbers`` {gait: value}."""
    if winner not in numbers or len(numbers) < 2:
        return {"id": cid, "claim": text, "values": numbers, "holds": None}
    others = [v for g, v in numbers.items() if g != winner]
    holds = numbers[winner] > max(others) if largest else numbers[winner] < min(others)
    return {"id": cid, "claim": text, "values": numbers, "holds": bool(holds)}


def paper_claims(summaries: dict) -> list[dict]:
    """The claims E, WB, EN, PP, SL, MJ (module docstring) from {gait: analysis.summary(traj)}.

    Helper: each claim's number is a field of ``analysis.summary``; nothing is typed in.
    """
    s = {g: v for g, v in summaries.items() if not v.get("error")}
    pick = lambda key: {g: s[g][key] for g in s}  # noqa: E731
    out = []
    slope = pick("efficiency_slope")
    need = ("S", "J", "C", "sidewinding")
    holds = None
    if all(g in slope for g in need):
        holds = bool(max(slope["S"], slope["J"]) < min(slope["C"], slope["sidewinding"]))
    out.append({"id": "E", "claim": "S and J rolling are more efficient than C and sidewinding "
                                    "(lower slope W_loc / W_box, fig. 6)", "values": slope, "holds": holds})
    out.append(_rank_claim("WB", "sidewinding does the most work on the box (W_box, J)",
                           pick("box_work"), "sidewinding"))
    out.append(_rank_claim("EN", "sidewinding uses the most energy for locomotion (W_loc, J)",
                           pick("locomotion_work"), "sidewinding"))
    out.append(_rank_claim("PP", "sidewinding has the largest peaks of locomotion power (max |P_loc|, W)",
                           pick("peak_abs_power"), "sidewinding"))
    out.append(_rank_claim("SL", "the steady rolling gaits are slower: each moves the box less far than "
                                 "sidewinding in the same time (box distance, m, fig. 9)",
                           pick("box_distance"), "sidewinding"))
    disp = {g: s[g]["box_displacement"] for g in ("J", "J-mirror") if g in s}
    holds = None
    if len(disp) == 2:
        y_J, y_M = disp["J"][1], disp["J-mirror"][1]
        holds = bool(y_J * y_M < 0 and min(abs(y_J), abs(y_M)) > 1e-3)
    out.append({"id": "MJ", "claim": "the mirrored J moves the box to the other side (sideways box "
                                     "displacement y, m, of opposite signs, each > 1 mm)",
                "values": disp, "holds": holds})
    failed = {g: v["error"] for g, v in summaries.items() if v.get("error")}
    if failed:
        for c in out:
            c["values"] = {"numbers": c["values"], "failed runs (left out)": failed}
    return out


def gait_summaries(results: dict) -> dict:
    """{gait: analysis.summary(traj)} plus each run's error (empty if it completed).

    Helper: the numbers behind ``paper_claims`` and the model-health table of ``claims.md``.
    """
    out = {}
    for g, traj in results.items():
        out[g] = analysis.summary(traj)
        out[g]["error"] = traj.error
        out[g]["max_penetration"] = float(np.max(traj.steps["max_penetration"], initial=0.0))
        out[g]["max_cone_residual"] = float(np.max(traj.steps["cone_residual"], initial=0.0))
        out[g]["steps_over_torque_limit"] = float(np.mean(traj.steps["tau_excess"] > 0)) if len(traj.tau) else 0.0
    return out


def _fmt(v) -> str:
    if isinstance(v, float):
        return "inf" if np.isinf(v) else f"{v:.4g}"
    if isinstance(v, (list, tuple)):
        return "(" + ", ".join(_fmt(x) for x in v) + ")"
    if isinstance(v, dict):
        return "; ".join(f"{k}: {_fmt(x)}" for k, x in v.items())
    return str(v)


def to_markdown(claims: list[dict], summaries: dict, settings: dict) -> str:
    """``claims.md``: the claims with their numbers and verdicts, then the per-gait numbers and
    the health of each run (fixed-point convergence, torque limit, penetration), then the settings.

    Helper: the human-readable claims report.
    """
    verdict = {True: "holds", False: "does NOT hold", None: "not tested"}
    lines = ["# Claims of [COBRA] checked in cobra_ref", "",
             "Generated by `cobra-ref figures`; every number is computed from the simulations in this run "
             "(definitions: `cobra_ref/analysis.py`, assumption A18).", "",
             "| id | claim | our numbers | verdict |", "|---|---|---|---|"]
    for c in claims:
        lines.append(f"| {c['id']} | {c['claim']} | {_fmt(c['values'])} | **{verdict[c['holds']]}** |")
    lines += ["", "## Per gait", "",
              "| gait | T (s) | W_loc (J) | W_box (J) | slope | peak abs(P) (W) | box moved (m) | "
              "fixed point converged | steps over tau_max | max penetration (m) | error |",
              "|---|---|---|---|---|---|---|---|---|---|---|"]
    for g, v in summaries.items():
        lines.append(f"| {g} | {v['duration']:.2f} | {v['locomotion_work']:.3g} | {v['box_work']:.3g} | "
                     f"{_fmt(v['efficiency_slope'])} | {v['peak_abs_power']:.3g} | {v['box_distance']:.3g} | "
                     f"{100 * v['fixed_point_converged']:.0f} % | {100 * v['steps_over_torque_limit']:.1f} % | "
                     f"{v['max_penetration']:.2g} | {v['error'] or ''} |")
    lines += ["", "## Settings", ""] + [f"- {k}: {_fmt(v)}" for k, v in settings.items()]
    lines += ["", "Model choices that change these outcomes (README, 'Pushing the box'): the robot-box "
              "friction mu_rb = 0.5 (assumption C22; at mu_rb = 1 the rolling push self-locks), the box "
              "placement per gait (cobra_ref/reproduce.py), prescribed joint motion (torques are recovered, "
              "never clipped: 'steps over tau_max')."]
    return "\n".join(lines) + "\n"
