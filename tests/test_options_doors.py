"""Explicit options, horizons, the files given to the command line, and the numbers of its messages.

The table runs ``cobra_ref.cli.main(argv)`` in an empty directory for each case an operator can
meet: an option that conflicts with ``--params``, a horizon outside the step-count rule, a params
JSON the model refuses, a run NPZ that ``render`` or ``view`` cannot show. Each must exit 1 with
one line that starts with ``error:`` and names the option or field, print no traceback and no
numpy repr, and write nothing. Then the options that win over the file (recorded in the NPZ's
meta), an optimization whose every rollout fails, and a solver failure that names the inputs.
"""

import json

import numpy as np
import pytest

from cobra_ref.cli import main

from test_inputs import _break_the_stepper_at, _listing, here, inputs, run_main, settled  # noqa: F401

TINY = ["--duration", "0.01", "--quiet"]


# ------------------------------------------------------------------------------------ the files

def _params_variant(inputs, name, change):
    """A copy of the inputs' good params JSON with ``change(record)`` applied, as ``name``.json."""
    record = json.loads((inputs / "good.json").read_text())
    change(record)
    (inputs / f"{name}.json").write_text(json.dumps(record))


def _cobra(field, value):
    return lambda r: r["settings"]["cobra_parameters"].__setitem__(field, value)


def _box_quaternion(*quat):
    return lambda r: r["settings"]["box_pose0"].__setitem__(slice(3, 7), list(quat))


PARAMS_FILES = {
    "n_body_links_50": _cobra("n_body_links", 50),
    "contact_damping_0": _cobra("contact_damping", 0),
    "servo_kd_0": _cobra("servo_kd", 0),
    "box_quaternion_zero": _box_quaternion(0, 0, 0, 0),
    "box_quaternion_long": _box_quaternion(2, 0, 0, 0),
    "huge_list": lambda r: r["settings"].__setitem__("box_pose0", list(range(100_000))),
    "huge_string": _cobra("mu", "a" * 100_000),
}


def _run_variant(inputs, run, name, **arrays):
    """A copy of the run NPZ ``run`` with ``arrays`` replaced, as ``name``.npz."""
    with np.load(run) as z:
        record = {k: z[k] for k in z.files}
    record.update(arrays)
    np.savez(inputs / f"{name}.npz", **record)


@pytest.fixture(scope="module")
def doors(inputs, tmp_path_factory):
    """The inputs directory with the params JSON and run NPZ variants of the table."""
    for name, change in PARAMS_FILES.items():
        _params_variant(inputs, name, change)
    (inputs / "deep.json").write_text("[" * 200_000 + "]" * 200_000)
    run = tmp_path_factory.mktemp("run") / "run.npz"
    assert main(["simulate", "--out", str(run), *TINY]) == 0
    with np.load(run) as z:
        t, pose, kind, step = z["t"], z["box_pose"], z["contact_kind"], z["contact_step"]
    nan_t, zero_quat, bad_kind, late_step = t.copy(), pose.copy(), kind.copy(), step.copy()
    nan_t[3], zero_quat[2, 3:], bad_kind[0], late_step[-1] = np.nan, 0.0, 7, 99
    for name, arrays in {"unequal": {"contact_kind": kind[:-3]}, "pose3": {"box_pose": pose[:, :3]},
                         "nan_t": {"t": nan_t}, "reversed": {"t": t[::-1].copy()},
                         "zero_quat": {"box_pose": zero_quat}, "kind7": {"contact_kind": bad_kind},
                         "step99": {"contact_step": late_step}, "string_t": {"t": np.array(["a"] * len(t))}}.items():
        _run_variant(inputs, run, name, **arrays)
    _run_variant(inputs, run, "good_run")
    np.save(inputs / "lone.npy", t)
    (inputs / "lone.npy").rename(inputs / "lone.npz")
    return inputs


# ------------------------------------------------------------------------------------ the table

