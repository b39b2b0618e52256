"""The receding-horizon push: one re-plan step by hand, the plan replays bit for bit, interrupts keep the run."""

import json

import numpy as np
import pytest

from cobra_ref.cli import main
from cobra_ref.infra.executors import SerialExecutor
from cobra_ref.planning.primitives import ROLLING, Primitive
from cobra_ref.planning.choices import candidates, warm_start
from cobra_ref.planning.facing import GENTLE
from cobra_ref.planning.receding import PushOptions, candidate_cost, push, replay
from cobra_ref.step import StepSettings

# two periods of 0.1 s at dt = 2 ms, one period ahead, one noisy sample: 19 rollouts of 50 steps per re-plan
TINY = PushOptions(goal=(0.05, 0.0), period=0.1, horizon=1, budget=0.2, samples=1,
                   settings=StepSettings(dt=0.002))


@pytest.fixture(scope="module")
def pushed():
    return push(TINY, SerialExecutor())


def from_start(pair: tuple, target=(0.3, 0.0), options: PushOptions = TINY):
    """The ``Rollout`` of ``pair`` from ``TINY``'s start (t = 0, no stepper memory) towards ``target``."""
    from cobra_ref.planning.primitives import PlanReference
    from cobra_ref.planning.receding import Rollout
    from cobra_ref.robots import cobra_model
    from cobra_ref.start import initial_state

    plan = PlanReference(TINY.start)
    q0, qd0 = initial_state(cobra_model(TINY.cobra), plan, TINY.settings)
    return Rollout(plan.to_dict(), pair, 0.0, q0, qd0, None, tuple(target), options)


def test_the_candidates_of_a_replan():
    # the last choice continued, then stopped, rolled back (then on), a stop near the goal, the four
    # other rolling shapes, near the goal a gentle push of each shape each way then a stop, the samples
    pairs = candidates(Primitive("C"), np.random.default_rng(0), 2)
    assert len(pairs) == 5 + 4 + 10 + 2
    assert pairs[0] == (Primitive("C"), Primitive("C")) and pairs[1][1].family == "stop"
    assert pairs[2][0].frequency == -0.5 and pairs[3] == (pairs[2][0], Primitive("C")) and pairs[4][0].family == "stop"
    assert {p[0].family for p in pairs[5:9]} == {"S", "S-mirror", "J", "J-mirror"}
    gentle = pairs[9:19]
    assert {(p[0].family, p[0].frequency) for p in gentle} == {(f, s * GENTLE[1]) for f in ROLLING for s in (1, -1)}
    assert all(p[0].amplitude == GENTLE[0] and p[1].family == "stop" for p in gentle)
    assert all(p[0].frequency > 0 for p in pairs[19:])  # noise keeps the direction of rolling
    assert len(candidates(Primitive("C"), np.random.default_rng(0), 2, near=False)) == 4 + 4 + 2
    # near but not yet within STILL: the gentle pushes without the stop
    assert len(candidates(Primitive("C"), np.random.default_rng(0), 2, still=False)) == 4 + 4 + 10 + 2


def test_the_next_replan_is_warm_started_from_the_plan_shifted_by_a_period():
    # the plant applied the pair's first period; the next re-plan starts from what the pair goes on with
    on, back, stop = Primitive("C", 0.25, 0.33), Primitive("C", 0.25, -0.33), Primitive("stop")
    turn = Primitive("sidewinding", 0.3, 1.0)
    assert warm_start((back, on), on) == on  # one period back, then on again: "on", not "back"
    assert warm_start((back, back), on) == back
    assert warm_start((on, stop), back) == on  # a push then a stop: the push
    assert warm_start((turn, on), back) == on  # a turn before the push: the push
    assert warm_start((turn, turn), on) == on and warm_start((stop, stop), back) == back  # nothing rolls: kept
    # so the candidates after a period back include going on and then stopping, not only going on
    assert (on, stop) in candidates(warm_start((back, on), on), np.random.default_rng(0), 0)
    assert (on, stop) not in candidates(back, np.random.default_rng(0), 0)
    # and, over a horizon of three periods, going on for two and then stopping: the last plan
    # (back, on, on) shifted by a period, with a stop where it ended
    assert (on, on, stop) in candidates(warm_start((back, on), on), np.random.default_rng(0), 0, horizon=3)


