"""`cobra-ref figures --quick`: the outputs exist and say they are a smoke run, the claims' numbers are
computed (one is recomputed here by hand from the cached NPZ), the cache is reused, --check refuses
a smoke run, and bad input is refused."""

import glob
import json
import math
import os

import numpy as np
import pytest

from cobra_ref.cli import main
from cobra_ref.reproduce.claims import paper_claims
from cobra_ref.quaternion import quat_to_rot
from cobra_ref.simulate import Trajectory


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    """One quick regeneration (5 gaits x 1 s at dt = 2 ms at their default parameters, one member each, on
    both cores, figures, claims; no MuJoCo here: tests/test_mujoco_rollout.py covers it, and the
    optimization figure is tested in tests/test_shooting.py)."""
    out = str(tmp_path_factory.mktemp("figures"))
    assert main(["figures", "--quick", "--no-mujoco", "--defaults", "--members", "1", "--quiet", "--out", out]) == 0
    return out


def test_every_output_is_written(quick_run):
    names = [f"fig0{i}_{s}" for i, s in zip(range(3, 10), ("snapshots", "robot_contacts", "box_contacts",
                                                              "work_efficiency", "power", "torques", "box_distance"))]
    for name in names:
        with open(os.path.join(quick_run, name + ".png"), "rb") as f:
            assert f.read(4) == b"\x89PNG", name
        assert not os.path.exists(os.path.join(quick_run, name + ".pdf")), "a smoke run writes the PNG only"
    for gait in ("C", "S", "J", "J-mirror", "sidewinding"):
        with open(os.path.join(quick_run, f"anim_{gait}.gif"), "rb") as f:
            assert f.read(6) == b"GIF89a"
    assert not glob.glob(os.path.join(quick_run, ".tmp_*")), "a temporary file was left behind"


def test_every_report_says_it_is_a_smoke_run_on_its_first_line(quick_run):
    for name in ("claims.json", "summary.json", "claims.md"):
        with open(os.path.join(quick_run, name)) as f:
            assert "SMOKE RUN (cobra-ref figures --quick)" in f.readline(), name
    for name in ("claims.json", "summary.json"):
        with open(os.path.join(quick_run, name)) as f:
            assert next(iter(json.load(f))) == "smoke run", name
    from cobra_ref.reproduce.rules import fingerprint

    with open(os.path.join(quick_run, "summary.json")) as f:
        settings = json.load(f)["settings"]
    assert settings["claim rules (SHA-256 of their code, rules.fingerprint)"] == fingerprint()


def test_check_refuses_a_quick_run_and_a_smoke_report(quick_run, capsys):
    from cobra_ref.reproduce.check import read_committed

    with pytest.raises(SystemExit) as exc:
        main(["figures", "--quick", "--check", "--quiet", "--out", quick_run])
    assert exc.value.code == 2 and "a --quick run is a smoke run and cannot be compared" in capsys.readouterr().err
    with pytest.raises(ValueError, match="is a smoke run's report"):
        read_committed(os.path.join(quick_run, "claims.json"))


def test_a_quick_run_defaults_to_one_member_and_no_mujoco_a_full_one_does_not():
    from cobra_ref.reproduce.regenerate import MEMBERS, FiguresOptions, smoke_note

    quick, full = FiguresOptions(quick=True), FiguresOptions()
    assert (quick.n_members, quick.mujoco) == (1, False) and (full.n_members, full.mujoco) == (MEMBERS, True)
    assert FiguresOptions(quick=True, n_members=3, mujoco=True).n_members == 3
    assert smoke_note(full) is None and "no MuJoCo comparison" in smoke_note(quick)