# (id, argv, words the one-line message must hold); {in}: the inputs directory. Every case exits 1.
REFUSED = [
    # an option that conflicts with --params: an error (tested with `is not None`: 0 counts)
    ("params-mu-0", ["simulate", "--params", "{in}/good.json", "--mu", "0"], ["--mu cannot be combined"]),
    ("params-box-gap-0", ["simulate", "--params", "{in}/good.json", "--box-gap", "0"], ["--box-gap cannot"]),
    ("params-box-yaw-0", ["simulate", "--params", "{in}/good.json", "--box-yaw", "0"], ["--box-yaw cannot"]),
    ("params-param", ["simulate", "--params", "{in}/good.json", "--param", "amplitude=0.4"], ["--param cannot"]),
    # an empty name is given: it is refused, never replaced by a default
    ("params-empty-name", ["simulate", "--params", "", "--out", "x.npz"], ["params file not found"]),
    ("reference-empty-name", ["simulate", "--reference", "", "--out", "x.npz"], ["is not a file name"]),
    ("figures-empty-out", ["figures", "--quick", "--out", ""], ["output directory is empty"]),
    # an option that does not apply to the rest of the command line: an error, not ignored
    ("pattern-seed", ["optimize", "--gait", "C", "--seed", "3", "--out", "o.json"],
     ["--seed: only --method de draws a population"]),
    ("pattern-popsize-seed", ["optimize", "--gait", "C", "--method", "pattern", "--popsize", "4", "--seed", "0",
                              "--out", "o.json"], ["--seed, --popsize: only --method de"]),
    ("still-fps", ["render", "{in}/good_run.npz", "--out", "x.png", "--fps", "10"], ["--fps sets a video's frames"]),
    ("still-fps-speed", ["render", "{in}/good_run.npz", "--out", "x.png", "--fps", "10", "--speed", "1"],
     ["--fps and --speed set a video's frames"]),
    # a --dt that wins over the file's puts the file's horizon through the step-count rule
    ("params-dt-horizon", ["simulate", "--params", "{in}/good.json", "--dt", "0.0007"],
     ["--duration = 0.1 s is not a whole number of steps of --dt = 0.0007 s"]),
    # every horizon: the step-count rule
    ("optimize-2e6-steps", ["optimize", "--gait", "C", "--duration", "20", "--dt", "1e-5", "--out", "o.json"],
     ["--duration = 20 s at --dt = 1e-5 s is 2e6 steps", "at most 1000000 steps"]),
    ("optimize-half-step", ["optimize", "--gait", "C", "--duration", "1.0005", "--out", "o.json"],
     ["--duration = 1.0005 s is not a whole number of steps of --dt = 0.001 s (1000.5 steps)"]),
    ("convergence-half-step", ["convergence", "--duration", "0.003", "--quiet"],
     ["--duration = 0.003 s is not a whole number of steps of dt = 0.002 s"]),
    ("convergence-below-a-step", ["convergence", "--duration", "0.0001", "--quiet"],
     ["--duration = 0.0001 s is shorter than one step of dt = 0.002 s"]),
    ("sweep-below-a-step", ["sweep", "--n", "1", "--duration", "0.0001", "--quiet"],
     ["--duration = 0.0001 s is shorter than one step of scenario 0's dt"]),
    # numbers as a person writes them
    ("goal-1e308", ["optimize", "--gait", "C", "--goal", "1e308,0", "--out", "o.json"],
     ["goal = (1e308, 0) m is unreachable: 1e308 m from the box's start"]),
    ("goal-100", ["optimize", "--gait", "C", "--goal", "100,0", "--out", "o.json"], ["goal = (100, 0) m is unreachable"]),
    # params JSON: values the model refuses, refused at the door by their rule
    ("json-n-body-links", ["simulate", "--params", "{in}/n_body_links_50.json"],
     ["n_body_links = 50 is out of range", "allowed: an integer [10, 10]"]),
    ("json-contact-damping", ["simulate", "--params", "{in}/contact_damping_0.json"],
     ["contact_damping = 0 N s/m is out of range", "allowed: (0, 1e8] N s/m"]),
    ("json-servo-kd", ["simulate", "--params", "{in}/servo_kd_0.json"], ["servo_kd = 0 N m s/rad is out of range"]),
    ("json-zero-quaternion", ["simulate", "--params", "{in}/box_quaternion_zero.json"],
     ["box_pose0: the quaternion (qw, qx, qy, qz) = (0, 0, 0, 0) has norm 0", "allowed: a unit quaternion"]),
    ("json-long-quaternion", ["simulate", "--params", "{in}/box_quaternion_long.json"],
     ["box_pose0: the quaternion (qw, qx, qy, qz) = (2, 0, 0, 0) has norm 2"]),
    ("json-huge-list", ["simulate", "--params", "{in}/huge_list.json"],
     ["box_pose0: expected 7 finite numbers", "got [0, 1, 2, 3, 4, 5, ...]"]),
    ("json-huge-string", ["simulate", "--params", "{in}/huge_string.json"], ["mu = 'aaaa", "...", "is not a number"]),
    ("json-nested-200000", ["simulate", "--params", "{in}/deep.json"], ["deep.json", "nested deeper than"]),
    # runs given to render and view
    ("render-unequal-contacts", ["render", "{in}/unequal.npz", "--out", "x.png"],
     ["the contact log's arrays have different lengths", "contact_kind 107"]),
    ("render-pose-3", ["render", "{in}/pose3.npz", "--out", "x.png"], ["box_pose has shape (11, 3), expected (11, 7)"]),
    ("render-nan-time", ["render", "{in}/nan_t.npz", "--out", "x.png"], ["t[3] = nan s (allowed: finite times)"]),
    ("render-reversed-times", ["render", "{in}/reversed.npz", "--out", "x.png"],
     ["t[1] = 0.009 s does not follow t[0] = 0.01 s", "strictly increasing"]),
    ("render-zero-quaternion", ["render", "{in}/zero_quat.npz", "--out", "x.gif"],
     ["box_pose[2]: the quaternion", "has norm 0"]),
    ("render-unknown-kind", ["render", "{in}/kind7.npz", "--out", "x.png"], ["contact_kind[0] = 7 (allowed: 0, 1, 2"]),
    ("render-step-beyond", ["render", "{in}/step99.npz", "--out", "x.png"],
     ["contact_step[", "= 99 (allowed: a step of the run, 0 to 9)"]),
    ("render-string-times", ["render", "{in}/string_t.npz", "--out", "x.png"], ["t holds <U1 values"]),
    ("render-npy", ["render", "{in}/lone.npz", "--out", "x.png"], ["lone.npz is not a readable NPZ run"]),
    ("view-reversed-times", ["view", "{in}/reversed.npz"], ["does not follow t[0]"]),
]