def test_each_period_applies_the_cheapest_candidate(pushed):
    # one re-plan by hand: the chosen primitive is the argmin of the candidates' costs from that state
    assert len(pushed.cycles) == 2
    first = pushed.cycles[0]
    assert first["rollouts"] == 4 + 4 + 10 + 1 and first["t"] == 0.0  # 5 cm away: gentle pushes, no stop yet
    assert Primitive(**first["chosen"]) == pushed.plan.primitives[0]
    assert pushed.plan.starts == [0.0, pytest.approx(0.1)]


def test_a_replans_candidates_cost_the_same_in_a_batch_as_one_by_one():
    # candidate_costs advances the candidates together (cobra_ref.batch); each is its own rollout
    from cobra_ref.planning.receding import candidate_costs

    pairs = [candidates(TINY.start, np.random.default_rng(0), 1)[i] for i in (0, 2, 4, 5)]  # C, back, stop, S
    jobs = [from_start(pair) for pair in pairs]
    batched = candidate_costs(jobs)
    assert [r["cost"] for r in batched] == [candidate_cost(job)["cost"] for job in jobs]
    assert len({r["cost"] for r in batched}) == 4  # four different first periods, four different rollouts
    # a re-plan's batches do not mix rollout lengths: a longer sequence (a recovery's) among the
    # pairs leaves every cost as its own rollout's, and the cheapest is chosen
    from cobra_ref.planning.receding import replan_batched
    longer = from_start((Primitive("C", 0.4, -0.5), Primitive("stop"), Primitive("stop")))
    best, results = replan_batched(jobs[:2] + [longer] + jobs[2:])
    alone = [candidate_cost(job)["cost"] for job in jobs[:2] + [longer] + jobs[2:]]
    assert [r["cost"] for r in results] == alone and best == int(np.argmin(alone))


def test_the_plan_replays_to_the_executed_run_bit_for_bit(pushed):
    again = replay(pushed.plan.to_dict(), TINY)
    for name in ("q", "qd", "tau", "box_pose"):
        np.testing.assert_array_equal(getattr(again, name), getattr(pushed.trajectory, name))


def test_an_interrupt_keeps_what_was_executed():
    calls = []

    def progress(line):
        calls.append(line)
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt) as info:
        push(TINY, SerialExecutor(), progress=progress)
    result = info.value.result
    assert result.reason == "interrupted" and len(result.cycles) == 1
    assert result.trajectory.t[-1] == pytest.approx(0.1)  # the whole first period


def test_push_command_writes_the_run_and_a_plan_that_replays(tmp_path, capsys):
    out, again = tmp_path / "run.npz", tmp_path / "again.npz"
    code = main(["push", "--goal", "0.05,0", "--period", "0.1", "--budget", "0.2", "--horizon", "1",
                 "--samples", "0", "--dt", "0.002", "--workers", "1", "--out", str(out), "--quiet"])
    assert code in (0, 1)  # reached, or the budget ran out first
    record = json.loads((tmp_path / "run.plan.json").read_text())
    assert len(record["cycles"]) == 2 and record["format"] == "cobra-ref push v1"
    line = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert line["final_distance"] == pytest.approx(record["final_distance"])
    assert main(["push", "--replay", str(tmp_path / "run.plan.json"), "--out", str(again)]) == 0
    a, b = np.load(out), np.load(again)
    np.testing.assert_array_equal(a["q"], b["q"])


def test_push_without_a_goal_is_refused(tmp_path):
    with pytest.raises(SystemExit, match="--goal"):
        main(["push", "--out", str(tmp_path / "run.npz")])


def test_the_benchmark_has_sixteen_goals_around_the_box_and_two_paths():
    from cobra_ref.planning.benchmark import GOALS

    singles = [g for g in GOALS if not g[2]]
    assert len(singles) == 16 and len(GOALS) == 18
    distances = sorted({round(float(np.hypot(*g[1])), 9) for g in singles})
    angles = sorted({round(float(np.degrees(np.arctan2(g[1][1], g[1][0]))) % 360) for g in singles})
    assert distances == [0.25, 0.5] and angles == list(range(0, 360, 45))


