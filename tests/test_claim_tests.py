"""Claim tests that test what they say, worked on hand-built ensembles (no simulation): a mirrored copy
never moves a pooled verdict; TL, MJ-sym and GT-own are checks of the model, reported apart; MJ asks
whether J pushes sideways; GT judges the direction optima by their distance to the goal; each
threshold's sensitivity is counted by hand."""

import math

import pytest

from cobra_ref.reproduce.check import compare_claims
from cobra_ref.reproduce.claims import ensemble_claims, to_markdown
from test_claims import GOALS_MET, GOALS_MISSED, by_id, ensemble


def test_a_mirrored_copy_does_not_change_a_pooled_verdict():
    """J-mirror (``ensemble.MIRRORED``) does twice sidewinding's work on the box and every one of
    its impacts is 5 % of m g. Counted as a fifth gait it would make WB fail and NI undecided (32 of
    40); as a copy of J it is shown, marked, and not counted. Renamed to a gait that copies no
    one, the same numbers do count."""
    def loud_copy(g, s):
        if g == "J-mirror":
            s.update(box_work=5.0, impact_impulse_per_second=0.05 * s["robot_weight"])
    e = ensemble(change=loud_copy)
    c = by_id(ensemble_claims(e, GOALS_MET))
    assert c["WB"]["verdict"] == "holds" and c["WB"]["values"]["J-mirror"]["mean"] == 5.0
    assert "J-mirror" in c["WB"]["details"]["copies"]
    assert (c["NI"]["ensemble"]["n"], c["NI"]["ensemble"]["holds"], c["NI"]["verdict"]) == (32, 32, "holds")
    assert c["NI"]["details"]["per gait"]["J-mirror"] == "does not hold (0 of 8, a copy of J, not counted)"
    renamed = {("J-other" if g == "J-mirror" else g): v for g, v in e.items()}
    c = by_id(ensemble_claims(renamed, GOALS_MET))
    assert c["WB"]["verdict"] == "does not hold"
    assert (c["NI"]["ensemble"]["n"], c["NI"]["ensemble"]["holds"], c["NI"]["verdict"]) == (40, 32, "holds")
    # without J, J-mirror is no one's copy and counts
    alone = {g: v for g, v in e.items() if g != "J"}
    assert by_id(ensemble_claims(alone, GOALS_MET))["WB"]["verdict"] == "does not hold"


def test_the_checks_are_kind_check_and_listed_apart():
    """TL (the servo clamps at tau_max, A7), MJ-sym (J-mirror is J mirrored by construction) and
    GT-own (the optimizer's own goals) are checks; every other entry is a claim of the paper. In
    claims.md they follow the heading of their own section, with why."""
    claims = ensemble_claims(ensemble(), GOALS_MET)
    kinds = {c["id"]: c["kind"] for c in claims}
    assert {cid for cid, k in kinds.items() if k == "check"} == {"TL", "MJ-sym", "GT-own"}
    assert set(kinds.values()) == {"claim", "check"}
    text = to_markdown(claims, ensemble(), {})
    head, checks = text.split("## Checks of the model, not claims of the paper")
    for cid in ("TL", "MJ-sym", "GT-own"):
        assert f"\n| {cid} |" in checks and f"\n| {cid} |" not in head, cid
    for cid in ("MJ", "GT", "NI"):
        assert f"\n| {cid} |" in head, cid
    assert "clamps the torque at tau_max (assumption A7)" in checks


@pytest.mark.parametrize("angle, verdict, at_margin", [
    (0.0, "does not hold", ("does not hold", "does not hold", "does not hold")),  # straight ahead
    (3.0, "does not hold", ("holds", "does not hold", "does not hold")),  # 3 deg: beyond 2, not 5
    (8.0, "holds", ("holds", "holds", "does not hold")),
    (-49.5, "holds", ("holds", "holds", "holds")),  # the committed J ensemble's mean push
])
def test_mj_asks_whether_j_pushes_sideways(angle, verdict, at_margin):
    """Every scenario's J pushes 0.3 m at ``angle`` from +x (half-spread 0): MJ holds beyond 5 deg;
    the sensitivity gives the verdict at margins 2, 5 and 10 deg. The lateral displacement is
    0.3 sin(angle)."""
    a = math.radians(angle)

    def push(g, s):
        if g == "J":
            s["box_displacement"] = [0.3 * math.cos(a), 0.3 * math.sin(a)]
    mj = by_id(ensemble_claims(ensemble(change=push), GOALS_MET))["MJ"]
    assert mj["verdict"] == verdict
    assert tuple(row["verdict"] for row in mj["details"]["sensitivity"].values()) == at_margin
    assert mj["details"]["lateral_displacement_J_m"]["mean"] == pytest.approx(0.3 * math.sin(a), abs=1e-12)
    assert mj["values"]["J"]["mean"] == pytest.approx(abs(angle))