@pytest.mark.parametrize("case", REFUSED, ids=[c[0] for c in REFUSED])
def test_refused_with_one_line_naming_the_input_and_nothing_written(case, here, doors, capsys):
    name, argv, words = case
    argv = [a.replace("{in}", str(doors)) for a in argv]
    before = _listing(here)
    try:
        main(argv)
        pytest.fail(f"{name}: the command did not stop")
    except SystemExit as exc:
        message = exc.code
    err = capsys.readouterr().err
    assert isinstance(message, str), f"{name}: exit status {message!r}, expected 1 with a message: {err}"
    assert message.startswith("error:") and "\n" not in message and len(message) < 600, message
    for word in words:
        assert word in message, f"{name}: {word!r} not in {message!r}"
    assert "Traceback" not in err + message and "np.float64" not in message and "e+" not in message
    assert "--at" in argv or "--at" not in message, "a message names only options that were given"
    assert _listing(here) == before, "a refused command writes nothing"


# ------------------------------------------------------------------ options that win, and recorded

def _meta(path):
    with np.load(path) as z:
        return float(z["dt"]), len(z["t"]), json.loads(str(z["meta"]))


@pytest.mark.parametrize("option, value, field, recorded", [
    ("--dt", "0.0005", "dt", 0.0005),
    ("--contact", "rigid", "contact", "rigid"),
    ("--servo", "prescribed", "servo", "prescribed"),
])
def test_a_step_option_wins_over_the_params_file_and_is_recorded(option, value, field, recorded, here, inputs,
                                                                  capsys):
    code, said = run_main(["simulate", "--params", str(inputs / "good.json"), option, value, "--out", "p.npz",
                           *TINY], capsys)
    assert code == 0, said
    dt, n, meta = _meta(here / "p.npz")
    assert meta["options"][field] == recorded and meta["options"]["overrides"][field] == recorded
    assert meta["options"]["overrides"]["duration"] == 0.01
    assert n == round(0.01 / dt) + 1 and dt == (0.0005 if field == "dt" else 0.001)


