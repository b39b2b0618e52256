"""Single shooting (cobra_ref.planning, cobra-ref optimize): worked examples on a tiny problem.

The tiny problem: the C gait over 0.3 s (ramp 0.1 s), the box 5 mm from the middle link (instead
of 5 cm, so that a short rollout already pushes it), one decision parameter (the frequency in
[0.5, 1.5] Hz), goal 5 cm ahead of the box. At the initial guess (0.5 Hz) the box moves about
2 cm; at 1 Hz about 5 cm, close to the goal. A rollout costs 2-10 s, so the file keeps to about
ten of them.
"""

import argparse
import dataclasses
import json
import os
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pytest

from cobra_ref import planning as sh
from cobra_ref.cli.optimize import add_parsers
from cobra_ref.cli.simulate import cmd_simulate_params
from cobra_ref.infra.arguments import ArgumentTypeError
from cobra_ref.planning.problem import Weights
from cobra_ref.planning.results import params_reference

def one_by_one(evaluate):
    """A made-up ``evaluate(problem, x)`` as the search's ``evaluate_batch(problem, xs)``."""
    return lambda problem, xs: [evaluate(problem, x) for x in xs]


GOAL = (0.05, -0.01)


def tiny_problem(goal=GOAL, names=("frequency",), bounds=None, settings=None, **kw):
    """C over 0.3 s with the box 5 mm away, its frequency in [0.5, 1.5] Hz (or ``names`` in ``bounds``)."""
    space = sh.DecisionSpace(names=names, bounds={"frequency": (0.5, 1.5)} if bounds is None else bounds,
                             ramp_time=0.1)
    return sh.make_problem("C", goal, 0.3, settings, space, box_gap=0.005, **kw)


@pytest.fixture(scope="module")
def problem():
    return tiny_problem()


@pytest.fixture(scope="module")
def serial_result(problem):
    """One compass poll (step 0.5 of the range: the poll point is 1 Hz), serially: 2 rollouts."""
    return sh.optimize(problem, sh.SearchOptions(maxiter=1, step=0.5), executor=sh.SerialExecutor())


@pytest.fixture(scope="module")
def params_file(serial_result, tmp_path_factory):
    path = tmp_path_factory.mktemp("opt") / "params.json"
    sh.write_result(serial_result, str(path))
    return path


def run_cli(argv):
    parser = argparse.ArgumentParser(prog="cobra-ref")
    add_parsers(parser.add_subparsers(dest="command"))
    args = parser.parse_args(argv)
    return args.func(args)


# --- the optimizer --------------------------------------------------------------------------------


def test_optimizer_lowers_the_cost_and_brings_the_box_closer_to_the_goal(serial_result):
    """The shooting method's purpose: J(p*) < J(p0), and the box ends nearer the goal."""
    first, best = serial_result.history[0], serial_result.best
    assert first["params"] == {"frequency": 0.5}, "the first rollout is the initial guess"
    assert best["cost"] < first["cost"], f"cost {first['cost']} -> {best['cost']}"
    assert best["box_distance_to_goal"] < 0.5 * first["box_distance_to_goal"], \
        f"box distance {first['box_distance_to_goal']} -> {best['box_distance_to_goal']}"
    assert [e["rollout"] for e in serial_result.history] == list(range(len(serial_result.history)))
    assert not serial_result.interrupted


def test_cost_terms_add_up_to_the_cost(serial_result, problem):
    """J = w_e E + w_g (d_T / d_0)^2 + w_I I + w_tau P_tau + w_q P_q, with d_0 = |goal| (module docstring)."""
    w = problem.weights
    for e in serial_result.history:
        t = e["terms"]
        expected = (w.effort * t["effort"] + w.goal * t["goal"] + w.impact * t["impact"] + w.tau * t["tau_limit"]
                    + w.q * t["q_limit"])
        np.testing.assert_allclose(e["cost"], expected, rtol=1e-14, err_msg=f"rollout {e['rollout']}")
        np.testing.assert_allclose(np.sqrt(t["goal"]) * np.hypot(*GOAL), e["box_distance_to_goal"], rtol=1e-12)