def test_claims_json_has_the_issue_keys(quick_run):
    with open(os.path.join(quick_run, "claims.json")) as f:
        claims = json.load(f)["claims"]
    assert [c["id"] for c in claims] == ["E", "WB", "EN", "PP", "SP", "SL", "MJ", "MJ-C", "NI", "PS", "GT", "TL",
                                         "MJ-sym", "GT-own"]
    for c in claims:
        assert set(c) - {"statistics"} == {"id", "kind", "claim", "values", "holds", "verdict", "ensemble", "details"}
        assert c["kind"] == ("check" if c["id"] in ("TL", "MJ-sym", "GT-own") else "claim")
        assert c["holds"] in (True, False, None)
        assert c["verdict"] in ("holds", "does not hold", "undecided", "ties", "not tested")
        # one member per gait: per scenario 1, per run 4 (J-mirror, a copy of J, not counted); GT
        # (the direction optima) not tested with --defaults
        assert c["ensemble"]["n"] in (0, 1, 4)
    with open(os.path.join(quick_run, "claims.md")) as f:
        assert "| WB |" in f.read()


def test_work_on_the_box_recomputed_by_hand_from_the_npz(quick_run):
    """Claim WB's number for J, recomputed from the cached trajectory with an explicit loop:
    W_box = sum over robot-box rows of (-f) . (v + omega x (p - x_box)) dt (assumption A18)."""
    with open(os.path.join(quick_run, "claims.json")) as f:
        wb = next(c for c in json.load(f)["claims"] if c["id"] == "WB")
    path, = glob.glob(os.path.join(quick_run, ".cache", "J-" + "?" * 16 + ".npz"))  # not J-mirror-...
    traj = Trajectory.from_npz(path)
    c, total = traj.contacts, 0.0
    for k, kind, point, force in zip(c["contact_step"], c["contact_kind"], c["contact_point"], c["contact_force"]):
        if kind == 1:
            u = 0.5 * (traj.qd[k, -6:] + traj.qd[k + 1, -6:])
            omega = quat_to_rot(traj.box_pose[k, 3:]) @ u[3:]
            total -= force @ (u[:3] + np.cross(omega, point - traj.box_pose[k, :3])) * traj.dt
    assert total > 0, "the J hook reaches the box within the quick run's 1 s"
    assert wb["values"]["J"]["mean"] == pytest.approx(total, rel=1e-9)


def test_a_warm_run_reuses_the_simulations_and_the_figures(quick_run):
    before = {p: os.path.getmtime(p) for p in glob.glob(os.path.join(quick_run, "fig0*.png"))}
    assert main(["figures", "--quick", "--no-mujoco", "--defaults", "--members", "1", "--quiet", "--out", quick_run]) == 0
    after = {p: os.path.getmtime(p) for p in before}
    assert after == before, "unchanged inputs must keep the figures"


def test_claim_verdicts_follow_the_numbers():
    """Hand-made single summaries (``paper_claims``): sidewinding largest everywhere, S and J with the
    lowest slopes; the six ranking and mirror claims hold, then fail as the numbers change."""
    base = {"efficiency_slope": 10.0, "box_work": 1.0, "locomotion_work": 5.0, "peak_abs_power": 3.0,
            "box_distance": 0.1, "box_displacement": [0.1, 0.0], "error": ""}
    s = {g: dict(base) for g in ("C", "S", "J", "J-mirror", "sidewinding")}
    s["S"]["efficiency_slope"] = s["J"]["efficiency_slope"] = 5.0
    for key in ("box_work", "locomotion_work", "peak_abs_power", "box_distance"):
        s["sidewinding"][key] = 2 * base[key]
    s["J"]["box_displacement"], s["J-mirror"]["box_displacement"] = [0.1, -0.02], [0.1, 0.02]
    six = ("E", "WB", "EN", "PP", "SL", "MJ")
    assert all(c["holds"] for c in paper_claims(s) if c["id"] in six)
    s["J"]["efficiency_slope"] = 12.0  # J now less efficient than C and sidewinding (10), S still better
    assert {c["id"]: c["holds"] for c in paper_claims(s)}["E"] is False, "both S and J must beat both"
    s["J"]["efficiency_slope"] = 5.0
    s["C"]["efficiency_slope"] = 4.0  # C now beats S and J
    s["J-mirror"]["box_displacement"] = [0.1, -0.01]  # same side as J
    verdicts = {c["id"]: c["holds"] for c in paper_claims(s)}
    assert verdicts["E"] is False and verdicts["MJ-sym"] is False
    assert verdicts["MJ"] is True, "J itself still pushes 11 degrees off +x"
    del s["sidewinding"]
    assert {c["id"]: c["holds"] for c in paper_claims(s)}["WB"] is None