def test_without_params_the_step_options_record_their_defaults(here, capsys):
    code, said = run_main(["simulate", "--dt", "0.002", "--out", "s.npz", *TINY], capsys)
    assert code == 0, said
    dt, n, meta = _meta(here / "s.npz")
    assert (dt, n) == (0.002, 6)
    assert (meta["options"]["dt"], meta["options"]["contact"], meta["options"]["servo"]) == \
        (0.002, "compliant", "position")


def test_a_replay_with_the_files_own_settings_compares_the_cost(here, inputs, capsys):
    """The good file's horizon is 0.1 s: a replay of it as recorded replays the recorded cost's run."""
    code, said = run_main(["simulate", "--params", str(inputs / "good.json"), "--out", "p.npz", "--quiet"], capsys)
    assert code == 0, said
    _, _, meta = _meta(here / "p.npz")
    assert meta["options"]["overrides"] == {} and meta["options"]["dt"] == 0.001


# ---------------------------------------------------------------------- failures that name their input

def test_an_optimization_whose_every_rollout_fails_exits_1_and_writes_nothing(here, capsys, monkeypatch):
    def fails(problem, xs):  # every rollout of the batch fails at its start, as rollouts reports it
        return [(None, "step failed at step 3, t = 0.0030 s: OSQPException: 4") for _ in xs]

    monkeypatch.setattr("cobra_ref.planning.cost.rollouts", fails)
    code, said = run_main(["optimize", "--gait", "C", "--duration", "0.01", "--goal", "0.003,0", "--maxiter", "0",
                           "--no-companion", "--workers", "1", "--box-mass", "0.7", "--out", "o.json", "--quiet"],
                          capsys)
    assert code == 1 and said.startswith("error: every rollout failed (rollouts: 1); the first: step failed at step 3")
    assert "OSQPException: 4" in said and "--box-mass 0.7" in said and "--dt 0.001" in said
    assert "nothing was written to o.json" in said and not (here / "o.json").exists()


def test_a_solver_failure_while_settling_names_the_inputs(here, capsys, monkeypatch):
    import osqp

    def fails(*args, **kwargs):
        raise osqp.OSQPException(4)

    monkeypatch.setattr("cobra_ref.start.initial_state", fails)
    code, said = run_main(["simulate", "--box-mass", "0.7", "--mu", "0.3", "--out", "s.npz", *TINY], capsys)
    assert code == 1 and "the start could not be placed and settled: OSQPException" in said
    assert "--box-mass 0.7" in said and "--mu 0.3" in said and "--dt 0.001" in said
    assert not (here / "s.npz").exists()


def test_a_solver_failure_mid_run_names_the_inputs(here, capsys, monkeypatch, settled):
    _break_the_stepper_at(0.005, RuntimeError("OSQPException: 4"), monkeypatch, settled)
    code, said = run_main(["simulate", "--box-mass", "0.7", "--out", "run.npz", *TINY], capsys)
    assert code == 1 and "t = 0.0050 s: RuntimeError: OSQPException: 4 (with --dt 0.001" in said
    assert "--box-mass 0.7" in said


def test_a_replay_at_another_dt_is_the_transfer_check(here, inputs, capsys):
    """``simulate --params FILE --dt D`` settles the start and rolls out under D, as the transfer
    check of a params JSON does (``planning.results.transfer``): the same box distance to the goal
    and impact impulse, bit for bit."""
    from cobra_ref.planning.results import decision_vector, load_result, transfer

    record = load_result(str(inputs / "good.json"))
    problem = record["problem"]
    check = transfer(problem, decision_vector(problem, record["params"]), check_dt=0.0005)
    code, said = run_main(["simulate", "--params", str(inputs / "good.json"), "--dt", "0.0005", "--out", "p.npz",
                           "--quiet"], capsys)
    assert code == 0, said
    with np.load(here / "p.npz") as z:
        distance = float(np.linalg.norm(z["box_pose"][-1, :2] - np.asarray(problem.goal_world)))
        impulse = float(np.sum(z["impact_impulse"])) / problem.duration
    assert (distance, impulse) == (check["check_distance_to_goal"], check["check_impact_impulse_per_s"])
