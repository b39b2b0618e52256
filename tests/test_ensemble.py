"""Ensembles of the figure runs, as worked examples: who the members are, where their box starts,
how their runs are keyed, that any executor gives the same numbers, and how ``--check`` judges a
regenerated claims report against the committed one.
"""

import json
import math

import numpy as np
import pytest

from cobra_ref.infra.executors import SerialExecutor
from cobra_ref.gaits import gait
from cobra_ref.robots import cobra_model
from cobra_ref.start import BoxPlacement, placed_state
from cobra_ref.reproduce import check, ensemble, regenerate
from cobra_ref.reproduce.ensemble import Member, members
from cobra_ref.reproduce.runs import RunSpec, run_all

TINY = 0.05  # [s] 50 steps: enough to tell two runs apart, cheap enough for a test


# ------------------------------------------------------------------------------------ the members

def test_member_0_is_nominal_and_the_others_lie_within_the_stated_bounds():
    ms = members("C", 8)
    assert [m.index for m in ms] == list(range(8))
    assert ms[0] == Member(0) and ms[0].nominal
    for m in ms[1:]:
        assert not m.nominal
        assert all(abs(x) <= 0.005 for x in m.box_shift)
        assert abs(m.box_turn) <= math.radians(2.0)
        assert abs(m.phase) <= 0.05
        assert 0.97 <= m.mu_scale <= 1.03


def test_members_are_the_same_every_time_and_a_smaller_ensemble_is_a_prefix():
    assert members("S", 8) == members("S", 8)
    assert members("S", 8)[:3] == members("S", 3)
    # the draws do not depend on the gait
    assert members("C", 4) == members("sidewinding", 4)


def test_j_mirror_members_are_j_members_reflected_about_the_start_heading():
    for j, m in zip(members("J", 6), members("J-mirror", 6)):
        assert m.box_shift == (j.box_shift[0], -j.box_shift[1] if j.box_shift[1] else 0.0)
        assert m.box_turn == -j.box_turn and m.phase == j.phase and m.mu_scale == j.mu_scale


@pytest.mark.parametrize("n", [0, -1, 2.0, "8", True])
def test_an_ensemble_needs_a_whole_number_of_members(n):
    with pytest.raises(ValueError, match="whole number n >= 1"):
        members("C", n)


# ---------------------------------------------------------------------------- the perturbed start

def _box(model, q):
    iq = model.q_idx[model.boxes[0].body]
    x, y, _, w, _, _, z = q[iq]
    return np.array([x, y]), 2 * math.atan2(z, w)


def test_box_shift_and_box_turn_move_the_placed_box_by_exactly_that_much():
    """The shift is added to the placed centre and the turn to its yaw; the robot does not move."""
    model, ref = cobra_model(), gait("J")
    q_nominal = placed_state(model, ref)
    q = placed_state(model, ref, BoxPlacement(shift=(0.004, -0.003), turn=math.radians(1.5)))
    (c0, yaw0), (c1, yaw1) = _box(model, q_nominal), _box(model, q)
    assert np.allclose(c1 - c0, [0.004, -0.003], atol=1e-12)
    assert yaw1 - yaw0 == pytest.approx(math.radians(1.5), abs=1e-12)
    iq = model.q_idx[model.boxes[0].body]
    robot = np.ones(model.nq, bool)
    robot[iq] = False
    assert np.array_equal(q[robot], q_nominal[robot])
    assert np.array_equal(placed_state(model, ref, BoxPlacement(shift=None, turn=0.0)), q_nominal)


@pytest.mark.parametrize("kwargs, message", [({"shift": (0.01,)}, r"box_shift = \(0.01,\) has 1 value"),
                                             ({"shift": (np.nan, 0.0)}, "box_shift DX = nan is not finite"),
                                             ({"turn": np.inf}, "box_turn = inf is not finite")])
def test_a_bad_perturbation_is_refused_naming_it(kwargs, message):
    with pytest.raises(ValueError, match=message):
        placed_state(cobra_model(), gait("C"), BoxPlacement(**kwargs))