def test_a_benchmark_subset_writes_rows_and_a_picture(tmp_path):
    from cobra_ref.planning.benchmark import run_benchmark, summary
    from cobra_ref.viz.push_paths import plot_pushes

    kept = []
    tasks = (("ahead", (0.05, 0.0), ()), ("via", (0.05, 0.0), ((0.02, 0.0),)))
    rows = run_benchmark(TINY, SerialExecutor(), tasks=tasks, keep=lambda r: kept.append(len(r)))
    assert kept == [1, 2] and [r["task"] for r in rows] == ["ahead", "via"]
    assert len(rows[1]["waypoint_passes"]) == 1 and rows[0]["simulated_time"] == pytest.approx(0.2)
    s = summary(rows)
    assert s["tasks"] == 2 and s["waypoints"] == 1
    assert s["median_final_error"] == pytest.approx(np.median([r["final_error"] for r in rows]))
    plot_pushes(rows, str(tmp_path / "paths.png"))
    assert (tmp_path / "paths.png").stat().st_size > 1000


def test_the_benchmark_on_a_dask_cluster_gives_exactly_the_serial_rows():
    # the same task, its rollouts distributed by a Dask cluster's executor: the same choices, the same run
    distributed = pytest.importorskip("distributed", reason="dask is an optional extra: pip install 'cobra-ref[dask]'")
    from cobra_ref.planning.benchmark import run_benchmark

    tasks = (("ahead", (0.05, 0.0), ()),)
    serial = run_benchmark(TINY, SerialExecutor(), tasks=tasks)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        on_dask = run_benchmark(TINY, client.get_executor(), tasks=tasks)
    for key in ("final_error", "box_path", "rollouts", "simulated_time", "impact_impulse_per_second", "reason"):
        assert on_dask[0][key] == serial[0][key], key


def test_a_rollout_that_ends_with_the_box_at_the_goal_is_not_charged_for_the_next_push():
    # the approach distance and the lateral weight on the miss prepare a next push: a rollout whose
    # box ends within the tolerance of its target needs none, and costs its distance and its effort,
    # impact and torque terms only, whatever those weights; 5 cm short of the target they count
    from dataclasses import replace as replaced

    pair = (TINY.start, Primitive("stop"))
    end = candidate_cost(from_start(pair))["boxes"][-1]

    def cost(target, **weights):
        return candidate_cost(from_start(pair, target, replaced(TINY, **weights)))["cost"]

    at_goal = np.asarray(end)  # the rollout is deterministic: its box ends exactly here
    assert cost(at_goal, w_approach=0.0, w_lateral=1.0) == cost(at_goal, w_approach=5.0, w_lateral=5.0)
    short = at_goal + (0.05, 0.0)
    assert cost(short, w_approach=0.0, w_lateral=1.0) < cost(short, w_approach=5.0, w_lateral=5.0)


def test_the_pushing_point_lies_behind_the_box_on_the_line_from_the_target():
    # put the box so that the pushing point for a target 0.25 m ahead of it (+x) is exactly the head's
    # centre of mass: half a box and a link radius behind the box centre; the distance is then zero
    from cobra_ref.kinematics import forward_kinematics
    from cobra_ref.params import CobraParameters
    from cobra_ref.planning.receding import pushing_distance
    from cobra_ref.robots import cobra_model, neutral_q

    model, cobra = cobra_model(), CobraParameters()
    q = neutral_q(model)
    kin = forward_kinematics(model, q)
    head = kin.o[0][:2] + (kin.R[0] @ model.com[0])[:2]
    box = model.q_idx[model.boxes[0].body].start
    centre = head + np.array([cobra.box_size / 2 + cobra.radius_link, 0.0])
    q[box:box + 2] = centre
    assert pushing_distance(model, q, centre + [0.25, 0.0], cobra) == pytest.approx(0.0, abs=1e-12)
    # the target on the other side: the pushing point is on the far side of the box
    far = pushing_distance(model, q, centre - [0.25, 0.0], cobra)
    assert far == pytest.approx(min(
        np.linalg.norm(kin.o[i][:2] + (kin.R[i] @ model.com[i])[:2] - (centre + [cobra.box_size / 2 + cobra.radius_link, 0]))
        for i in range(model.nb) if i != model.boxes[0].body))