def test_a_negative_efficiency_slope_ranks_as_the_least_efficient():
    """E ranks by the slope W_loc / W_box, lower = more efficient, which holds for positive slopes
    only: 1 / slope is the efficiency. A slope of -685 J/J (the box's work falling while the robot
    works, as in a sidewinding member that brakes the box) has a negative efficiency, the worst of
    all, so it must not beat S's 4 J/J: it ranks as +inf, like a run that never works on the box,
    and the claim still fails when C's positive slope beats S and J."""
    from cobra_ref.reproduce.claims import inefficiency

    assert inefficiency(4.0) == 4.0 and inefficiency(-685.0) == inefficiency(0.0) == float("inf")
    assert math.isnan(inefficiency(float("nan")))
    base = {"efficiency_slope": 15.0, "box_work": 1.0, "locomotion_work": 5.0, "peak_abs_power": 3.0,
            "box_distance": 0.1, "box_displacement": [0.1, 0.0], "error": ""}
    s = {g: dict(base) for g in ("C", "S", "J", "J-mirror", "sidewinding")}
    s["S"]["efficiency_slope"], s["J"]["efficiency_slope"] = 4.0, 2.7
    s["sidewinding"]["efficiency_slope"] = -685.0
    assert {c["id"]: c["holds"] for c in paper_claims(s)}["E"] is True
    s["C"]["efficiency_slope"] = 3.0  # C's positive slope beats S's 4
    assert {c["id"]: c["holds"] for c in paper_claims(s)}["E"] is False


@pytest.mark.parametrize("args, message", [
    (["--gaits", "C,crawl"], "unknown gait(s) crawl"),
    (["--out", "/proc/cobra_figures"], "output directory"),
])
def test_bad_input_is_refused_before_any_work(args, message, capsys, tmp_path):
    argv = ["figures", "--quick", "--quiet"] + (args if "--out" in args else args + ["--out", str(tmp_path / "o")])
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert message in str(exc.value)
    assert not os.path.exists(tmp_path / "o") or not os.listdir(tmp_path / "o")


# --- the ensemble claims: every claim can hold and can fail (hand-made summaries, no simulation) ------------------

from cobra_ref.reproduce.claims import ensemble_claims, to_markdown, verdict  # noqa: E402

GAITS = ("C", "S", "J", "J-mirror", "sidewinding")


def member(gait: str, i: int) -> dict:
    """Scenario i's summary of ``gait`` in an ensemble where every claim holds: sidewinding does the
    most work, uses the most energy, has the largest and least steady power and moves the box
    furthest; S and J have the lowest slopes (5 against 10, spreads 0.07 apart from overlapping);
    J pushes the box 17-20 degrees to the right of C, J-mirror as far to the left; no impacts to
    speak of (0.1 N against m g = 58.86 N), no step over tau_max, the joints' torques one profile
    shifted by 0.1 period (peak correlation 0.9), and every box within 20 degrees of the goal +x
    (GT-own; GT is judged on ``GOALS_MET``)."""
    eps = 0.01 * i
    s = {"error": "", "efficiency_slope": 10.0 + eps, "box_work": 1.0 + eps, "locomotion_work": 5.0 + eps,
         "peak_abs_power": 3.0 + eps, "power_cv": 0.2 + eps, "box_distance": 0.1 + eps / 10,
         "box_displacement": [0.1, 0.0], "impact_impulse_per_second": 0.1, "robot_weight": 58.86,
         "steps_over_torque_limit": 0.0, "joint_phase_correlation": [1.0] + [0.9] * 10,
         "joint_phase_lags": [0.0] + [0.1] * 10, "goal_direction": [1.0, 0.0]}
    if gait in ("S", "J"):
        s["efficiency_slope"] = 5.0 + eps
    if gait == "sidewinding":
        s.update(box_work=2.0 + eps, locomotion_work=10.0 + eps, peak_abs_power=6.0 + eps, power_cv=0.8 + eps,
                 box_distance=0.2 + eps / 10, box_displacement=[0.2, 0.0])
    if gait == "J":
        s["box_displacement"] = [0.1, -0.03 - eps / 10]
    if gait == "J-mirror":
        s["box_displacement"] = [0.1, 0.03 + eps / 10]
    return s