# ------------------------------------------------------------------------------------ the run specs

def test_a_member_changes_the_key_the_file_name_the_phase_and_every_friction():
    m = members("J", 2)[1]
    nominal, perturbed = RunSpec("J", duration=2.0), RunSpec("J", duration=2.0, member=m)
    assert nominal.key() != perturbed.key()
    assert perturbed.filename().startswith("J-m1-") and perturbed.label() == "J#1"
    # member 0 is the nominal run: the same cache entry as a spec without a member
    assert RunSpec("J", duration=2.0, member=Member(0)).key() == nominal.key()
    assert perturbed.reference().phase == pytest.approx(nominal.reference().phase + m.phase)
    p0, p1 = nominal.cobra_parameters(), perturbed.cobra_parameters()
    assert p1.mu == pytest.approx(p0.mu * m.mu_scale) and p1.mu_robot_box == pytest.approx(p0.mu_robot_box * m.mu_scale)


@pytest.fixture(scope="module")
def tiny_specs():
    return [RunSpec("J", duration=TINY, member=m) for m in members("J", 2)]


@pytest.fixture(scope="module")
def serial_runs(tiny_specs, tmp_path_factory):
    return run_all(tiny_specs, str(tmp_path_factory.mktemp("serial")), executor=SerialExecutor(), progress=False)


def test_run_all_keys_the_results_by_spec_and_the_member_starts_where_it_was_put(tiny_specs, serial_runs):
    assert list(serial_runs) == tiny_specs
    a, b = (serial_runs[s] for s in tiny_specs)
    assert [a.meta["member"]["index"], b.meta["member"]["index"]] == [0, 1]
    # the member's box starts shifted by its box_shift (before settling, which moves it by far less)
    shift = np.asarray(tiny_specs[1].member.box_shift)
    assert np.allclose(b.box_pose[0, :2] - a.box_pose[0, :2], shift, atol=5e-4)


def test_the_process_pool_gives_exactly_the_serial_numbers(tiny_specs, serial_runs, tmp_path):
    pooled = run_all(tiny_specs, str(tmp_path), workers=2, progress=False)
    for s in tiny_specs:
        assert np.array_equal(pooled[s].q, serial_runs[s].q) and np.array_equal(pooled[s].tau, serial_runs[s].tau)


def test_a_dask_cluster_gives_exactly_the_serial_numbers(tiny_specs, serial_runs, tmp_path):
    distributed = pytest.importorskip("distributed", reason="dask is an optional extra: pip install 'cobra-ref[dask]'")
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        on_dask = run_all(tiny_specs, str(tmp_path), executor=client.get_executor(), progress=False)
    for s in tiny_specs:
        assert np.array_equal(on_dask[s].q, serial_runs[s].q) and np.array_equal(on_dask[s].tau, serial_runs[s].tau)


def test_a_truncated_run_is_its_first_seconds(serial_runs, tiny_specs):
    traj = serial_runs[tiny_specs[0]]
    short = traj.truncated(0.02)
    assert len(short.t) == 21 and len(short.tau) == 20 and short.t[-1] == pytest.approx(0.02)
    assert np.array_equal(short.q, traj.q[:21])
    assert np.all(short.contacts["contact_step"] < 20)
    assert len(short.contacts["contact_step"]) == int(np.sum(traj.contacts["contact_step"] < 20))
    assert traj.truncated(1.0) is traj  # longer than the run: the whole run
    with pytest.raises(ValueError, match="duration must be positive"):
        traj.truncated(0.0)


def test_ensemble_summaries_judge_every_member_on_the_same_window(serial_runs, tiny_specs):
    specs = {"J": tiny_specs}
    out = regenerate.ensemble_summaries(specs, serial_runs, 0.03, goals={"J": [0.6, 0.8]})
    assert [s["duration"] for s in out["J"]] == pytest.approx([0.03, 0.03])
    assert [s["member"]["index"] for s in out["J"]] == [0, 1]
    assert out["J"][1]["goal_direction"] == [0.6, 0.8]


