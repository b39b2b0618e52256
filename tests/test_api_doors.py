"""The public Python functions check their arguments by the command line's rules, tried as a notebook
user would: wrong types, NaN, inf, negative, wrong lengths, None.

Each row of ``BAD`` is one call: it must raise the expected class (each an ``ArgumentError``, a
ValueError, or an ``ArgumentTypeError``, a TypeError, of :mod:`cobra_ref.infra.arguments`) with a
message that holds every listed fragment (the argument's name with its value as a person writes
it, and what is allowed) and no numpy repr. Worked example: ``initial_state(model, reference,
placement=BoxPlacement(gap=-1))`` put the box 1 m away on the robot's other side; now
``BoxPlacement(gap=-1)`` raises ``ArgumentError("box_gap = -1 m is out of range (allowed: [0, 1] m)
...")``. ``GOOD`` then shows that valid calls (numpy numbers, paths, a tiny run) still work.
"""

import json
import pathlib
from types import SimpleNamespace

import numpy as np
import pytest

from cobra_ref import (ArgumentError, ArgumentTypeError, BoxPlacement, StepSettings, Trajectory, cobra_model, gait,
                       initial_state, make_stepper, simulate)
from cobra_ref.gaits import GaitError, gait_params
from cobra_ref.mjcf import to_mjcf
from cobra_ref.planning import problem as sh
from cobra_ref.reference import ReferenceError, load_reference

DT = StepSettings(dt=0.002)  # the tiny runs: 10 steps of 2 ms
GOAL = (0.005, 0.0)  # within reach of a 0.02 s horizon (0.5 m/s x 0.02 s = 1 cm)