@pytest.mark.parametrize("field, value, error", [
    ("goal", (0.1,), ValueError), ("goal", (float("nan"), 0.0), ValueError), ("goal", "0.1,0", TypeError),
    ("via", ((0.1, 0.0, 0.2),), ValueError), ("via", "0.1,0", TypeError), ("period", 0.0, ValueError),
    ("horizon", 0, ValueError), ("budget", -1.0, ValueError), ("samples", 1.5, ValueError),
    ("w_impact", -1.0, ValueError), ("w_face", -1.0, ValueError), ("settings", {"dt": 0.001}, TypeError), ("start", "C", TypeError),
])
def test_push_options_are_checked_by_the_command_lines_rules(field, value, error):
    from dataclasses import replace

    with pytest.raises(error, match=field):
        replace(TINY, **{field: value})


def test_a_plant_at_a_finer_dt_executes_the_plan_and_replays_it():
    # the plant steps at 1 ms while the rollouts predict at 2 ms: two worlds; the replay is the plant's
    from dataclasses import replace

    options = replace(TINY, plant_dt=0.001, budget=0.1)
    result = push(options, SerialExecutor())
    assert result.trajectory.dt == 0.001 and len(result.trajectory.tau) == 100
    again = replay(result.plan.to_dict(), options)
    np.testing.assert_array_equal(again.q, result.trajectory.q)


def test_mujoco_as_the_plant_executes_the_plan_and_replays_it():
    # the planner predicts with cobra_ref (2 ms), MuJoCo executes at its 0.05 ms step and is read back
    # every plant step (1 ms: 100 in the 0.1 s budget)
    pytest.importorskip("mujoco")
    from dataclasses import replace

    from cobra_ref.reproduce.mujoco_plant import MujocoPlant

    options = replace(TINY, plant="mujoco", budget=0.1)
    result = push(options, SerialExecutor(), plant=MujocoPlant)
    assert result.trajectory.meta["plant"] == "mujoco" and len(result.trajectory.tau) == 100
    assert np.isfinite(result.trajectory.q).all()
    again = replay(result.plan.to_dict(), options, plant=MujocoPlant)
    np.testing.assert_array_equal(again.q, result.trajectory.q)
    with pytest.raises(ValueError, match="needs its factory"):
        push(options, SerialExecutor())


def test_a_goal_on_the_robots_side_or_beyond_the_budget_is_said_up_front():
    # the start: C with the box on its concave side, pushed along +x; 0.25 m ahead is plain, 0.25 m
    # behind lies on the robot's side (it must go round the box), 12 m ahead is beyond 0.3 m/s for 30 s
    from cobra_ref.planning.primitives import PlanReference
    from cobra_ref.planning.reasons import PUSH_SPEED, outlook
    from cobra_ref.robots import cobra_model
    from cobra_ref.start import initial_state

    model = cobra_model()
    q, _ = initial_state(model, PlanReference(Primitive("C")), StepSettings())
    box = q[model.q_idx[model.boxes[0].body].start:][:2]
    assert outlook(model, q, [tuple(box + (0.25, 0.0))], 30.0) == []
    behind = outlook(model, q, [tuple(box + (-0.25, 0.0))], 30.0)
    assert len(behind) == 1 and "the goal lies on the robot's side of the box" in behind[0]
    far = outlook(model, q, [tuple(box + (0.2, 0.0)), tuple(box + (12.0, 0.0))], 30.0)
    assert len(far) == 1 and "out of reach" in far[0] and 12.0 > PUSH_SPEED * 30.0