def test_optimum_meets_the_contact_conditions_and_reports_the_limits(serial_result, problem):
    """Every step of the optimum solved eq. (6): p_N w_N ~ 0 (f_ext orthogonal to the gap rates) and
    p inside the friction cone. Joint limits hold by construction (prescribed joints, A <= q_max);
    the torque limit is exceeded only in the few impact steps, and the penalty counts exactly those."""
    c = problem.cobra
    report = serial_result.best["contact"]
    assert report["max_complementarity"] < 1e-2, report  # [N s m/s]; impulses ~1e-2 N s, speeds ~0.1 m/s
    assert report["max_cone_residual"] < 1e-6, report
    assert report["max_q_excess"] <= 0.0, report
    assert report["fraction_over_tau_max"] < 0.1, report
    assert report["rms_tau_over_tau_max"] < 1.0, report
    traj = sh.rollout(problem, [serial_result.best["params"]["frequency"]])
    excess = np.maximum(traj.steps["tau_excess"], 0.0)
    np.testing.assert_allclose(serial_result.best["terms"]["tau_limit"],
                               traj.dt * excess.sum() / (c.tau_max * problem.duration), rtol=1e-12)
    assert np.count_nonzero(excess) == report["steps_over_tau_max"]


def test_serial_executor_and_process_pool_give_the_same_result(serial_result, problem):
    """The rollouts are deterministic and each batch is collected in order: any executor, same result."""
    with ProcessPoolExecutor(2) as pool:
        pooled = sh.optimize(problem, sh.SearchOptions(maxiter=1, step=0.5), executor=pool)
    keys = ("params", "cost", "box_distance_to_goal", "terms", "box_final")
    assert [{k: e[k] for k in keys} for e in pooled.history] == \
           [{k: e[k] for k in keys} for e in serial_result.history]
    assert pooled.best["cost"] == serial_result.best["cost"]


def test_ctrl_c_keeps_the_best_rollout_found_so_far(problem, tmp_path):
    """A KeyboardInterrupt during the second batch: the first rollout is kept, flagged interrupted."""

    class InterruptSecondBatch(sh.SerialExecutor):
        calls = 0

        def submit(self, fn, /, *args, **kwargs):
            InterruptSecondBatch.calls += 1
            if InterruptSecondBatch.calls > 1:
                raise KeyboardInterrupt
            return super().submit(fn, *args, **kwargs)

    result = sh.optimize(problem, sh.SearchOptions(maxiter=3), executor=InterruptSecondBatch())
    assert result.interrupted and len(result.history) == 1
    record = sh.write_result(result, str(tmp_path / "p.json"))
    assert record["interrupted"] is True and record["params"]["frequency"] == 0.5


# --- the impact term: the paper's "f_ext orthogonal to the gap functions and their derivative" ----------


def made_up_trajectory(problem, impact_impulse, box_xy):
    """A trajectory of 1.5 s at dt = 0.5 s (3 steps): no torque, no limit excess, the given impact
    impulses per step [N s] and the box ending at box_xy (only what ``shooting_cost`` reads)."""
    from types import SimpleNamespace

    n = len(impact_impulse)
    box = np.zeros((n + 1, 7))
    box[-1, :2] = box_xy
    steps = {"impact_impulse": np.asarray(impact_impulse, dtype=float), "tau_excess": np.full(n, -1.0),
             "q_excess": np.full(n, -1.0)}
    return SimpleNamespace(dt=0.5, tau=np.zeros((n, 11)), box_pose=box, steps=steps)


def test_robot_weight_is_twelve_half_kilogram_bodies():
    """m_robot g: head, 10 links and tail of 0.5 kg each (params.py) under 9.81 m/s^2; the box is not counted."""
    from cobra_ref.planning.cost import robot_weight
    from cobra_ref.robots import cobra_model

    assert robot_weight(cobra_model()) == pytest.approx(12 * 0.5 * 9.81, rel=1e-12)
    assert robot_weight(cobra_model(with_box=False)) == pytest.approx(58.86, rel=1e-12)


def test_impact_term_is_zero_without_impacts_and_the_hand_computed_value_for_a_made_up_rollout():
    """Worked example: the box ends on the goal and no torque acts, so J = w_I I. Without impacts
    I = 0 and J = 0. With three impacts of a 0.5 kg link landing at 0.2 m/s (m v_a = 0.1 N s each)
    over T = 1.5 s: I = 0.3 N s / (58.86 N * 1.5 s) = 0.3 / 88.29 = 0.00339789, J = 100 I = 0.339789"""
    from cobra_ref.planning.cost import shooting_cost

    problem = dataclasses.replace(tiny_problem(), duration=1.5)
    goal = problem.goal_world
    calm = shooting_cost(problem, made_up_trajectory(problem, [0.0, 0.0, 0.0], goal))
    assert calm["terms"]["impact"] == 0.0 and calm["cost"] == 0.0
    hits = shooting_cost(problem, made_up_trajectory(problem, [0.1, 0.2, 0.0], goal))
    assert hits["terms"]["impact"] == pytest.approx(0.3 / (58.86 * 1.5), rel=1e-12)
    assert hits["terms"]["impact"] == pytest.approx(0.0033978933, rel=1e-8)
    assert problem.weights.impact == 100.0
    assert hits["cost"] == pytest.approx(100 * 0.3 / (58.86 * 1.5), rel=1e-12)
    unweighted = dataclasses.replace(problem, weights=sh.problem.Weights(impact=0.0))
    assert shooting_cost(unweighted, made_up_trajectory(problem, [0.1, 0.2, 0.0], goal))["cost"] == 0.0