@pytest.fixture(scope="module")
def ctx(tmp_path_factory):
    """What the calls need: COBRA, a gait, a tiny problem, a run's NPZ and foreign files."""
    d = tmp_path_factory.mktemp("doors")
    model, ref = cobra_model(), gait("C", ramp_time=0.0)
    traj = simulate(model, ref, 0.02, DT)
    traj.to_npz(str(d / "run.npz"))
    np.savez(d / "foreign.npz", a=np.zeros(3))
    (d / "garbage.npz").write_text("not a zip")
    whole = (d / "run.npz").read_bytes()
    (d / "truncated.npz").write_bytes(whole[:len(whole) // 2])
    with np.load(d / "run.npz") as z:
        arrays = dict(z)
    np.savez(d / "bad_meta.npz", **{**arrays, "meta": np.array("{not json")})
    np.savez(d / "bad_dt.npz", **{**arrays, "dt": np.zeros(3)})
    np.savez(d / "reference.npz", t=np.linspace(0.0, 1.0, 5), q=np.zeros((5, 11)))
    problem = sh.make_problem("C", GOAL, 0.02, DT, box_gap=0.05)
    return SimpleNamespace(dir=d, model=model, ref=ref, traj=traj, problem=problem)


def npz(c, name):
    return str(c.dir / name)


T, V = ArgumentTypeError, ArgumentError
# (label, call, class, fragments of the message)
BAD = [
    # simulate
    ("simulate-model-None", lambda c: simulate(None, c.ref, 0.02), T, ["model = None", "a Model"]),
    ("simulate-settings-dict", lambda c: simulate(c.model, c.ref, 0.02, {"dt": 1e-3}), T,
     ["settings = {'dt': 0.001}", "StepSettings"]),
    ("simulate-reference-name", lambda c: simulate(c.model, "C", 0.02), T, ["reference = 'C' is not callable"]),
    ("simulate-duration-str", lambda c: simulate(c.model, c.ref, "0.02"), T, ["duration = '0.02' is not a number"]),
    ("simulate-duration-nan", lambda c: simulate(c.model, c.ref, float("nan")), V, ["duration = nan", "> 0 s"]),
    ("simulate-duration-inf", lambda c: simulate(c.model, c.ref, float("inf")), V, ["duration = inf", "> 0 s"]),
    ("simulate-duration-negative", lambda c: simulate(c.model, c.ref, -1), V, ["duration = -1 s", "> 0 s"]),
    ("simulate-2e6-steps", lambda c: simulate(c.model, c.ref, 20.0, StepSettings(dt=1e-5)), V,
     ["duration = 20 s at dt = 1e-5 s", "at most 1000000 steps"]),
    ("simulate-stepper", lambda c: simulate(c.model, c.ref, 0.02, stepper="quick"), V,
     ["stepper = 'quick' is unknown", "fast, reference"]),
    ("simulate-progress", lambda c: simulate(c.model, c.ref, 0.02, progress=1), T, ["progress = 1 is not callable"]),
    # the settings, the start's settle, the MJCF and a gait's parameters
    ("settings-dt-str", lambda c: StepSettings(dt="0.001"), T, ["dt = '0.001' is not a number"]),
    ("settings-margin-list", lambda c: StepSettings(margin=[0.01]), T, ["margin = [0.01] is not a number"]),
    ("initial-state-settle-str", lambda c: initial_state(c.model, c.ref, StepSettings(dt=0.002), settle="no"), T,
     ["settle = 'no' is a str", "True or False"]),
    ("to-mjcf-None", lambda c: to_mjcf(None), T, ["model = None", "a Model"]),
    ("gait-params-None", lambda c: gait_params(None), T, ["g = None", "RollingGait or SidewindingGait"]),
    # initial_state and its BoxPlacement
    ("box-gap-negative", lambda c: BoxPlacement(gap=-1), V, ["box_gap = -1 m is out of range", "[0, 1] m"]),
    ("box-gap-nan", lambda c: BoxPlacement(gap=float("nan")), V, ["box_gap = nan is not finite", "[0, 1] m"]),
    ("box-gap-str", lambda c: BoxPlacement(gap="0.1"), T, ["box_gap = '0.1' is not a number"]),
    ("box-offset-three", lambda c: BoxPlacement(offset=(1, 2, 3)), V, ["box_offset = (1, 2, 3) has 3 values",
                                                                       "2 numbers (DX, DY)"]),
    ("box-offset-far", lambda c: BoxPlacement(offset=(9.0, 0.0)), V, ["box_offset DX = 9 m", "[-5, 5] m"]),
    ("box-yaw-inf", lambda c: BoxPlacement(yaw=float("inf")), V, ["box_yaw = inf", "[-pi, pi] rad"]),
    ("box-yaw-big", lambda c: BoxPlacement(yaw=4.0), V, ["box_yaw = 4 rad is out of range", "[-pi, pi] rad"]),
    ("box-direction-zero", lambda c: BoxPlacement(direction=(0.0, 0.0)), V, ["box_direction = (0, 0)"]),
    ("box-shift-None-item", lambda c: BoxPlacement(shift=(None, 0.0)), T, ["box_shift DX = None"]),
    ("initial-state-placement-dict", lambda c: initial_state(c.model, c.ref, placement={"gap": 0.05}), T,
     ["placement = {'gap': 0.05}", "BoxPlacement"]),
    ("initial-state-model-None", lambda c: initial_state(None, c.ref), T, ["model = None"]),
    ("initial-state-settings-str", lambda c: initial_state(c.model, c.ref, "fast"), T, ["settings = 'fast'"]),
    ("initial-state-stepper-None", lambda c: initial_state(c.model, c.ref, stepper=None), T, ["stepper = None"]),
    # the model and the stepper a notebook builds first
    ("cobra-model-dict", lambda c: cobra_model({"mu": 0.8}), T, ["params = {'mu': 0.8}", "CobraParameters"]),
    ("make-stepper-model-None", lambda c: make_stepper("fast", None), T, ["model = None", "a Model"]),
    ("make-stepper-settings-float", lambda c: make_stepper("fast", c.model, 0.001), T,
     ["settings = 0.001 is a float", "StepSettings"]),
    # gait
    ("gait-amplitude-str", lambda c: gait("C", amplitude="0.5"), T,
     ["amplitude = '0.5' is not a number", "(0, pi/2] rad"]),
    ("gait-amplitude-bool", lambda c: gait("C", amplitude=True), T, ["amplitude = True is not a number"]),
    ("gait-amplitude-nan", lambda c: gait("C", amplitude=float("nan")), GaitError, ["amplitude = nan is not finite"]),
    ("gait-amplitude-big", lambda c: gait("C", amplitude=2), GaitError,
     ["amplitude = 2 rad is out of range", "(0, pi/2] rad"]),
    ("gait-yaw-huge", lambda c: gait("sidewinding", amplitude_yaw=1e300), GaitError, ["amplitude_yaw = 1e300 rad"]),
    ("gait-frequency-list", lambda c: gait("C", frequency=[1, 2]), T, ["frequency = [1, 2] is not a number",
                                                                        "(0, 10] Hz"]),
    ("gait-ramp-negative", lambda c: gait("J", ramp_time=-1), GaitError, ["ramp_time = -1 s", ">= 0 s"]),
    ("gait-name-None", lambda c: gait(None), T, ["name = None", "sidewinding"]),
    ("gait-name-unknown", lambda c: gait("slithering"), GaitError, ["name = 'slithering' is unknown", "J-mirror"]),
    # make_problem (each refused before any simulation) and its Weights
    ("weights-negative", lambda c: sh.make_problem("C", GOAL, 0.02, weights=sh.Weights(goal=-1)), sh.ShootingError,
     ["weights.goal = -1 is out of range", "[0, 1e6]"]),
    ("weights-nan", lambda c: sh.Weights(effort=float("nan")), sh.ShootingError, ["weights.effort = nan"]),
    ("weights-dict", lambda c: sh.make_problem("C", GOAL, 0.02, weights={"goal": 1}), T, ["weights = {'goal': 1}"]),
    ("problem-2e6-steps", lambda c: sh.make_problem("C", GOAL, 20.0, StepSettings(dt=1e-5)), sh.ShootingError,
     ["duration = 20 s at dt = 1e-5 s", "at most 1000000 steps"]),
    ("problem-duration-str", lambda c: sh.make_problem("C", GOAL, "0.02"), T, ["duration = '0.02' is not a number"]),
    ("problem-duration-nan", lambda c: sh.make_problem("C", GOAL, float("nan")), sh.ShootingError,
     ["duration = nan"]),
    ("problem-box-gap-far", lambda c: sh.make_problem("C", GOAL, 0.02, box_gap=5), sh.ShootingError,
     ["box_gap = 5 m is out of range", "[0, 1] m"]),
    ("problem-box-gap-negative", lambda c: sh.make_problem("C", GOAL, 0.02, box_gap=-1), sh.ShootingError,
     ["box_gap = -1 m"]),
    ("problem-settings-dict", lambda c: sh.make_problem("C", GOAL, 0.02, {"dt": 1e-3}), T, ["settings = {'dt': 0.001}"]),
    ("problem-space-dict", lambda c: sh.make_problem("C", GOAL, 0.02, space={}), T, ["space = {}", "DecisionSpace"]),
    ("space-names-str", lambda c: sh.DecisionSpace(names="frequency"), T,
     ["space.names = 'frequency' is one str", "('frequency',)"]),
    ("space-bounds-list", lambda c: sh.DecisionSpace(bounds=[0.5, 1.0]), T, ["space.bounds = [0.5, 1.0] is a list"]),
    ("space-ramp-negative", lambda c: sh.DecisionSpace(ramp_time=-0.1), sh.ShootingError,
     ["space.ramp_time = -0.1 s is out of range", "[0, 100] s"]),
    ("problem-cobra-str", lambda c: sh.make_problem("C", GOAL, 0.02, cobra="cobra"), T, ["cobra = 'cobra'"]),
    ("problem-gait-None", lambda c: sh.make_problem(None, GOAL, 0.02), T, ["gait_name = None", "sidewinding"]),
    # rollout
    ("rollout-x-short", lambda c: sh.rollout(c.problem, (0.5,)), sh.ShootingError,
     ["x = (0.5,) has 1 value", "2 numbers (amplitude, frequency)"]),
    ("rollout-x-long", lambda c: sh.rollout(c.problem, (0.5, 0.5, 0.5)), sh.ShootingError, ["has 3 values"]),
    ("rollout-x-nan", lambda c: sh.rollout(c.problem, (float("nan"), 0.5)), sh.ShootingError,
     ["x amplitude = nan is not finite"]),
    ("rollout-x-str", lambda c: sh.rollout(c.problem, ("a", 0.5)), T, ["x amplitude = 'a' is not a number"]),
    ("rollout-x-None", lambda c: sh.rollout(c.problem, None), T, ["x = None is not a sequence"]),
    ("rollout-problem-None", lambda c: sh.rollout(None, (0.5, 0.5)), T, ["problem = None", "ShootingProblem"]),
    ("rollout-progress-str", lambda c: sh.rollout(c.problem, (0.5, 0.5), progress="bar"), T,
     ["progress = 'bar' is not callable"]),
    # check_goal
    ("goal-duration-nan", lambda c: sh.check_goal((0.1, 0.0), float("nan")), sh.ShootingError,
     ["duration = nan is not finite", "> 0 s"]),
    ("goal-duration-negative", lambda c: sh.check_goal((0.1, 0.0), -1), sh.ShootingError, ["duration = -1 s"]),
    ("goal-duration-str", lambda c: sh.check_goal((0.1, 0.0), "1"), T, ["duration = '1' is not a number"]),
    ("goal-numpy-far", lambda c: sh.check_goal(np.array([100.0, 0.0]), 1.0), sh.ShootingError,
     ["goal = (100, 0) m is unreachable: 100 m", "at most 0.5 m"]),
    ("goal-1e308", lambda c: sh.check_goal((1e308, 0.0), 1.0), sh.ShootingError,
     ["goal = (1e308, 0) m is unreachable: 1e308 m from"]),
    ("goal-str", lambda c: sh.check_goal("0.1,0", 1.0), T, ["goal = '0.1,0' is not a sequence"]),
    ("goal-three", lambda c: sh.check_goal((0.1, 0.0, 0.0), 1.0), sh.ShootingError,
     ["goal = (0.1, 0.0, 0.0) has 3 values", "2 numbers (X, Y)"]),
    ("goal-inf", lambda c: sh.check_goal((0.1, float("inf")), 1.0), sh.ShootingError, ["goal Y = inf is not finite"]),
    # load_reference
    ("reference-None", lambda c: load_reference(None), T, ["path = None is not a file name"]),
    ("reference-number", lambda c: load_reference(5), T, ["path = 5 is not a file name"]),
    ("reference-q-max-nan", lambda c: load_reference(npz(c, "reference.npz"), float("nan")), ReferenceError,
     ["q_max = nan is not finite", "(0, pi] rad"]),
    ("reference-q-max-str", lambda c: load_reference(npz(c, "reference.npz"), "1.5"), T, ["q_max = '1.5'"]),
    ("reference-missing", lambda c: load_reference(npz(c, "nope.npz")), ReferenceError, ["not found", "nope.npz"]),
    # Trajectory.from_npz
    ("npz-None", lambda c: Trajectory.from_npz(None), T, ["path = None is not a file name"]),
    ("npz-foreign", lambda c: Trajectory.from_npz(npz(c, "foreign.npz")), V,
     ["foreign.npz' is not a run's NPZ", "t, q, qd, tau, box_pose"]),
    ("npz-garbage", lambda c: Trajectory.from_npz(npz(c, "garbage.npz")), V,
     ["garbage.npz' is not an NPZ (zip) archive"]),
    ("npz-truncated", lambda c: Trajectory.from_npz(npz(c, "truncated.npz")), V, ["truncated.npz' is not an NPZ"]),
    ("npz-bad-meta", lambda c: Trajectory.from_npz(npz(c, "bad_meta.npz")), V,
     ["bad_meta.npz': a damaged run NPZ", "JSONDecodeError"]),
    ("npz-bad-dt", lambda c: Trajectory.from_npz(npz(c, "bad_dt.npz")), V, ["bad_dt.npz': a damaged run NPZ"]),
]


@pytest.mark.parametrize("label, call, error, fragments", BAD, ids=[row[0] for row in BAD])
def test_a_bad_argument_is_named_with_its_value_and_what_is_allowed(ctx, label, call, error, fragments):
    with pytest.raises(error) as caught:
        call(ctx)
    message = str(caught.value)
    assert isinstance(caught.value, (ArgumentError, ArgumentTypeError)), f"{label}: {type(caught.value).__name__}"
    for fragment in fragments:
        assert fragment in message, f"{label}: {fragment!r} not in {message!r}"
    assert "np.float64" not in message and "\n" not in message, message


def test_the_families_are_value_and_type_errors():
    """``except ValueError`` / ``except TypeError`` catch them, as a notebook user writes it."""
    assert issubclass(ArgumentError, ValueError) and issubclass(ArgumentTypeError, TypeError)
    for error in (GaitError, ReferenceError, sh.ShootingError):
        assert issubclass(error, ArgumentError), error


@pytest.mark.parametrize("name, call", [
    ("missing", lambda c: Trajectory.from_npz(npz(c, "missing.npz"))),
    ("directory", lambda c: Trajectory.from_npz(str(c.dir))),
])
def test_a_file_that_cannot_be_opened_is_an_oserror_naming_it(ctx, name, call):
    with pytest.raises(OSError) as caught:
        call(ctx)
    assert str(ctx.dir) in str(caught.value)


# (label, call, what the result must satisfy)
GOOD = [
    ("simulate-tiny", lambda c: simulate(c.model, c.ref, np.float64(0.02), DT), lambda r: len(r.t) == 11),
    ("initial-state-placement", lambda c: initial_state(c.model, c.ref, DT, BoxPlacement(
        gap=np.float64(0.1), yaw=np.float32(0.3), offset=None, shift=np.array([0.01, 0.0])), settle=False),
     lambda r: len(r[0]) == 25),
    ("gait-numpy-numbers", lambda c: gait("J", amplitude=np.float64(0.5), frequency=1, s_J=0.4),
     lambda r: r.amplitude == 0.5 and r.frequency == 1),
    ("check-goal-array", lambda c: sh.check_goal(np.array([0.1, -0.05]), 1), lambda r: r == (0.1, -0.05)
     and all(type(v) is float for v in r)),
    ("rollout-array", lambda c: sh.rollout(c.problem, np.array(c.problem.x0)), lambda r: len(r.t) == 11),
    ("load-reference-path", lambda c: load_reference(c.dir / "reference.npz"), lambda r: r.t_end == 1.0),
    ("from-npz-path", lambda c: Trajectory.from_npz(c.dir / "run.npz"),
     lambda r: len(r.t) == 11 and r.meta["settings"]["dt"] == 0.002),
]


@pytest.mark.parametrize("label, call, holds", GOOD, ids=[row[0] for row in GOOD])
def test_valid_calls_still_work(ctx, label, call, holds):
    assert holds(call(ctx)), label


def test_a_run_read_back_is_the_run_written(ctx):
    back = Trajectory.from_npz(pathlib.Path(ctx.dir) / "run.npz")
    assert np.array_equal(back.q, ctx.traj.q) and back.dt == ctx.traj.dt
    assert json.loads(json.dumps(back.meta)) == back.meta