def test_a_push_that_spends_its_budget_says_why():
    from cobra_ref.planning.reasons import gave_up

    # the box at each period's start and at the end, and its distance to the target
    still = [(0.0, 0.0), (0.001, 0.0), (0.0, 0.001), (0.002, 0.0), (0.001, 0.0)]
    assert gave_up(still, [0.25, 0.249, 0.25, 0.248, 0.249]) == "budget spent: the robot never moved the box"
    # the box drifts by centimetres but comes less than 3 mm nearer in the last three periods
    creeping = [(0.0, 0.0), (0.1, 0.0), (0.2, 0.0), (0.21, 0.01), (0.21, 0.02), (0.22, 0.03)]
    assert gave_up(creeping, [0.25, 0.15, 0.052, 0.051, 0.05, 0.05]) == \
        "budget spent: the push stalled 5.00 cm from its target"
    pushing = [(0.0, 0.0), (0.05, 0.0), (0.1, 0.0), (0.15, 0.0)]
    assert gave_up(pushing, [0.25, 0.2, 0.15, 0.1]) == "budget spent: still pushing, 10.00 cm from its target"


def test_a_stall_is_offered_the_recoveries_once_then_not_for_three_re_plans():
    # the box stays 5 cm from its target, off the robot's push line (phi 0.3 rad): stalled from the
    # fourth period on (it came less than 3 mm nearer in three periods). Each offer rolls a dozen
    # recoveries out; after one, the next three re-plans push or turn only, whatever they choose
    from cobra_ref.planning.reasons import STALL_PERIODS, calm_after, recovery_periods

    ds, calm, offered = [], 0, []
    for k in range(12):
        ds.append(0.05)
        left = recovery_periods(calm, ds, 0.3, 30 - k)
        offered.append(left)
        calm = calm_after(calm, "push", ("push", "recover") if left is not None else ("push",))
    assert offered == [None] * 3 + [27, None, None, None, 23, None, None, None, 19]
    assert STALL_PERIODS == 3
    # a robot facing away (|phi| > 25 deg) may recover without a stall, by the same count
    assert recovery_periods(3, [0.3], 0.6, 30) == 30 and recovery_periods(2, [0.3], 0.6, 30) is None
    # a recovery's back-off and turns run from the queue (no candidates): the count starts after them
    assert calm_after(5, "recover", ()) == 0 and calm_after(0, "push", ()) == 1


def test_a_push_ends_when_the_robot_has_rested_for_three_periods():
    # three re-plans in a row chose to stop: nothing the planner has brings the box nearer
    from cobra_ref.planning.primitives import PlanReference
    from cobra_ref.planning.receding import ending, resting
    from cobra_ref.planning.reasons import STALL_PERIODS

    on, stop = Primitive("C"), Primitive("stop")
    plan = PlanReference(on)
    for k, p in enumerate([on] + [stop] * (STALL_PERIODS - 1)):
        plan.extend(p, float(k))
    assert not resting(plan)  # two stops after a push
    assert ending(plan, 0.012, 0.01) is None and ending(plan, 0.008, 0.01) == "the box is at the goal"
    plan.extend(stop, float(STALL_PERIODS))
    assert resting(plan)
    assert ending(plan, 0.012, 0.01) == "the robot rests 1.20 cm from the goal: 3 re-plans in a row chose to stop"
    plan.extend(on, 10.0)
    assert not resting(plan) and ending(plan, 0.008, 0.01) is None  # at the goal, but still rolling


def test_the_box_passes_a_waypoint_anywhere_on_its_way_during_a_period():
    # advance_watching takes the steps one advance of the period takes, bit for bit, and returns the
    # box's closest distance to the target on the way: here a target on the box's path at the
    # period's middle, which the period's end has left behind
    from cobra_ref.planning.primitives import PlanReference
    from cobra_ref.planning.receding import advance_watching
    from cobra_ref.robots import cobra_model
    from cobra_ref.simulate import Run
    from cobra_ref.start import initial_state

    model, settings = cobra_model(), StepSettings(dt=0.002)
    plan = PlanReference(Primitive("C", 0.5, 1.0))
    plan.extend(Primitive("C", 0.5, 1.0), 0.0)
    q0, qd0 = initial_state(model, plan, settings)
    box = model.q_idx[model.boxes[0].body].start
    whole, watched = (Run(model, settings, q0, qd0, "fast", 250) for _ in range(2))
    whole.advance(plan, 250)
    middle = whole.finish().q[125, box:box + 2]  # where the box was at 0.25 s
    closest = advance_watching(watched, plan, 250, box, middle)
    np.testing.assert_array_equal(watched.q, whole.q)
    end = float(np.linalg.norm(watched.q[box:box + 2] - middle))
    assert closest == 0.0 and end > 0.005  # sampled every 50 ms, 0.25 s among them; the end 5 mm or more away