def test_each_rollouts_history_entry_carries_the_impact_term(serial_result, problem):
    """terms["impact"] of every rollout = its impacts' impulse (contact report) / (m_robot g T)."""
    for e in serial_result.history:
        assert e["terms"]["impact"] == pytest.approx(
            e["contact"]["impact_impulse"] / (58.86 * problem.duration), rel=1e-12, abs=0.0)
    rollout = sh.rollout(problem, [serial_result.best["params"]["frequency"]])
    assert serial_result.best["contact"]["impact_impulse"] == float(np.sum(rollout.steps["impact_impulse"]))


# --- the plan-to-check transfer ----------------------------------------------------------------------


def test_transfer_record_is_written_and_read_back(serial_result, problem, tmp_path):
    """The optimum in the plan (dt = 1 ms, the numbers of its history entry) and in the check
    (dt = 0.5 ms); written into the params JSON and read back by load_result. From 1 to 0.5 ms the
    box displacement changes by about 1 % (docs/results.md); the box moves about 5 cm here, so the
    two distances to the goal agree within 2 mm (four times that). A malformed record is refused."""
    from cobra_ref.planning.results import transfer

    x = [serial_result.best["params"]["frequency"]]
    t = transfer(problem, x, serial_result.best)
    assert (t["plan_dt"], t["check_dt"], t["check_error"]) == (1e-3, 5e-4, None)
    assert t["plan_distance_to_goal"] == serial_result.best["box_distance_to_goal"]
    assert t["plan_impact_impulse_per_s"] == serial_result.best["contact"]["impact_impulse"] / problem.duration
    assert abs(t["check_distance_to_goal"] - t["plan_distance_to_goal"]) < 2e-3, t
    assert t["check_impact_impulse_per_s"] >= 0.0
    path = tmp_path / "checked.json"
    sh.write_result(dataclasses.replace(serial_result, transfer=t), str(path))
    assert sh.load_result(str(path))["transfer"] == t
    record = json.loads(path.read_text())
    record["transfer"]["check_distance_to_goal"] = "far"
    path.write_text(json.dumps(record))
    with pytest.raises(sh.ShootingError, match="malformed 'transfer'"):
        sh.load_result(str(path))


def test_committed_optima_load_and_replay():
    """Every committed optimum (cobra_ref/optimized/*.json) loads, was found with the impact term
    at its default weight, has no higher an impact impulse per second than its companion search's
    optimum without the term (lower where they are different rollouts), carries a transfer
    record whose plan numbers are its optimum's, and replays: 0.2 s of the C optimum from its
    recorded start, the box at its recorded pose, the joint torques within tau_max (the position
    servo)."""
    from cobra_ref.reproduce.regenerate import DIRECTIONS, OPTIMIZED_DIR
    from cobra_ref.simulate import simulate

    names = ["C", "S", "J", "J-mirror", "sidewinding"] + [f"direction-{d}" for d in DIRECTIONS]
    for name in names:
        path = os.path.join(OPTIMIZED_DIR, f"{name}.json")
        record = sh.load_result(path)
        assert record["problem"].weights == Weights(), name
        assert not record["interrupted"], name
        impacts = record["impacts"]
        # no more impacts than the optimum without the term (the companion's guarantee); fewer where
        # they are different rollouts
        mine, theirs = impacts["optimum"]["impact_impulse_per_s"], impacts["without_impact_term"]["impact_impulse_per_s"]
        assert (impacts["same"] and mine == theirs) or (impacts["lower"] and mine < theirs), name
        t = record["transfer"]
        assert t["check_error"] is None and t["check_dt"] == 5e-4, name
        assert t["plan_distance_to_goal"] == record["box_distance_to_goal"], name
        assert record["terms"]["impact"] == pytest.approx(
            t["plan_impact_impulse_per_s"] / 58.86, rel=1e-12), name
        assert list(record["box_path"]["xy"][-1]) == record["box_final"], name  # the path ends where the box did
    run = params_reference(os.path.join(OPTIMIZED_DIR, "C.json"), duration=0.2)
    traj = simulate(run.model, run.reference, run.duration, run.settings, run.q0, run.qd0)
    np.testing.assert_array_equal(traj.box_pose[0], run.problem.box_pose0)
    assert np.all(traj.steps["tau_excess"] <= 1e-12)