def test_the_goal_direction_is_the_unit_goal_of_the_params_json(tmp_path):
    path = tmp_path / "J.json"
    path.write_text(json.dumps({"settings": {"goal": [0.3, -0.4]}}))
    (tmp_path / "C.json").write_text(json.dumps({"settings": {}}))
    assert regenerate.goal_directions({"J": str(path), "C": str(tmp_path / "C.json")}) == {"J": [0.6, -0.8]}


def test_ensemble_specs_member_0_is_the_figure_run_and_the_others_run_the_window():
    specs = regenerate.ensemble_specs(("C", "J-mirror"), 3)
    assert [s.duration for s in specs["C"]] == [regenerate.FULL_DURATION] + [regenerate.ENSEMBLE_DURATION] * 2
    assert specs["C"][0].member is None and specs["J-mirror"][1].member == ensemble.mirrored(members("J", 3)[1])
    quick = regenerate.ensemble_specs(("C",), 2, quick=True)
    assert [s.duration for s in quick["C"]] == [1.0, 1.0]


# ------------------------------------------------------------------------------------------ --check

def _entry(cid, holds, mean, lo, hi):
    return {"id": cid, "claim": "...", "values": {}, "holds": holds,
            "statistics": {"sidewinding": {"mean": mean, "min": lo, "max": hi, "n": 8}}}


def test_compare_claims_accepts_a_mean_inside_the_committed_spread():
    old = [_entry("WB", True, 2.0, 1.5, 2.5)]
    assert check.compare_claims(old, [_entry("WB", True, 2.4, 2.3, 2.6)]) == []
    # 1 % of 2.5 beyond the top is within the tolerance, 2 % is not
    assert check.compare_claims(old, [_entry("WB", True, 2.52, 2.5, 2.6)]) == []
    assert len(check.compare_claims(old, [_entry("WB", True, 2.55, 2.5, 2.6)])) == 1


def test_compare_claims_names_each_mismatch():
    old = [_entry("WB", True, 2.0, 1.5, 2.5), _entry("E", False, -1.0, -1.2, -0.8), _entry("MJ", True, 0.1, 0.1, 0.1)]
    new = [_entry("WB", False, 2.0, 1.5, 2.5), _entry("E", False, 0.5, 0.4, 0.6), _entry("PP", True, 1.0, 1.0, 1.0)]
    found = check.compare_claims(old, new)
    assert any(m.startswith("WB: verdict True committed, False now") for m in found)
    assert any(m.startswith("E sidewinding: mean 0.5 now, outside the committed [-1.2, -0.8]") for m in found)
    assert "MJ: committed, missing from the regenerated report" in found
    assert "PP: regenerated, not in the committed report" in found
    assert len(found) == 4


def test_a_verdict_field_is_compared_before_holds():
    old = [{"id": "E", "holds": True, "verdict": "holds in 8 of 8"}]
    assert check.compare_claims(old, [{"id": "E", "holds": True, "verdict": "holds in 7 of 8"}])


def test_claim_statistics_are_over_the_members_of_every_gait():
    def fake_claims(summaries):
        return [{"id": "X", "values": {g: s["v"] for g, s in summaries.items()}, "holds": True}]

    stats = check.claim_statistics({"C": [{"v": 1.0}, {"v": 3.0}], "S": [{"v": 2.0}, {"v": 2.0}]}, fake_claims)
    assert stats["X"]["C"] == {"mean": 2.0, "min": 1.0, "max": 3.0, "n": 2}
    assert stats["X"]["S"]["mean"] == 2.0


def test_figures_check_exits_0_when_the_claims_agree_and_1_with_a_table_otherwise(tmp_path, capsys):
    from cobra_ref.cli.figures import check_report

    committed_file = tmp_path / "claims.json"
    committed_file.write_text(json.dumps([_entry("WB", True, 2.0, 1.5, 2.5)]))
    committed = check.read_committed(str(committed_file))
    assert check_report(committed, [_entry("WB", True, 1.9, 1.8, 2.0)]) == 0
    assert "agree" in capsys.readouterr().err
    assert check_report(committed, [_entry("WB", False, 1.9, 1.8, 2.0)]) == 1
    err = capsys.readouterr().err
    assert "1 mismatch" in err and "| 1 | WB: verdict True committed, False now |" in err