@pytest.mark.parametrize("displacement, share, holds", [
    ([0.25, 0.0], 1 / 6, True),  # 5 cm short of 0.3 m: 17 %
    ([0.3, 0.05], 1 / 6, True),  # 5 cm to the side
    ([0.2, 0.0], 1 / 3, False),  # 10 cm short: 33 %
    ([0.1, 0.0], 2 / 3, False),  # the right direction (0 deg), a third of the way
])
def test_gt_is_judged_by_the_distance_to_the_goal(displacement, share, holds):
    """One direction optimum, goal (0.3, 0) m from the box's start: GT holds when the box ends
    within 20 % of 0.3 m = 6 cm of it, whatever the angle."""
    goals = [{"name": "ahead", "gait": "J", "goal": [0.3, 0.0], "displacement": displacement}]
    gt = by_id(ensemble_claims(ensemble(), goals))["GT"]
    assert gt["values"]["ahead (J)"]["mean"] == pytest.approx(share)
    assert gt["holds"] is holds and gt["ensemble"]["n"] == 1


def test_gt_sensitivity_on_the_committed_misses():
    """The committed direction optima end 29 %, 32 % and 43 % of the start distance from their
    goals: 0 of 3 within 10 % or 20 %, 1 within 30 %, 3 within 50 %; their angles to the goal are
    8.6, 12.8 and 25.1 deg: 2 within 15 deg, all 3 within 30."""
    gt = by_id(ensemble_claims(ensemble(), GOALS_MISSED))["GT"]
    assert gt["verdict"] == "does not hold"
    assert gt["details"]["sensitivity"] == {
        "10 %": {"threshold": 0.1, "holds": 0, "n": 3, "verdict": "does not hold"},
        "20 %": {"threshold": 0.2, "holds": 0, "n": 3, "verdict": "does not hold"},
        "30 %": {"threshold": 0.3, "holds": 1, "n": 3, "verdict": "undecided"},
        "50 %": {"threshold": 0.5, "holds": 3, "n": 3, "verdict": "holds"}}
    assert [row["holds"] for row in gt["details"]["sensitivity_angle"].values()] == [2, 3, 3]


def test_ni_sensitivity_counted_by_hand():
    """Impacts at 0.4, 0.8, 1.5 and 2.5 % of m g for C, S, J and sidewinding (8 runs each;
    J-mirror's 5 % not counted): within 0.5 % 8 of 32 runs (25 %, undecided), within 1 % 16,
    within 2 % 24 (75 %, undecided), within 3 % all 32."""
    share = {"C": 0.004, "S": 0.008, "J": 0.015, "sidewinding": 0.025, "J-mirror": 0.05}
    e = ensemble(change=lambda g, s: s.update(impact_impulse_per_second=share[g] * s["robot_weight"]))
    ni = by_id(ensemble_claims(e))["NI"]
    assert ni["details"]["sensitivity"] == {
        "0.5 %": {"threshold": 0.005, "holds": 8, "n": 32, "verdict": "undecided"},
        "1 %": {"threshold": 0.01, "holds": 16, "n": 32, "verdict": "undecided"},
        "2 %": {"threshold": 0.02, "holds": 24, "n": 32, "verdict": "undecided"},
        "3 %": {"threshold": 0.03, "holds": 32, "n": 32, "verdict": "holds"}}
    assert ni["verdict"] == ni["details"]["sensitivity"]["1 %"]["verdict"]
    text = to_markdown([ni], e, {})
    assert "0.5 %: 8/32 undecided; 1 %: 16/32 undecided; 2 %: 24/32 undecided; 3 %: 32/32 holds" in text