def ensemble(n: int = 8, change=None, members=None) -> dict:
    """{gait: [member(gait, i) for i < n]}, with ``change(gait, summary)`` applied to the members
    ``members`` (default all)."""
    out = {g: [member(g, i) for i in range(n)] for g in GAITS}
    for g in GAITS:
        for i in (range(n) if members is None else members):
            if change is not None:
                change(g, out[g][i])
    return out


# the direction optima's outcomes (GT): each box ends 3.3-3.6 cm from a goal 0.25-0.3 m away (11-14 %)
GOALS_MET = [{"name": "ahead", "gait": "J", "goal": [0.3, 0.0], "displacement": [0.27, 0.015]},
             {"name": "left", "gait": "J-mirror", "goal": [0.25, 0.15], "displacement": [0.22, 0.13]},
             {"name": "right", "gait": "C", "goal": [0.2, -0.15], "displacement": [0.18, -0.12]}]
# the committed optima's: 8.8, 9.4 and 10.6 cm, 29 %, 32 % and 43 % of the start distance
GOALS_MISSED = [dict(o, displacement=d) for o, d in zip(GOALS_MET, ([0.2183, -0.0331], [0.2054, 0.0674],
                                                                    [0.2155, -0.0447]))]


def by_id(claims) -> dict:
    return {c["id"]: c for c in claims}


def _set(gait, key, value):
    """A change of ``key`` to ``value`` in ``gait``'s members (a callable value gets the summary)."""
    def change(g, s):
        if g == gait:
            s[key] = value(s) if callable(value) else value
    return change


# one change per claim that makes it fail for every member it touches
BREAK = {
    "E": _set("S", "efficiency_slope", 20.0),  # S now the least efficient, far outside C's spread
    "WB": _set("sidewinding", "box_work", 0.5),
    "EN": _set("sidewinding", "locomotion_work", 1.0),
    "PP": _set("sidewinding", "peak_abs_power", 1.0),
    "SP": _set("sidewinding", "power_cv", 0.1),  # sidewinding now the steadiest
    "SL": _set("sidewinding", "box_distance", 0.01),
    "MJ": _set("J", "box_displacement", lambda s: [0.1, 0.0]),  # J pushes straight ahead
    "MJ-C": _set("C", "box_displacement", lambda s: [0.1, -0.03]),  # C pushes where J does
    "NI": _set("C", "impact_impulse_per_second", 1.0),  # 1.7 % of m g
    "PS": _set("J", "joint_phase_correlation", [1.0] * 10 + [0.5]),  # one joint unlike J0
    "GT": None,  # GOALS_MISSED instead of GOALS_MET
    "TL": _set("S", "steps_over_torque_limit", 0.001),
    "MJ-sym": _set("J-mirror", "box_displacement", lambda s: [0.1, -0.03]),  # pushed to J's side
    "GT-own": _set("C", "goal_direction", [0.0, 1.0]),  # the box goes +x, the goal is +y
}
PER_RUN = {"NI": ("impact_impulse_per_second", 1.0), "TL": ("steps_over_torque_limit", 0.001),
           "PS": ("joint_phase_correlation", [1.0] * 10 + [0.5]), "GT-own": ("goal_direction", [0.0, 1.0])}