def test_a_committed_file_that_is_not_a_claims_report_is_refused(tmp_path):
    path = tmp_path / "claims.json"
    path.write_text(json.dumps({"E": True}))
    with pytest.raises(ValueError, match="is not a claims report"):
        check.read_committed(str(path))


def test_check_leaves_out_the_mujoco_claims_only_when_this_run_made_no_mujoco_comparison(capsys):
    """Without mujoco the regenerated report has no MJ-travel/MJ-box entries: the committed ones
    are left out with a note and the rest agrees (exit 0). With a MuJoCo comparison in the run, a
    committed MuJoCo claim that is missing is a mismatch (exit 1)."""
    from cobra_ref.cli.figures import check_report

    wb = _entry("WB", True, 2.0, 1.5, 2.5)
    travel_C, travel_S = ({"id": f"MJ-travel-{g}", "holds": True} for g in ("C", "S"))
    assert check_report([wb, travel_C, travel_S], [wb]) == 0
    assert "its 2 committed claims are not compared" in capsys.readouterr().err
    assert check_report([wb, travel_C, travel_S], [wb, travel_C]) == 1
    assert "MJ-travel-S: committed, missing from the regenerated report" in capsys.readouterr().err


def test_sidewinding_members_start_from_their_nominal_runs_placement_made_once_per_process(tmp_path):
    """The box-free placement run is made once per process for each nominal run: a member in the
    same process reads it from the cache (``runs._placement``), starts from the same placement
    (direction, reach, gap) as its nominal run, and comes out exactly as a member alone."""
    from cobra_ref.reproduce import runs as runs_mod

    nominal = RunSpec("sidewinding", duration=TINY)
    member = RunSpec("sidewinding", duration=TINY, member=members("sidewinding", 2)[1])
    runs_mod._placement.cache_clear()
    got = run_all([nominal, member], str(tmp_path), executor=SerialExecutor(), progress=False)
    info = runs_mod._placement.cache_info()
    assert (info.misses, info.hits) == (1, 1)  # made for the first run, read for the second
    for key in ("box_direction", "box_reach", "box_gap"):
        assert got[member].meta[key] == got[nominal].meta[key] is not None
    runs_mod._placement.cache_clear()
    alone, _ = runs_mod.simulate_spec(member)
    assert np.array_equal(alone.q, got[member].q) and np.array_equal(alone.tau, got[member].tau)


def test_own_pool_waits_for_its_work_or_ends_its_workers_after_an_exception():
    """On a normal exit the pool has finished what it was given and takes nothing more; when the block
    raises (as Ctrl-C does), the exception goes on and the worker processes are ended, not waited for."""
    import time

    from cobra_ref.infra.executors import own_pool

    with own_pool(1) as pool:
        future = pool.submit(abs, -3)
    assert future.result() == 3
    with pytest.raises(RuntimeError):
        pool.submit(abs, -1)
    start = time.perf_counter()
    with pytest.raises(KeyboardInterrupt):
        with own_pool(1) as pool:
            pool.submit(time.sleep, 30)
            workers = list(pool._processes.values())
            raise KeyboardInterrupt
    assert time.perf_counter() - start < 10  # the 30 s task was not waited for
    # The pool's manager thread reaps the workers too: between its waitpid and its recording of the
    # exit code, our own ``is_alive`` cannot see the exit. So wait (10 s at most) for the exit code
    # that either thread records: a worker that was not ended never gets one.
    deadline = time.perf_counter() + 10
    for process in workers:
        while process.exitcode is None and time.perf_counter() < deadline:
            time.sleep(0.05)
        assert process.exitcode is not None, f"worker {process.pid} was not ended"
        assert process.exitcode != 0  # ended by a signal, not finished