# --- generic searches on a function known in closed form -----------------------------------------------


def bowl(xs):
    """f(x) = (x0 - 0.3)^2 + 2 (x1 + 0.2)^2, minimum 0 at (0.3, -0.2)."""
    return [float((x[0] - 0.3) ** 2 + 2 * (x[1] + 0.2) ** 2) for x in xs]


def test_compass_search_converges_to_the_minimum_of_a_bowl_within_the_mesh():
    """Compass search: at convergence every poll point at the final step is no better, so the
    minimiser lies within one mesh step (step < min_step) of the iterate."""
    x, f, message = sh.compass_search(bowl, [0.0, 0.0], [-1, -1], [1, 1], maxiter=50, min_step=1 / 64)
    assert message.startswith("converged")
    np.testing.assert_allclose(x, [0.3, -0.2], atol=2 / 64)


def test_compass_search_stays_in_the_bounds():
    seen = []
    sh.compass_search(lambda xs: seen.extend(xs) or bowl(xs), [0.9, 0.9], [0.5, 0.5], [1, 1], maxiter=10)
    assert np.all(np.array(seen) >= 0.5) and np.all(np.array(seen) <= 1.0)


def test_differential_evolution_is_deterministic_for_a_seed_and_starts_from_x0():
    """scipy's DE through our batch map: x0 is the first member, the same seed gives the same run."""
    runs = []
    for _ in range(2):
        seen = []
        sh.differential_evolution_search(lambda xs: seen.extend(map(tuple, xs)) or bowl(xs), [0.1, 0.1],
                                         [-1, -1], [1, 1], maxiter=3, seed=7)
        runs.append(seen)
    assert runs[0] == runs[1]
    np.testing.assert_allclose(runs[0][0], (0.1, 0.1), rtol=1e-14)  # scipy scales x0 to [0, 1] and back
    assert len(runs[0]) == 5 * 4  # max(5, popsize * n) members, initial population + 3 generations


def test_the_companion_search_keeps_the_optimum_from_having_more_impacts_than_the_unpenalized_one(problem, monkeypatch):
    """Made-up rollouts over u = frequency - 0.5 in [0, 1], from u = 0 (step 0.25), w_I = 10:
    G = J - w_I I = 1 - 0.2 u falls to the right, and I = 0.05 + 0.04 u up to u = 0.5, then
    0.07 - 0.06 (u - 0.5). The search of J alone polls u = 0.25 (J = 1.55), 0.125, ... against
    J(0) = 1.5 and stays at u = 0 with I = 0.05; the search of G walks right to u = 1 (G = 0.8,
    I = 0.04, J = 1.2): on its own the penalized search would end with more impacts than the
    unpenalized one. The optimum is the least J over both searches' rollouts, u = 1, which is also
    the least G: the same rollout, so the same impacts."""
    from cobra_ref.planning import search

    def made_up(problem, x):
        u = float(x[0]) - 0.5
        G, I = 1 - 0.2 * u, (0.05 + 0.04 * u if u <= 0.5 else 0.07 - 0.06 * (u - 0.5))
        return {"params": {"frequency": float(x[0])}, "error": None, "cost": G + 10 * I, "box_distance_to_goal": 0.0,
                "terms": {"impact": I}, "contact": {"impact_impulse": I * 58.86 * problem.duration}}

    problem = dataclasses.replace(problem, weights=Weights(impact=10.0))  # the weight the landscape is made for
    monkeypatch.setattr(search, "evaluate_batch", one_by_one(made_up))
    alone = sh.optimize(problem, sh.SearchOptions(maxiter=6, companion=False), executor=sh.SerialExecutor())
    assert alone.best["params"]["frequency"] == 0.5 and alone.best["terms"]["impact"] == 0.05
    result = sh.optimize(problem, sh.SearchOptions(maxiter=6), executor=sh.SerialExecutor())
    assert result.best["params"]["frequency"] == pytest.approx(1.5) and result.best["terms"]["impact"] == pytest.approx(0.04)
    assert result.best["cost"] == min(e["cost"] for e in result.history)
    record = sh.results.impact_comparison(result)
    assert record["same"] and not record["lower"]
    assert record["without_impact_term"]["cost_without_impact"] == min(
        search.cost_without_impact(problem, e) for e in result.history)
    # every point is rolled out once, whichever search polled it
    assert len({e["params"]["frequency"] for e in result.history}) == len(result.history)