def test_every_claim_holds_on_the_made_up_ensemble():
    claims = ensemble_claims(ensemble(), GOALS_MET)
    assert [c["id"] for c in claims] == list(BREAK)
    for c in claims:
        assert c["holds"] is True and c["verdict"] == "holds", c["id"]
        assert c["ensemble"]["holds"] == c["ensemble"]["n"] > 0
    c = by_id(claims)
    # per scenario; per run of the 4 distinct gaits; per direction optimum
    assert (c["WB"]["ensemble"]["n"], c["NI"]["ensemble"]["n"], c["GT"]["ensemble"]["n"]) == (8, 32, 3)
    assert c["WB"]["values"]["sidewinding"] == {"mean": pytest.approx(2.035), "spread": [2.0, pytest.approx(2.07)]}


@pytest.mark.parametrize("cid", list(BREAK))
def test_every_claim_can_fail(cid):
    """The change that breaks claim ``cid`` makes it "does not hold"; a per-run claim broken in one
    gait fails for that gait's 8 of 32 runs, which is 75 % holding: it breaks the per-scenario
    claims only. So for the per-run claims the change is applied to every gait. GT fails on the
    committed direction optima's misses."""
    change = BREAK[cid]
    if cid in PER_RUN:
        key, value = PER_RUN[cid]

        def change(g, s):
            s[key] = value
    c = by_id(ensemble_claims(ensemble(change=change), GOALS_MISSED if cid == "GT" else GOALS_MET))[cid]
    assert c["holds"] is False and c["verdict"] == "does not hold", c
    assert c["ensemble"]["holds"] == 0


@pytest.mark.parametrize("cid", list(PER_RUN))
def test_a_per_run_claim_broken_in_one_gait_fails_for_its_runs(cid):
    """BREAK changes one gait only: its 8 runs fail, the other 24 of the 4 distinct gaits hold
    (75 %: undecided)."""
    c = by_id(ensemble_claims(ensemble(change=BREAK[cid])))[cid]
    assert (c["ensemble"]["n"], c["ensemble"]["holds"], c["verdict"]) == (32, 24, "undecided")


def test_phase_claim_needs_a_nonzero_lag():
    """Every joint correlating 1 at lag 0 (a profile not shifted) fails PS; one lag of 0.05 period
    suffices, 0.049 does not."""
    def lags(value):
        def change(g, s):
            s["joint_phase_correlation"], s["joint_phase_lags"] = [1.0] * 11, [0.0] * 10 + [value]
        return change
    assert by_id(ensemble_claims(ensemble(change=lags(0.0))))["PS"]["verdict"] == "does not hold"
    assert by_id(ensemble_claims(ensemble(change=lags(0.049))))["PS"]["verdict"] == "does not hold"
    assert by_id(ensemble_claims(ensemble(change=lags(-0.05))))["PS"]["verdict"] == "holds"


def test_efficiency_ties_when_the_spreads_overlap():
    """S's slopes 9.955 + 0.02 i reach into C's spread 10 + 0.01 i (i < 8): the ensemble does not
    resolve the ranking, whatever the per-scenario count (here S beats C in scenarios 0-4 only)."""
    slope = _set("S", "efficiency_slope", lambda s: 9.955 + 2 * (s["efficiency_slope"] - 5))
    c = by_id(ensemble_claims(ensemble(change=slope)))["E"]
    assert c["verdict"] == "ties" and c["holds"] is None
    assert "S / C" in c["details"]["overlapping spreads"]
    assert c["ensemble"]["holds"] == 5


def test_five_of_eight_is_undecided():
    """Sidewinding does the most work on the box in 5 of 8 scenarios: 62.5 %, between 20 % and 80 %."""
    c = by_id(ensemble_claims(ensemble(change=BREAK["WB"], members=[5, 6, 7])))["WB"]
    assert (c["ensemble"]["n"], c["ensemble"]["holds"]) == (8, 5)
    assert c["verdict"] == "undecided" and c["holds"] is None


