"""The batched rollout engine: a batch of runs is its members' single runs, bit for bit."""

import numpy as np
import pytest

from cobra_ref.batch import BatchRun, initial_states, simulate_batch
from cobra_ref.fast.chain import ChainModel
from cobra_ref.gaits import gait
from cobra_ref.params import CobraParameters
from cobra_ref.robots import cobra_model
from cobra_ref.simulate import simulate
from cobra_ref.start import BoxPlacement, initial_state
from cobra_ref.step import SimulationError, StepSettings

SETTINGS = StepSettings(dt=1e-3)


def random_states(model, k, seed=0):
    """k configurations and velocities: random joint angles and rates, unit quaternions, bases off the ground."""
    rng = np.random.default_rng(seed)
    Q, QD = np.zeros((k, model.nq)), rng.normal(size=(k, model.nv))
    for i in range(model.nb):
        start = model.q_idx[i].start
        if model.joint_type[i] == "free":
            Q[:, start:start + 3] = rng.normal(size=(k, 3)) + [0.0, 0.0, 1.0]
            quat = rng.normal(size=(k, 4))
            Q[:, start + 3:start + 7] = quat / np.linalg.norm(quat, axis=1, keepdims=True)
        else:
            Q[:, start] = rng.uniform(-1.0, 1.0, size=k)
    return Q, QD


def test_the_chain_terms_of_a_batch_are_each_members_own():
    model = cobra_model()
    chain = ChainModel(model)
    Q, QD = random_states(model, 5)
    batch = chain.terms(Q, QD)
    for k in range(5):
        own = chain.terms(Q[k], QD[k])
        for name, part in zip(own._fields, own):
            np.testing.assert_array_equal(getattr(batch, name)[k], part, err_msg=name)


def _members():
    """Three members of one model: C, J and sidewinding, each from its own settled start."""
    model = cobra_model()
    references = [gait(name) for name in ("C", "J", "sidewinding")]
    return model, references, [initial_state(model, ref, SETTINGS) for ref in references]