def test_the_optimums_impacts_are_at_most_the_unpenalized_optimums_on_any_landscape(problem, monkeypatch):
    """Over one common set of rollouts, J(p*) <= J(p0) and G(p0) <= G(p*) give w_I I(p*) <= w_I I(p0):
    random landscapes, each optimum's impact term no larger than the unpenalized optimum's."""
    from cobra_ref.planning import search

    for seed in range(5):
        rng = np.random.default_rng(seed)
        a, b = rng.uniform(-1, 1, 6), rng.uniform(0, 0.05, 6)

        def made_up(problem, x, a=a, b=b):
            u = float(x[0]) - 0.5
            G = sum(a[k] * np.cos((k + 1) * 3 * u) for k in range(6))
            I = sum(b[k] * (1 + np.sin((k + 2) * 2 * u)) for k in range(6))
            return {"params": {"frequency": float(x[0])}, "error": None, "cost": G + 10 * I, "box_distance_to_goal": 0.0,
                    "terms": {"impact": I}, "contact": {"impact_impulse": I * problem.duration}}

        monkeypatch.setattr(search, "evaluate_batch", one_by_one(made_up))
        record = sh.results.impact_comparison(sh.optimize(problem, sh.SearchOptions(maxiter=8), executor=sh.SerialExecutor()))
        assert record["optimum"]["impact_impulse_per_s"] <= record["without_impact_term"]["impact_impulse_per_s"]
        assert record["lower"] or record["same"]


# --- the params JSON and its replay -----------------------------------------------------------------


def test_replaying_the_json_reproduces_the_recorded_cost_exactly(params_file, tmp_path, capsys):
    """The simulator is deterministic and JSON floats round-trip: the replayed cost is bit-identical,
    through the library (replay) and through `cobra-ref simulate --params` (cmd_simulate_params)."""
    record = json.loads(params_file.read_text())
    traj, cost = sh.replay(str(params_file))
    assert cost["cost"] == record["cost"]
    assert cost["box_distance_to_goal"] == record["box_distance_to_goal"]
    args = argparse.Namespace(params=str(params_file), duration=None, out=str(tmp_path / "r.npz"), quiet=True,
                              stepper="fast")
    assert cmd_simulate_params(args) == 0
    line = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert line["cost_matches"] is True and line["params_cost"] == record["cost"]
    assert (tmp_path / "r.npz").exists()
    run = params_reference(str(params_file))
    assert run.duration == record["settings"]["duration"] and run.recorded_cost == record["cost"]


def test_params_json_holds_every_setting(params_file, problem):
    record = json.loads(params_file.read_text())
    s = record["settings"]
    for key in ("gait", "goal", "duration", "dt", "weights", "decision", "box_pose0", "middle_pose0",
                "fixed", "cobra_parameters", "step_settings"):
        assert key in s, key
    assert record["optimizer"]["seed"] == 0 and record["code"]["version"]
    assert sh.problem_from_dict(s) == problem
    assert len(record["history"]) == 2 and {"cost", "box_distance_to_goal", "params"} <= set(record["history"][0])


def test_params_json_keeps_the_touchdown_substeps_the_run_took(params_file, problem):
    # the file records the setting (None: the law's default, A33) and the n it meant; a file whose n is not
    # this code's default is read with its own n, an older file without them with the default
    s = json.loads(params_file.read_text())["settings"]
    assert s["step_settings"]["touchdown_substeps"] is None and s["step_settings"]["substeps"] == 2
    s["step_settings"]["substeps"] = 4
    assert sh.problem_from_dict(s).settings.substeps == 4
    del s["step_settings"]
    assert sh.problem_from_dict(s) == problem
    s["step_settings"] = {"substeps": 0}
    with pytest.raises(sh.ShootingError, match="step_settings: .*touchdown_substeps"):
        sh.problem_from_dict(s)


@pytest.mark.parametrize("text, message", [
    ("{not json", "not a readable JSON"),
    ('{"format": "something else"}', "not a params file"),
    ('{"format": "cobra-ref optimize v1", "params": {}}', "missing"),
])
def test_malformed_params_json_is_a_clear_error(tmp_path, text, message):
    path = tmp_path / "bad.json"
    path.write_text(text)
    with pytest.raises(sh.ShootingError, match=message):
        params_reference(str(path))