def test_the_80_20_bands():
    assert verdict(5, 4) == (True, "holds")
    assert verdict(8, 6) == (None, "undecided")  # 75 %
    assert verdict(8, 7) == (True, "holds")
    assert verdict(10, 2) == (False, "does not hold")
    assert verdict(8, 2) == (None, "undecided")  # 25 %
    assert verdict(0, 0) == (None, "not tested")


def test_a_member_with_an_error_is_left_out_and_named():
    """C's scenario 3 failed (and its numbers are nonsense): the per-scenario claims count 7
    scenarios, the per-run claims 31 runs, every verdict still holds, and each names C[3]."""
    e = ensemble()
    e["C"][3].update(error="SimulationError: diverged at t = 2.1 s", box_work=99.0, impact_impulse_per_second=99.0)
    claims = by_id(ensemble_claims(e, GOALS_MET))
    assert claims["WB"]["ensemble"]["n"] == 7 and claims["NI"]["ensemble"]["n"] == 31
    for cid in ("E", "WB", "EN", "PP", "SP", "SL", "MJ-C", "NI", "TL", "PS", "GT-own"):
        assert claims[cid]["verdict"] == "holds", cid
        assert claims[cid]["ensemble"]["left_out"] == {"C[3]": "SimulationError: diverged at t = 2.1 s"}, cid
    for cid in ("MJ", "MJ-sym", "GT"):  # J's and J-mirror's runs, the direction optima
        assert claims[cid]["verdict"] == "holds" and claims[cid]["ensemble"]["left_out"] == {}, cid


def test_not_tested_without_a_gait_or_a_statistic():
    e = ensemble()
    del e["sidewinding"]
    c = by_id(ensemble_claims(e))
    for cid in ("WB", "EN", "PP", "SP", "SL"):
        assert c[cid]["verdict"] == "not tested" and c[cid]["holds"] is None, cid
    assert c["E"]["verdict"] == "not tested"
    assert c["WB"]["values"]["C"]["mean"] == pytest.approx(1.035)  # the gaits there still shown
    assert c["MJ"]["verdict"] == "holds"
    e = ensemble(change=lambda g, s: [s.pop("power_cv"), s.pop("goal_direction")])
    c = by_id(ensemble_claims(e))
    assert c["SP"]["verdict"] == "not tested" and c["GT-own"]["verdict"] == "not tested"
    assert c["GT"]["verdict"] == "not tested"  # no direction optima given
    e = ensemble(change=lambda g, s: s.update(joint_phase_correlation=[float("nan")] * 11))  # runs too short
    assert by_id(ensemble_claims(e))["PS"]["verdict"] == "not tested"
    e = ensemble(change=lambda g, s: s.update(error="killed"))
    assert all(c["verdict"] == "not tested" for c in ensemble_claims(e))


def test_mirror_check_tolerance_is_the_spread_of_J():
    """J's sideways push varies by 7 mm over the ensemble, so J-mirror may miss the reflection by up
    to 8 mm in y; 9 mm misses it."""
    def mirror_off(dy):
        return _set("J-mirror", "box_displacement", lambda s: [0.1, s["box_displacement"][1] + dy])
    assert by_id(ensemble_claims(ensemble(change=mirror_off(0.0079))))["MJ-sym"]["verdict"] == "holds"
    c = by_id(ensemble_claims(ensemble(change=mirror_off(0.009))))["MJ-sym"]
    assert c["verdict"] == "does not hold"
    assert c["details"]["tolerance_y_m"] == pytest.approx(0.008)