def _same_run(a, b):
    for name in ("q", "qd", "tau", "box_pose"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    for key in a.steps:
        np.testing.assert_array_equal(a.steps[key], b.steps[key], err_msg=key)
    for key in a.contacts:
        np.testing.assert_array_equal(a.contacts[key], b.contacts[key], err_msg=key)


@pytest.mark.slow
def test_starts_settled_together_are_each_members_own_start_bit_for_bit():
    # C, J and sidewinding settle over different numbers of steps (sidewinding's 3-D shape first rolls
    # onto its side, its velocities zeroed at each peak of its kinetic energy), J on less friction and
    # C with its box pushed aside: each member leaves the batch when it has settled, as alone it stops
    models = [cobra_model(), cobra_model(CobraParameters(mu=0.6)), cobra_model()]
    references = [gait(name) for name in ("C", "J", "sidewinding")]
    boxes = [BoxPlacement(gap=0.08, shift=(0.01, -0.02)), BoxPlacement(), BoxPlacement(turn=0.3)]
    for (q0, qd0), model, ref, box in zip(initial_states(models, references, boxes, SETTINGS), models, references,
                                          boxes):
        alone = initial_state(model, ref, SETTINGS, placement=box)
        np.testing.assert_array_equal(q0, alone[0])
        np.testing.assert_array_equal(qd0, alone[1])


def test_starts_of_a_batch_need_a_model_reference_and_placement_each():
    model, ref = cobra_model(), gait("C")
    with pytest.raises(ValueError, match="as many models, references and placements, got 1, 2 and 1"):
        initial_states([model], [ref, ref], [BoxPlacement()])
    with pytest.raises(TypeError, match="placement"):
        initial_states([model], [ref], [(0.1, 0.0)])
    assert initial_states([], [], []) == []


@pytest.mark.slow
def test_every_member_of_a_batch_takes_its_single_runs_steps_bit_for_bit():
    model, references, starts = _members()
    batch = simulate_batch(model, references, 0.3, SETTINGS, starts)
    for traj, ref, (q0, qd0) in zip(batch, references, starts):
        assert traj.error == ""
        _same_run(traj, simulate(model, ref, 0.3, SETTINGS, q0, qd0))


class _Broken:
    """A reference that stops being finite after t_end (the member's step then fails)."""

    def __init__(self, reference, t_end):
        self.reference, self.t_end = reference, t_end

    def __call__(self, t):
        q, qd, qdd = self.reference(t)
        return (q * np.nan, qd, qdd) if t > self.t_end else (q, qd, qdd)


@pytest.mark.slow
def test_a_failing_member_leaves_the_batch_and_the_others_go_on():
    model, references, starts = _members()
    references[1] = _Broken(references[1], 0.1)
    run = BatchRun(model, SETTINGS, starts, 200)
    run.advance(references, 200)
    C, J, side = run.finish()
    assert "not finite" in J.error and J.error.startswith("step 100 (t = 0.1000 s)")
    assert len(J.tau) == 100  # the steps before the failure are kept
    assert C.error == side.error == "" and len(C.tau) == len(side.tau) == 200
    _same_run(side, simulate(model, references[2], 0.2, SETTINGS, *starts[2]))


@pytest.mark.slow
def test_members_touching_down_together_take_their_substeps_together_as_alone():
    # three C rollouts from one start, their amplitudes 0.01 % apart (a planner's candidates): their
    # touch-downs fall on the same steps, so their substeps (A33) go as one batch of dt / 2, from
    # BATCHED_FROM members on with their problems and friction loops written together
    from cobra_ref.fast.batch import BATCHED_FROM

    model, amplitude = cobra_model(), gait("C").amplitude
    references = [gait("C", amplitude=amplitude * f) for f in (1.0, 1.0001, 0.9999)]
    start = initial_state(model, references[0], SETTINGS)
    batch = simulate_batch(model, references, 0.2, SETTINGS, [start] * 3)
    together = np.sum([traj.steps["substeps"] > 1 for traj in batch], axis=0) >= BATCHED_FROM
    assert together.sum() >= 2
    for traj, ref in zip(batch, references):
        _same_run(traj, simulate(model, ref, 0.2, SETTINGS, *start))


class _BrokenBetweenSteps(_Broken):
    """A reference that stops being finite after t_end at the half steps only, which touch-down
    substeps (A33) read and whole steps do not: the member fails in a substep."""

    def __call__(self, t):
        q, qd, qdd = self.reference(t)
        half_step = round(t / (SETTINGS.dt / 2)) % 2 == 1
        return (q * np.nan, qd, qdd) if t > self.t_end and half_step else (q, qd, qdd)


@pytest.mark.slow
def test_a_member_failing_in_a_substep_fails_as_its_single_run_and_the_others_go_on():
    # the members' substeps are taken together, in a batch of dt / 2: C fails in its first touch-down
    # after 0.05 s, in that batch, as alone
    model, references, starts = _members()
    references[0] = _BrokenBetweenSteps(references[0], 0.05)
    batch = simulate_batch(model, references, 0.3, SETTINGS, starts)
    with pytest.raises(SimulationError, match="not finite at t = 0.1375 s") as err:  # a half step
        simulate(model, references[0], 0.3, SETTINGS, *starts[0])
    alone = err.value.trajectory
    assert batch[0].error == alone.error and "not finite" in alone.error
    assert len(alone.tau) == 137 and np.all(alone.steps["substeps"] == 1)  # the failed step is not logged
    _same_run(batch[0], alone)
    for traj, ref, (q0, qd0) in zip(batch[1:], references[1:], starts[1:]):
        assert traj.error == ""
        _same_run(traj, simulate(model, ref, 0.3, SETTINGS, q0, qd0))


@pytest.mark.slow
def test_a_batch_started_mid_run_continues_as_the_single_run_does():
    # a planner's rollouts start from a plant's state, time and stepper memory
    from cobra_ref.simulate import Run

    model, references, starts = _members()
    plant = Run(model, SETTINGS, *starts[0], "fast", 50)
    plant.advance(references[0], 50)
    single = Run(model, SETTINGS, plant.q, plant.qd, "fast", 100, t0=plant.t, memory=plant.stepping.memory)
    single.advance(references[0], 100)
    batch = BatchRun(model, SETTINGS, [(plant.q, plant.qd)] * 2, 100, t0=plant.t, memory=plant.stepping.memory)
    batch.advance([references[0], references[1]], 100)
    own, other = batch.finish()
    _same_run(own, single.finish())
    assert own.t[0] == pytest.approx(0.05) and not np.array_equal(own.q, other.q)


@pytest.mark.slow
def test_the_optimizers_rollouts_cost_the_same_in_a_batch_as_one_by_one():
    # the search sends each worker its points as one batch (planning.cost.evaluate_batch)
    from cobra_ref import planning as sh
    from cobra_ref.planning.cost import evaluate, evaluate_batch

    space = sh.DecisionSpace(names=("frequency",), bounds={"frequency": (0.5, 1.5)}, ramp_time=0.1)
    problem = sh.make_problem("C", (0.05, -0.01), 0.3, None, space, box_gap=0.005)
    xs = [np.array([0.6]), np.array([0.9]), np.array([1.2])]
    for alone, together in zip([evaluate(problem, x) for x in xs], evaluate_batch(problem, xs)):
        assert alone.keys() == together.keys()
        for key in alone:
            np.testing.assert_array_equal(np.asarray(together[key], dtype=object), np.asarray(alone[key], dtype=object),
                                          err_msg=key)
    assert len({e["cost"] for e in evaluate_batch(problem, xs)}) == 3


@pytest.mark.slow
def test_the_figures_ensemble_members_run_in_a_batch_as_alone():
    # members of one ensemble differ in friction (their models) and start (the box): one batch
    from cobra_ref.reproduce.ensemble import members
    from cobra_ref.reproduce.runs import (BATCH_SIZE, POOL_BATCH, RunSpec, batch_size, batches, simulate_spec,
                                          simulate_specs)

    specs = [RunSpec("C", duration=0.2, member=m) for m in members("C", 3)[1:]] + [RunSpec("J", duration=0.2)]
    # one key's three runs in batches of at most two: two batches, the larger (more steps) first, then the
    # 0.3 s run (more steps than the 0.2 s run alone); five runs in batches of at most four: three and two
    longer = RunSpec("C", duration=0.3)
    assert [[s.duration for s in b] for b in batches(specs + [longer], size=2)] == [[0.2, 0.2], [0.3], [0.2]]
    assert [len(b) for b in batches(specs + [RunSpec("S", duration=0.2), RunSpec("J-mirror", duration=0.2)], 4)] == [3, 2]
    # every worker gets a batch: three runs on two workers go as two batches, 165 on two as batches of at most
    # POOL_BATCH, on an executor's unknown workers of BATCH_SIZE
    assert (batch_size(3, 2), batch_size(165, 2), batch_size(5, None), batch_size(1, 8)) == (2, POOL_BATCH, BATCH_SIZE, 1)
    for (together, failed), spec in zip(simulate_specs(specs), specs):
        alone, alone_failed = simulate_spec(spec)
        assert failed is alone_failed is False and together.meta["member"] == alone.meta["member"]
        _same_run(together, alone)