def test_params_json_with_broken_settings_is_a_clear_error(params_file, tmp_path):
    record = json.loads(params_file.read_text())
    record["settings"]["goal"] = ["a", 1]
    path = tmp_path / "broken.json"
    path.write_text(json.dumps(record))
    with pytest.raises(sh.ShootingError, match="malformed settings"):
        params_reference(str(path))
    with pytest.raises(sh.ShootingError, match="not found"):
        params_reference(str(tmp_path / "missing.json"))


# --- bad input -------------------------------------------------------------------------------------


@pytest.mark.parametrize("goal, error, message", [
    (("a", "b"), ArgumentTypeError, "goal X = 'a' is not a number"),
    ((0.1,), sh.ShootingError, r"goal = \(0.1,\) has 1 value \(allowed: 2 numbers \(X, Y\)\)"),
    ((np.nan, 0.0), sh.ShootingError, "goal X = nan is not finite"),
    ((10.0, 0.0), sh.ShootingError, r"goal = \(10, 0\) m is unreachable: 10 m from the box's start"),
    ((0.3, 0.0), sh.ShootingError, "unreachable"),  # 0.3 m in 0.3 s: more than 0.5 m/s
    ((0.0, 0.0), sh.ShootingError, "where the box starts"),
])
def test_bad_goals_are_clear_errors(goal, error, message):
    with pytest.raises(error, match=message):
        tiny_problem(goal=goal)


def test_bounds_that_exclude_the_initial_guess_are_a_clear_error():
    with pytest.raises(sh.ShootingError, match="exclude the initial guess: frequency = 0.5"):
        tiny_problem(bounds={"frequency": (0.6, 1.0)})
    with pytest.raises(sh.ShootingError, match="lo < hi"):
        tiny_problem(bounds={"frequency": (1.0, 0.6)})
    with pytest.raises(sh.ShootingError, match="amplitude"):  # beyond q_max = pi/2: the gait rejects it
        tiny_problem(names=("amplitude",), bounds={"amplitude": (0.3, 2.0)})
    with pytest.raises(sh.ShootingError, match=r"gait_name = .walking. is unknown \(allowed: C, S, J, J-mirror, sidewinding\)"):
        sh.make_problem("walking", GOAL)


def test_optimize_cli_rejects_bad_input_before_any_rollout(tmp_path, capsys):
    out = str(tmp_path / "p.json")
    with pytest.raises(SystemExit) as exc:
        run_cli(["optimize", "--gait", "C", "--goal", "a,b", "--out", out])
    assert exc.value.code == 2 and "not a number" in capsys.readouterr().err
    with pytest.raises(SystemExit, match="unreachable"):
        run_cli(["optimize", "--gait", "C", "--goal", "9,0", "--out", out])
    with pytest.raises(SystemExit, match="exclude the initial guess"):
        run_cli(["optimize", "--gait", "C", "--goal", "0.1,0", "--bound", "frequency=0.7,0.9", "--out", out])
    with pytest.raises(SystemExit, match="NAME=LO,HI"):
        run_cli(["optimize", "--gait", "C", "--goal", "0.1,0", "--bound", "frequency=0.7", "--out", out])
    assert not (tmp_path / "p.json").exists()


def test_optimize_cli_writes_the_json_and_one_json_line(tmp_path, capsys, monkeypatch):
    """`cobra-ref optimize ... --maxiter 0` (the initial guess only), and Ctrl-C in the next run:
    the file is written with "interrupted": true and the exit status is 130."""
    out = tmp_path / "p.json"
    argv = ["optimize", "--gait", "C", "--goal", "0.05,-0.01", "--duration", "0.3", "--ramp-time", "0.1",
            "--box-gap", "0.005", "--workers", "1", "--out", str(out)]
    assert run_cli(argv + ["--maxiter", "0"]) == 0
    captured = capsys.readouterr()
    line = json.loads(captured.out.strip().splitlines()[-1])
    assert len(captured.out.strip().splitlines()) == 1 and line["rollouts"] == 1
    assert "iteration  0/0" in captured.err and "wrote" in captured.err
    record = json.loads(out.read_text())
    assert record["interrupted"] is False and record["cost"] == line["cost"]

    class Interrupt(sh.SerialExecutor):
        def submit(self, fn, /, *args, **kwargs):
            if getattr(self, "done", False):
                raise KeyboardInterrupt
            self.done = True
            return super().submit(fn, *args, **kwargs)

    monkeypatch.setattr("cobra_ref.cli.optimize.SerialExecutor", Interrupt)
    assert run_cli(argv + ["--maxiter", "2"]) == 130
    assert json.loads(out.read_text())["interrupted"] is True
    assert "INTERRUPTED" in capsys.readouterr().err