def test_steering_margin_widens_with_the_angular_spreads():
    """J pushes the box 17 degrees right of C in every scenario: MJ-C holds (margin 0 + 0 + 5). With
    scenario 7's push at 47 degrees instead, J's directions spread 30 degrees, half-spread 15, and the
    margin 15 + 0 + 5 = 20 degrees exceeds the 17 degrees of the other 7 scenarios: 1 of 8 holds."""
    def at(angles):
        def change(g, s):
            if g == "J":
                i = round(-(s["box_displacement"][1] + 0.03) * 1000)  # member() puts y = -0.03 - i / 1000
                a = np.radians(-angles(i))
                s["box_displacement"] = [0.1 * np.cos(a), 0.1 * np.sin(a)]
        return change
    c = by_id(ensemble_claims(ensemble(change=at(lambda i: 17.0))))["MJ-C"]
    assert c["verdict"] == "holds" and c["details"]["threshold_deg"] == pytest.approx(5.0)
    c = by_id(ensemble_claims(ensemble(change=at(lambda i: 47.0 if i == 7 else 17.0))))["MJ-C"]
    assert c["details"]["half_spread_J_deg"] == pytest.approx(15.0)
    assert c["details"]["threshold_deg"] == pytest.approx(20.0)
    assert (c["ensemble"]["n"], c["ensemble"]["holds"]) == (8, 1) and c["verdict"] == "does not hold"


def test_markdown_shows_the_ensemble_columns_and_the_failed_runs():
    e = ensemble()
    e["S"][2]["error"] = "diverged"
    text = to_markdown(ensemble_claims(e), e, {"members": 8})
    assert "| id | claim | per gait: mean [min, max] | n | members holding | verdict | sensitivity" in text
    assert "| S | 7 / 8 |" in text and "- S[2]: diverged" in text
    for row in (line for line in text.splitlines() if line.startswith("| WB ") or line.startswith("| PP ")):
        assert row.replace("\\|", "").count("|") == 8, row  # the claim's own |P| escaped
    assert "| 7 | 7 | **holds** |" in text
    assert "A22" in text and "A7" in text and "C22" not in text and "reproduce.py" not in text


def test_ensemble_summaries_keep_scenario_i_at_index_i():
    """Two scenarios of made-up (still) runs; scenario 1 has no S run: S's index 1 is an error
    summary, so S is left out of scenario 1 and named; the goal direction travels from the meta."""
    from cobra_ref.reproduce.claims import ensemble_summaries
    from test_analysis import made_up_trajectory
    meta = {"gait_params": {"frequency": 0.5, "ramp_time": None}, "goal_direction": [0.0, 1.0]}
    runs = [{g: made_up_trajectory(np.zeros((100, 11)), 0.01, meta) for g in ("C", "S")},
            {"C": made_up_trajectory(np.zeros((100, 11)), 0.01, meta)}]
    e = ensemble_summaries(runs)
    assert [len(e["C"]), len(e["S"])] == [2, 2] and e["S"][1] == {"error": "no run"}
    assert e["C"][0]["goal_direction"] == [0.0, 1.0] and e["C"][0]["steps_over_torque_limit"] == 0.0
    tl = by_id(ensemble_claims(e))["TL"]
    assert (tl["ensemble"]["n"], tl["ensemble"]["left_out"]) == (3, {"S[1]": "no run"})
    assert by_id(ensemble_claims(e))["GT-own"]["verdict"] == "does not hold"  # the boxes did not move


def test_a_claim_about_each_run_gives_each_gaits_own_verdict():
    """NI over two gaits: C's 8 runs are within 1 % of m g, J's 8 are not; over all 16 runs the
    claim is undecided (8 of 16), and the per-gait verdicts say where it holds."""
    from cobra_ref.reproduce.claims import ensemble_claims

    def run(rate):
        return {"impact_impulse_per_second": rate, "robot_weight": 58.86, "error": None}

    ni = next(c for c in ensemble_claims({"C": [run(0.1)] * 8, "J": [run(1.0)] * 8}) if c["id"] == "NI")
    assert ni["verdict"] == "undecided" and ni["ensemble"]["holds"] == 8
    assert ni["details"]["per gait"] == {"C": "holds (8 of 8)", "J": "does not hold (0 of 8)"}