def test_ps_and_mj_c_carry_their_sensitivity():
    """Every joint correlates at 0.75 with J0: PS holds at 0.5-0.7 and fails at 0.8 and 0.9."""
    e = ensemble(change=lambda g, s: s.update(joint_phase_correlation=[1.0] + [0.75] * 10))
    c = by_id(ensemble_claims(e))
    assert [row["verdict"] for row in c["PS"]["details"]["sensitivity"].values()] == \
        ["holds"] * 3 + ["does not hold"] * 2
    assert list(c["MJ-C"]["details"]["sensitivity"]) == ["2 deg", "5 deg", "10 deg"]


def test_check_reports_a_changed_kind():
    old = [{"id": "TL", "kind": "claim", "verdict": "holds"}]
    assert compare_claims(old, [{"id": "TL", "kind": "check", "verdict": "holds"}]) == \
        ["TL: kind 'claim' committed, 'check' now"]
    assert compare_claims([{"id": "TL", "verdict": "holds"}], old) == []  # no kind: a claim


def test_direction_outcomes_of_the_committed_optima():
    """GT's data: each committed direction optimum's goal and final box displacement, read from its
    recorded box path; the distance between them is the ``box_distance_to_goal`` its optimization
    reported (8.8, 9.4 and 10.6 cm)."""
    import json
    import os

    from cobra_ref.reproduce.optima import DIRECTIONS, OPTIMIZED_DIR, direction_outcomes

    outcomes = direction_outcomes(OPTIMIZED_DIR, "/nonexistent-cache")
    assert [(o["name"], o["gait"]) for o in outcomes] == [(n, g) for n, (g, _) in DIRECTIONS.items()]
    for o in outcomes:
        with open(os.path.join(OPTIMIZED_DIR, f"direction-{o['name']}.json")) as f:
            record = json.load(f)
        assert o["goal"] == list(DIRECTIONS[o["name"]][1])
        assert math.dist(o["displacement"], o["goal"]) == pytest.approx(record["box_distance_to_goal"], abs=1e-9)


def test_direction_outcomes_replay_an_optimum_without_a_recorded_path(tmp_path, monkeypatch):
    """A direction optimum's JSON without ``box_path`` is judged on its replayed path (here a stand-in
    for ``optima.replayed_box_path``, called with the JSON and the cache): goal (0.25, 0.15), box
    from (1, 2) to (1.2, 2.1)."""
    import json
    import os
    import shutil

    import numpy as np

    from cobra_ref.reproduce import optima

    with open(os.path.join(optima.OPTIMIZED_DIR, "direction-left.json")) as f:
        record = json.load(f)
    del record["box_path"]
    (tmp_path / "direction-left.json").write_text(json.dumps(record))
    shutil.copy(os.path.join(optima.OPTIMIZED_DIR, "direction-ahead.json"), tmp_path)
    calls = []

    def replayed(path, cache_dir):
        calls.append((os.path.basename(path), cache_dir))
        return np.array([[1.0, 2.0], [1.1, 2.05], [1.2, 2.1]])
    monkeypatch.setattr(optima, "replayed_box_path", replayed)
    outcomes = {o["name"]: o for o in optima.direction_outcomes(str(tmp_path), "cache-dir")}
    assert calls == [("direction-left.json", "cache-dir")] and set(outcomes) == {"ahead", "left"}
    assert outcomes["left"]["displacement"] == pytest.approx([0.2, 0.1]) and outcomes["left"]["goal"] == [0.25, 0.15]


def test_the_report_carries_gt_statistics_and_the_kinds_for_check():
    """``regenerate.ensemble_report`` with the direction optima's outcomes: GT's numbers become
    statistics over the members (the same each member: the optima are not perturbed) that
    ``--check`` compares, and every entry keeps its kind."""
    from cobra_ref.reproduce.regenerate import ensemble_report

    report = {c["id"]: c for c in ensemble_report(ensemble(n=3), GOALS_MISSED)}
    stat = report["GT"]["statistics"]["ahead (J).mean"]
    share = math.dist([0.2183, -0.0331], [0.3, 0.0]) / 0.3  # 29 %
    assert stat["n"] == 3 and stat["min"] == stat["max"] == pytest.approx(share)
    assert report["TL"]["kind"] == "check" and report["GT"]["kind"] == "claim"