def test_optimize_cli_no_companion_skips_the_search_without_the_impact_term(tmp_path, capsys):
    """One compass iteration with and without `--no-companion`: the flag leaves out the companion
    search (no 'impacts' comparison in the JSON, never more rollouts); without it the JSON compares
    the optimum with the unpenalized one, whose impact term is never lower than the optimum's."""
    out = tmp_path / "p.json"
    argv = ["optimize", "--gait", "C", "--goal", "0.05,-0.01", "--duration", "0.3", "--ramp-time", "0.1",
            "--box-gap", "0.005", "--workers", "1", "--maxiter", "1", "--quiet", "--out", str(out)]
    assert run_cli(argv) == 0
    both = json.loads(out.read_text())
    assert run_cli(argv + ["--no-companion"]) == 0
    alone = json.loads(out.read_text())
    capsys.readouterr()
    assert both["optimizer"]["companion"] is True and alone["optimizer"]["companion"] is False
    assert alone.get("impacts") is None and both["impacts"] is not None
    assert both["impacts"]["optimum"]["impact_impulse_per_s"] <= both["impacts"]["without_impact_term"]["impact_impulse_per_s"]
    assert len(alone["history"]) <= len(both["history"])
    # the search of J itself is the same: its first rollouts are the same points with the same costs
    assert [h["cost"] for h in alone["history"]] == [h["cost"] for h in both["history"][:len(alone["history"])]]


def test_problem_is_picklable_and_rebuilt_from_json(problem):
    import pickle

    assert pickle.loads(pickle.dumps(problem)) == problem
    assert sh.problem_from_dict(json.loads(json.dumps(sh.problem_to_dict(problem)))) == problem
    assert dataclasses.replace(problem, goal=(0.0, 0.1)).goal_world[1] == pytest.approx(problem.box_pose0[1] + 0.1)


# --- the optimization figure of `cobra-ref figures` --------------------------------------------------

def test_optimization_figure_draws_the_recorded_box_path_and_replays_only_a_json_without_one(
        params_file, tmp_path, monkeypatch):
    """fig_optimization comes from the params JSONs. The optimization keeps its optimum's box path
    (every BOX_PATH_DT = 10 ms, and the last step): exactly the replay's path at those steps, so the
    figure needs no simulation (replay is made to fail). A JSON without the path (written before
    it was kept) is replayed once, then read from the cache."""
    import shutil

    from cobra_ref.planning.cost import BOX_PATH_DT
    from cobra_ref.reproduce import optima

    directory, out, cache = tmp_path / "optimized", tmp_path / "out", tmp_path / "cache"
    directory.mkdir()
    out.mkdir()
    shutil.copy(params_file, directory / "C.json")
    record = sh.load_result(str(params_file))
    replayed, _ = sh.replay(str(params_file))
    every = int(round(BOX_PATH_DT / record["problem"].dt))
    n = len(replayed.box_pose)
    assert record["box_path"]["dt"] == BOX_PATH_DT
    np.testing.assert_array_equal(record["box_path"]["xy"],
                                  replayed.box_pose[[*range(0, n, every)] + ([n - 1] if (n - 1) % every else []), :2])
    assert list(record["box_path"]["xy"][-1]) == record["box_final"]

    def no_simulation(*args, **kw):
        raise AssertionError("replayed although the JSON holds the path (or the cache does)")

    monkeypatch.setattr("cobra_ref.planning.results.replay", no_simulation)
    files = optima.optimization_figures(str(directory), ["C"], str(out), str(cache), False)
    assert sorted(os.path.basename(f) for f in files) == ["fig_optimization.pdf", "fig_optimization.png"]
    with open(out / "fig_optimization.png", "rb") as f:
        assert f.read(4) == b"\x89PNG"
    assert optima.replays_submit(None, str(directory), ["C"], str(cache)) == []
    # a JSON without the path: replayed once (the executor gets it), then from the cache
    old = json.loads(params_file.read_text())
    del old["box_path"]
    (directory / "C.json").write_text(json.dumps(old))
    monkeypatch.undo()
    from cobra_ref.infra.executors import SerialExecutor

    futures = optima.replays_submit(SerialExecutor(), str(directory), ["C"], str(cache))
    assert len(futures) == 1
    np.testing.assert_array_equal(futures[0].result(), replayed.box_pose[:, :2])
    monkeypatch.setattr("cobra_ref.planning.results.replay", no_simulation)
    optima.optimization_figures(str(directory), ["C"], str(out), str(cache), False)