def test_benchmark_tasks_are_chosen_by_name_and_their_plans_kept(tmp_path, monkeypatch):
    # --task picks tasks by name (an unknown one is refused, naming the tasks there are); --plans keeps
    # each task's plan JSON, which replays; both apply only with --benchmark. The benchmark's options
    # are shortened by hand: one tiny task in 0.2 s
    from cobra_ref.planning import benchmark

    tiny = (("ahead", (0.05, 0.0), ()), ("left", (0.0, 0.05), ()))
    monkeypatch.setattr(benchmark, "GOALS", tiny)
    assert benchmark.select(["left"]) == tiny[1:] and benchmark.select([]) == tiny
    with pytest.raises(ValueError, match="'right'.*ahead, left"):
        benchmark.select(["right"])
    out, plans = tmp_path / "rows.json", tmp_path / "plans"
    base = ["push", "--benchmark", "--out", str(out), "--budget", "0.2", "--period", "0.1", "--horizon", "1",
            "--samples", "1", "--dt", "0.002", "--plant-dt", "0.002", "--workers", "1", "--quiet"]
    with pytest.raises(SystemExit, match="no benchmark task 'right'"):
        main(base + ["--task", "right"])
    assert main(base + ["--task", "left", "--plans", str(plans)]) == 0
    assert [r["task"] for r in json.loads(out.read_text())["rows"]] == ["left"]
    assert sorted(p.name for p in plans.iterdir()) == ["left.plan.json"]
    assert main(["push", "--replay", str(plans / "left.plan.json"), "--out", str(tmp_path / "again.npz")]) == 0
    box = np.load(tmp_path / "again.npz")["box_pose"][:, :2]  # the replay is the task's run: its box path
    every = 25  # the rows' box path is sampled every 50 ms: 25 steps of the 2 ms plant
    row = json.loads(out.read_text())["rows"][0]
    assert (box[::every] - box[0]).round(5).tolist() == row["box_path"]
    for option in (["--task", "left"], ["--plans", str(plans)], ["--figure", str(tmp_path / "p.png")]):
        with pytest.raises(SystemExit, match=f"{option[0]} applies only with --benchmark"):
            main(["push", "--goal", "0.05,0", "--out", str(tmp_path / "run.npz")] + option)


@pytest.mark.parametrize("nudge", [0.0, 0.05])
def test_a_committed_turn_is_re_planned_when_the_box_is_not_where_its_rollout_put_it(nudge):
    # the goal beside the box: the first re-plan turns, a pair of periods the plant runs whole while
    # the box stays within 2 cm of where the chosen rollout put it. A plant that moves the box 5 cm
    # after the first period (as a sweep the rollouts mispredict does) has the second period re-planned
    from dataclasses import replace

    from cobra_ref.planning.reasons import DEPARTED
    from cobra_ref.simulate import Run

    options = replace(TINY, goal=(0.0, -0.05))

    class Nudged(Run):
        def advance(self, reference, n_steps, progress=None):
            super().advance(reference, n_steps, progress)
            if abs(self.t - options.period) < 1e-9:  # the first period's end
                box = self.model.q_idx[self.model.boxes[0].body].start
                self.q[box] += nudge

    result = push(options, SerialExecutor(), plant=lambda *a: Nudged(*a[:4], "fast", a[4]))
    first, second = result.cycles
    assert first["mode"] == "turn" and first["rollouts"] > 0
    # the rollout (2 ms) put the box within 2 cm of where the plant (1 ms) took it; the nudge comes after
    n = int(round(options.period / options.plant_dt))
    assert np.linalg.norm(np.asarray(first["predicted_box"]) - result.trajectory.box_pose[n, :2]) < DEPARTED
    assert (second["rollouts"] > 0) == (nudge > DEPARTED)  # re-planned, or the committed half ran