def test_with_the_position_servo_the_optimum_respects_the_torque_and_joint_limits_at_every_step(problem, serial_result):
    """Eq. (6) constraints (2) and (3) held exactly: the default position servo's impulse is
    bounded by tau_max dt in the least-action QP, so no step of any rollout exceeds tau_max
    (tau_excess <= 0), and the joints stay inside q_max; the servo and the contact law are kept
    in the params JSON, and an unknown servo is refused."""
    assert problem.settings.servo == "position" and problem.settings.contact == "compliant"
    traj = sh.rollout(problem, [serial_result.best["params"]["frequency"]])
    assert np.all(traj.steps["tau_excess"] <= 1e-12), traj.steps["tau_excess"].max()
    assert np.all(traj.steps["q_excess"] <= 0.0), traj.steps["q_excess"].max()
    assert serial_result.best["terms"]["tau_limit"] == 0.0 and serial_result.best["terms"]["q_limit"] == 0.0
    again = sh.problem_from_dict(sh.problem_to_dict(problem))
    assert again == problem and (again.settings.servo, again.settings.contact) == ("position", "compliant")
    with pytest.raises(ArgumentTypeError, match="settings = 'stiff' is a str, not a StepSettings"):
        tiny_problem(settings="stiff")


def test_figures_reoptimize_writes_one_params_json_per_gait_and_direction(tmp_path, monkeypatch):
    """``cobra-ref figures --reoptimize`` runs ``regenerate.reoptimize``: one optimization per gait
    and per direction goal, each written as a params JSON that replays (tiny settings here)."""
    from cobra_ref.reproduce import regenerate

    monkeypatch.setattr("cobra_ref.planning.search.DEFAULTS", {"C": (GOAL, 0.3, 1)})
    monkeypatch.setattr("cobra_ref.reproduce.optima.DIRECTIONS", {"right": ("C", (0.05, -0.02))})
    files = regenerate.reoptimize(str(tmp_path), gaits=("C",), progress=False)
    assert sorted(files) == ["C", "direction-right"]
    for path in files.values():
        record = sh.load_result(path)
        assert record["problem"].duration == 0.3 and len(record["history"]) >= 1
        assert record["transfer"]["check_dt"] == 5e-4 and record["transfer"]["check_error"] is None
    assert regenerate.optimized_files(str(tmp_path), ("C", "S")) == {"C": files["C"]}
    assert set(regenerate.optimized_params({"C": files["C"]})["C"]) >= {"amplitude", "frequency"}


def test_candidates_with_the_same_start_shape_share_one_settle_bit_for_bit(monkeypatch):
    """The settled start depends on a candidate only through its t = 0 shape; a change of frequency
    leaves that shape alone (the gaits' t = 0 angles do not depend on it), so start_state settles
    once for both (one call of initial_state) and returns exactly what a fresh settle gives; a change
    of amplitude changes the shape and settles again. The copies it returns are the caller's own."""
    from cobra_ref.planning import problem as problem_module

    problem = tiny_problem(names=("amplitude", "frequency"), bounds={"amplitude": (0.25, 0.75), "frequency": (0.5, 1.5)})
    x = np.asarray(problem.x0, dtype=float)
    faster = x.copy()
    faster[list(problem.names).index("frequency")] += 0.1
    wider = x.copy()
    wider[list(problem.names).index("amplitude")] += 0.05
    problem_module._SETTLED.clear()
    fresh = [sh.start_state(problem, p) for p in (x, faster, wider)]  # the first call of each shape settles
    calls = []
    original = problem_module.initial_state
    monkeypatch.setattr(problem_module, "initial_state", lambda *a, **k: calls.append(1) or original(*a, **k))
    problem_module._SETTLED.clear()
    q_x, qd_x = sh.start_state(problem, x)
    q_x[:] = np.nan  # the caller's copy: the stored start is untouched
    q_f, qd_f = sh.start_state(problem, faster)
    assert len(calls) == 1
    np.testing.assert_array_equal(q_f, fresh[1][0])
    np.testing.assert_array_equal(qd_f, fresh[1][1])
    np.testing.assert_array_equal(sh.start_state(problem, x)[0], fresh[0][0])
    q_w, _ = sh.start_state(problem, wider)
    assert len(calls) == 2
    np.testing.assert_array_equal(q_w, fresh[2][0])
    assert not np.array_equal(q_w, q_f)
