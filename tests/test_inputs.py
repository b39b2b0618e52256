"""Every input checked, every output safe: the command line and the API tried as a new user would.

Each case of the table runs ``cobra_ref.cli.main(argv)`` in-process in an empty directory and
checks the exit status, that the message names the problem, that no traceback is printed, and
that nothing is left behind (no temporary file, no half-written output; a run that must start
writes only its own output). A handful run through a real subprocess to prove that no traceback
reaches the user's terminal. Then the API (settings, parameters, the writer, the time grid, the
box placement, a failure mid-run) and the generated option tables of docs/cli.md.
"""

import copy
import json
import os
import subprocess
import sys

import numpy as np
import pytest

from cobra_ref.cli import main
from cobra_ref.gaits import gait
from cobra_ref.infra.arguments import ArgumentError
from cobra_ref.infra.output import OutputError, atomic_write, check_output, write_binary, write_text
from cobra_ref.params import CobraParameters
from cobra_ref.robots import cobra_model
from cobra_ref.simulate import simulate
from cobra_ref.step import SimulationError, StepSettings
from cobra_ref.cli.options_doc import CLI_DOC, cli_markdown, options_markdown
from cobra_ref.infra.validation import MAX_STEPS, ValidationError, time_grid

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TINY = ["--duration", "0.01", "--quiet"]  # 10 steps: where a run must start


# ------------------------------------------------------------------------------------------ inputs

def _csv(path, t, q):
    with open(path, "w") as f:
        f.write("t," + ",".join(f"J{i}" for i in range(11)) + "\n")
        for ti, qi in zip(t, q):
            f.write(",".join(repr(float(v)) for v in [ti, *qi]) + "\n")


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    """A directory of input files: references (good and bad) and params JSON (good and bad)."""
    d = tmp_path_factory.mktemp("inputs")
    t = np.linspace(0.0, 2.0, 21)
    zero = np.zeros((21, 11))
    np.savez(d / "straight.npz", t=t, q=zero)
    ten = zero.copy()
    ten[10:, 3] = 10.0
    np.savez(d / "ten.npz", t=t, q=ten)
    _csv(d / "ten.csv", t, ten)
    fast = zero.copy()
    fast[:, 2] = 1.5 * np.sin(2 * np.pi * 3 * t)
    np.savez(d / "fast.npz", t=t, q=fast)
    overshoot = zero.copy()
    overshoot[:, 4] = np.where(np.arange(21) % 2, 1.57, -1.57)
    np.savez(d / "overshoot.npz", t=t, q=overshoot)
    np.savez(d / "negative_t.npz", t=t - 1.0, q=zero)
    nan = zero.copy()
    nan[5, 0] = np.nan
    np.savez(d / "nan.npz", t=t, q=nan)
    np.savez(d / "shape.npz", t=t, q=zero[:, :5])
    np.savez(d / "no_q.npz", t=t)
    (d / "garbage.npz").write_text("not a zip")
    (d / "ref.txt").write_text("t,J0\n")
    _csv(d / "straight.csv", t, zero)
    # params JSON: a tiny problem's settings (as ``cobra-ref optimize`` writes them) and variants
    from cobra_ref.planning import problem as sh
    from cobra_ref.planning.results import problem_to_dict

    problem = sh.make_problem("C", (0.03, -0.01), duration=0.1, box_gap=0.005,
                              space=sh.DecisionSpace(names=("frequency",), bounds={"frequency": (0.5, 1.5)},
                                                     ramp_time=0.05))
    good = {"format": sh.FORMAT, "gait": "C", "params": problem.params(problem.x0), "cost": 1.0,
            "settings": problem_to_dict(problem)}
    (d / "good.json").write_text(json.dumps(good))
    for name, change in PARAMS_VARIANTS.items():
        record = copy.deepcopy(good)
        change(record)
        (d / f"{name}.json").write_text(json.dumps(record))
    (d / "not_json.json").write_text("{not json")
    (d / "other.json").write_text('{"format": "something else"}')
    return d


def _set(path, value):
    """A change of a params record: the value at ``path`` (keys separated by '/'), or removed (None)."""
    *keys, last = path.split("/")

    def change(record):
        node = record
        for k in keys:
            node = node[k]
        if value is _REMOVE:
            del node[last]
        else:
            node[last] = value
    return change


_REMOVE = object()
PARAMS_VARIANTS = {
    "missing_dt": _set("settings/dt", _REMOVE),
    "missing_decision": _set("settings/decision", _REMOVE),
    "missing_params": _set("params", _REMOVE),
    "nan_mu": _set("settings/cobra_parameters/mu", float("nan")),
    "negative_box_mass": _set("settings/cobra_parameters/box_mass", -1.0),
    "string_mu": _set("settings/cobra_parameters/mu", "abc"),
    "string_duration": _set("settings/duration", "abc"),
    "bad_inertia": _set("settings/cobra_parameters/inertia_link", [1e-3, 1e-3, 5e-3]),
    "short_inertia": _set("settings/cobra_parameters/inertia_link", [1e-3, 1e-3]),
    "unknown_parameter": _set("settings/cobra_parameters/stiffness", 3.0),
    "goal_zero": _set("settings/goal", [0, 0]),
    "goal_far": _set("settings/goal", [9.0, 0.0]),
    "goal_string": _set("settings/goal", ["a", 1]),
    "weights_string": _set("settings/weights", "abc"),
    "weight_string": _set("settings/weights/goal", "abc"),
    "weight_negative": _set("settings/weights/effort", -1.0),
    "params_out_of_bounds": _set("params/frequency", 1.9),
    "params_refused_by_gait": _set("params/amplitude", 10.0),
    "params_string": _set("params/frequency", "fast"),
    "x0_out_of_bounds": _set("settings/decision/x0", [2.0]),
    "bounds_reversed": _set("settings/decision/lower", [1.6]),
    "dt_too_large": _set("settings/dt", 0.1),
    "servo_unknown": _set("settings/servo", "pd"),
    "gait_unknown": _set("settings/gait", "walking"),
    "box_pose_short": _set("settings/box_pose0", [0.0, 0.0]),
    "cost_nan": _set("cost", float("nan")),
}


# ------------------------------------------------------------------------------- the command table

# (id, argv, exit status, text the message must contain); {in} = the inputs directory, {here} = the
# empty working directory of the case. Status 2: argparse refused an option (message on stderr);
# status 1: the command refused the input (its message is the SystemExit's).
REFUSED = [
    # --- simulate: time grid
    ("dt-too-large", ["simulate", "--dt", "0.1"], 2, "--dt = 0.1 s is out of range (allowed: [1e-5, 0.005] s)"),
    ("dt-just-above", ["simulate", "--dt", "0.006"], 2, "--dt = 0.006 s is out of range"),
    ("dt-tiny", ["simulate", "--dt", "1e-9"], 2, "--dt = 1e-9 s is out of range"),
    ("dt-nan", ["simulate", "--dt", "nan"], 2, "--dt = nan is not finite"),
    ("dt-inf", ["simulate", "--dt", "inf"], 2, "--dt = inf is not finite"),
    ("dt-word", ["simulate", "--dt", "fast"], 2, "--dt = 'fast' is not a number"),
    ("dt-zero", ["simulate", "--dt=0"], 2, "--dt = 0 s is out of range"),
    ("dt-negative", ["simulate", "--dt=-1e-3"], 2, "--dt = -0.001 s is out of range"),
    ("duration-huge", ["simulate", "--duration", "1e9"], 2, "--duration = 1e9 s is out of range"),
    ("duration-zero", ["simulate", "--duration", "0"], 2, "--duration = 0 s is out of range"),
    ("duration-negative", ["simulate", "--duration=-1"], 2, "--duration = -1 s is out of range"),
    ("duration-nan", ["simulate", "--duration", "nan"], 2, "--duration = nan is not finite"),
    ("too-many-steps", ["simulate", "--duration", "2000"], 1, f"at most {MAX_STEPS} steps per run"),
    ("too-many-steps-small-dt", ["simulate", "--duration", "20", "--dt", "1e-5"], 1, "is 2e6 steps"),
    ("dt-longer-than-duration", ["simulate", "--dt", "0.004", "--duration", "0.001"], 1,
     "--duration = 0.001 s is shorter than one step of --dt = 0.004 s"),
    ("duration-not-whole-steps", ["simulate", "--dt", "0.003", "--duration", "1"], 1,
     "--duration = 1 s is not a whole number of steps of --dt = 0.003 s (333.33 steps): use --duration = 0.999 s or "
     "1.002 s"),
    ("half-a-step", ["simulate", "--dt", "0.004", "--duration", "0.01"], 1, "(2.5 steps)"),
    # --- simulate: friction, box
    ("mu-nan", ["simulate", "--mu", "nan"], 2, "--mu = nan is not finite (allowed: [0, 2])"),
    ("mu-negative", ["simulate", "--mu=-0.1"], 2, "--mu = -0.1 is out of range (allowed: [0, 2])"),
    ("mu-huge", ["simulate", "--mu", "5"], 2, "--mu = 5 is out of range"),
    ("mu-word", ["simulate", "--mu", "high"], 2, "--mu = 'high' is not a number"),
    ("mu-robot-box-negative", ["simulate", "--mu-robot-box=-1"], 2, "--mu-robot-box = -1 is out of range"),
    ("box-mass-negative", ["simulate", "--box-mass=-0.1"], 2, "--box-mass = -0.1 kg is out of range (allowed: [0.001, 100] kg)"),
    ("box-mass-zero", ["simulate", "--box-mass", "0"], 2, "--box-mass = 0 kg is out of range"),
    ("box-mass-inf", ["simulate", "--box-mass", "inf"], 2, "--box-mass = inf is not finite"),
    ("box-offset-one-number", ["simulate", "--box-offset", "0.1"], 2, "--box-offset = '0.1': expected DX,DY"),
    ("box-offset-three-numbers", ["simulate", "--box-offset", "1,2,3"], 2, "expected DX,DY"),
    ("box-offset-word", ["simulate", "--box-offset", "0.1,abc"], 2, "--box-offset DY = 'abc' is not a number"),
    ("box-offset-far", ["simulate", "--box-offset", "9,0"], 2, "--box-offset DX = 9 m is out of range (allowed: [-5, 5] m)"),
    ("box-offset-nan", ["simulate", "--box-offset", "0,nan"], 2, "--box-offset DY = nan is not finite"),
    ("box-yaw-large", ["simulate", "--box-yaw", "10"], 2, "--box-yaw = 10 rad is out of range (allowed: [-pi, pi] rad)"),
    ("box-yaw-nan", ["simulate", "--box-yaw", "nan"], 2, "--box-yaw = nan is not finite"),
    ("box-gap-negative", ["simulate", "--box-gap=-0.01"], 2, "--box-gap = -0.01 m is out of range"),
    ("box-gap-and-offset", ["simulate", "--box-gap", "0.02", "--box-offset", "0.3,0"], 1, "give one of them"),
    ("box-on-the-robot", ["simulate", "--box-offset", "0,0", *TINY], 1,
     "deep penetration: robot-box contact"),
    # --- simulate: the gait and its parameters
    ("gait-unknown", ["simulate", "--gait", "slithering"], 2, "unknown gait 'slithering'; gaits: rolling, C"),
    ("param-no-value", ["simulate", "--param", "amplitude"], 2, "--param = 'amplitude': expected NAME=VALUE"),
    ("param-word", ["simulate", "--param", "amplitude=big"], 2, "--param amplitude = 'big' is not a number"),
    ("param-nan", ["simulate", "--param", "amplitude=nan"], 2, "--param amplitude = nan is not finite"),
    ("param-beyond-q-max", ["simulate", "--param", "amplitude=10"], 1, "amplitude = 10 rad is out of range (allowed: (0, pi/2] rad)"),
    ("param-unknown", ["simulate", "--param", "wiggle=1"], 1, "unknown parameter(s) wiggle for gait 'C'"),
    ("param-twice", ["simulate", "--param", "amplitude=0.3", "--param", "amplitude=0.4"], 1,
     "--param amplitude is given twice"),
    ("param-frequency", ["simulate", "--param", "frequency=50"], 1, "frequency = 50 Hz is out of range (allowed: (0, 10] Hz)"),
    ("param-with-reference", ["simulate", "--reference", "{in}/straight.npz", "--param", "amplitude=0.3"], 1,
     "--param sets the parameters of a built-in gait"),
    ("contact-unknown", ["simulate", "--contact", "soft"], 2, "invalid choice: 'soft'"),
    ("servo-unknown", ["simulate", "--servo", "pd"], 2, "invalid choice: 'pd'"),
    ("stepper-unknown", ["simulate", "--stepper", "turbo"], 2, "invalid choice: 'turbo'"),
    ("gait-and-reference", ["simulate", "--gait", "S", "--reference", "{in}/straight.npz"], 2, "not allowed with"),
    # --- simulate: reference files
    ("reference-ten-radians", ["simulate", "--reference", "{in}/ten.npz"], 1,
     "joint J3 = 10 rad at t = 1 s is beyond the joint limit |q| <= q_max = 1.5708 rad"),
    ("reference-ten-radians-csv", ["simulate", "--reference", "{in}/ten.csv"], 1, "joint J3 = 10 rad at t = 1 s"),
    ("reference-overshoot", ["simulate", "--reference", "{in}/overshoot.npz", "--duration", "0.1"], 1,
     "(interpolated): joint J4"),
    ("reference-negative-time", ["simulate", "--reference", "{in}/negative_t.npz"], 1, "times must start at t >= 0 s"),
    ("reference-nan", ["simulate", "--reference", "{in}/nan.npz"], 1, "non-finite values in t or q"),
    ("reference-shape", ["simulate", "--reference", "{in}/shape.npz"], 1, "'q' must have shape (21, 11)"),
    ("reference-no-q", ["simulate", "--reference", "{in}/no_q.npz"], 1, "NPZ needs arrays 't' and 'q'"),
    ("reference-not-zip", ["simulate", "--reference", "{in}/garbage.npz"], 1, "malformed reference file"),
    ("reference-format", ["simulate", "--reference", "{in}/ref.txt"], 1, "unknown reference format"),
    ("reference-missing", ["simulate", "--reference", "{in}/nope.npz"], 1, "reference file not found"),
    # --- simulate: the output
    ("out-directory", ["simulate", "--out", "{here}/adir", *TINY], 1, "is a directory, not a regular file"),
    ("out-trailing-slash", ["simulate", "--out", "{here}/x/", *TINY], 1, "names a directory"),
    ("out-empty", ["simulate", "--out", "", *TINY], 1, "--out path is empty"),
    ("out-blank", ["simulate", "--out", "  ", *TINY], 1, "--out path is empty"),
    ("out-proc", ["simulate", "--out", "/proc/run.npz", *TINY], 1, "cannot write in output directory /proc"),
    ("out-missing-dir", ["simulate", "--out", "{here}/nope/run.npz", *TINY], 1, "output directory does not exist"),
    ("out-device", ["simulate", "--out", "/dev/null", *TINY], 1, "is a character device, not a regular file"),
    ("out-link-to-directory", ["simulate", "--out", "{here}/dirlink", *TINY], 1, "is a directory"),
    ("out-link-loop", ["simulate", "--out", "{here}/loop", *TINY], 1, "a loop of symbolic links"),
    # --- simulate --params
    ("params-with-mu", ["simulate", "--params", "{in}/good.json", "--mu", "0.5"], 1,
     "--mu cannot be combined with it"),
    ("params-with-box-offset", ["simulate", "--params", "{in}/good.json", "--box-offset", "0.2,0"], 1,
     "--box-offset cannot be combined"),
    ("params-duration-not-whole", ["simulate", "--params", "{in}/good.json", "--duration", "0.0105"], 1,
     "is not a whole number of steps of dt = 0.001 s"),
    ("params-missing-file", ["simulate", "--params", "{in}/nope.json"], 1, "params file not found"),
    ("params-not-json", ["simulate", "--params", "{in}/not_json.json"], 1, "not a readable JSON file"),
    ("params-not-ours", ["simulate", "--params", "{in}/other.json"], 1, "not a params file of cobra-ref optimize"),
    ("params-missing-dt", ["simulate", "--params", "{in}/missing_dt.json"], 1, "missing key 'dt'"),
    ("params-missing-decision", ["simulate", "--params", "{in}/missing_decision.json"], 1, "missing key 'decision'"),
    ("params-missing-params", ["simulate", "--params", "{in}/missing_params.json"], 1, "missing 'params'"),
    ("params-nan-mu", ["simulate", "--params", "{in}/nan_mu.json"], 1, "settings.cobra_parameters: mu = nan is not finite"),
    ("params-negative-box-mass", ["simulate", "--params", "{in}/negative_box_mass.json"], 1,
     "box_mass = -1 kg is out of range"),
    ("params-string-mu", ["simulate", "--params", "{in}/string_mu.json"], 1, "mu = 'abc' is not a number"),
    ("params-string-duration", ["simulate", "--params", "{in}/string_duration.json"], 1,
     "duration = 'abc' is not a number"),
    ("params-bad-inertia", ["simulate", "--params", "{in}/bad_inertia.json"], 1, "violates the triangle inequality"),
    ("params-short-inertia", ["simulate", "--params", "{in}/short_inertia.json"], 1, "expected three numbers"),
    ("params-unknown-parameter", ["simulate", "--params", "{in}/unknown_parameter.json"], 1,
     "unexpected keyword argument 'stiffness'"),
    ("params-goal-zero", ["simulate", "--params", "{in}/goal_zero.json"], 1, "is where the box starts"),
    ("params-goal-far", ["simulate", "--params", "{in}/goal_far.json"], 1, "is unreachable"),
    ("params-goal-string", ["simulate", "--params", "{in}/goal_string.json"], 1, "goal: expected 2 finite numbers"),
    ("params-weights-string", ["simulate", "--params", "{in}/weights_string.json"], 1,
     "settings.weights: ValueError: expected {term: weight}"),
    ("params-weight-string", ["simulate", "--params", "{in}/weight_string.json"], 1,
     "weights.goal = 'abc' is not a number"),
    ("params-weight-negative", ["simulate", "--params", "{in}/weight_negative.json"], 1,
     "weights.effort = -1 is out of range"),
    ("params-out-of-bounds", ["simulate", "--params", "{in}/params_out_of_bounds.json"], 1,
     "params frequency = 1.9 is outside the optimization's bounds [0.5, 1.5]"),
    ("params-refused-by-gait", ["simulate", "--params", "{in}/params_refused_by_gait.json"], 1,
     "malformed 'params': amplitude = 10 rad is out of range"),
    ("params-string-value", ["simulate", "--params", "{in}/params_string.json"], 1, "malformed 'params'"),
    ("params-x0-out-of-bounds", ["simulate", "--params", "{in}/x0_out_of_bounds.json"], 1,
     "x0 frequency = 2.0 is outside its bounds"),
    ("params-bounds-reversed", ["simulate", "--params", "{in}/bounds_reversed.json"], 1, "lower < upper"),
    ("params-dt-too-large", ["simulate", "--params", "{in}/dt_too_large.json"], 1, "dt = 0.1 s is out of range"),
    ("params-servo-unknown", ["simulate", "--params", "{in}/servo_unknown.json"], 1, "servo must be one of"),
    ("params-gait-unknown", ["simulate", "--params", "{in}/gait_unknown.json"], 1, "gait 'walking'"),
    ("params-box-pose-short", ["simulate", "--params", "{in}/box_pose_short.json"], 1,
     "box_pose0: expected 7 finite numbers"),
    ("params-cost-nan", ["simulate", "--params", "{in}/cost_nan.json"], 1, "malformed 'cost'"),
    # --- export-mjcf
    ("mjcf-timestep-nan", ["export-mjcf", "--timestep", "nan", "{here}/m.xml"], 2, "--timestep = nan is not finite"),
    ("mjcf-timestep-negative", ["export-mjcf", "--timestep=-1", "{here}/m.xml"], 2,
     "--timestep = -1 s is out of range (allowed: [1e-6, 0.002] s)"),
    ("mjcf-timestep-large", ["export-mjcf", "--timestep", "0.01", "{here}/m.xml"], 2, "stiff contact explicitly"),
    ("mjcf-timestep-word", ["export-mjcf", "--timestep", "small", "{here}/m.xml"], 2, "is not a number"),
    ("mjcf-device", ["export-mjcf", "/dev/null"], 1, "'/dev/null' is a character device, not a regular file"),
    ("mjcf-directory", ["export-mjcf", "{here}/adir"], 1, "is a directory"),
    ("mjcf-empty", ["export-mjcf", ""], 1, "path is empty"),
    ("mjcf-proc", ["export-mjcf", "/proc/cobra.xml"], 1, "cannot write in output directory /proc"),
    ("mjcf-missing-dir", ["export-mjcf", "{here}/nope/cobra.xml"], 1, "output directory does not exist"),
    ("mjcf-link-to-directory", ["export-mjcf", "{here}/dirlink"], 1, "is a directory"),
    # --- optimize (refused before any rollout)
    ("optimize-dt", ["optimize", "--gait", "C", "--dt", "0.1", "--out", "{here}/p.json"], 2, "--dt = 0.1 s is out of range"),
    ("optimize-mu-high", ["optimize", "--gait", "C", "--mu", "5", "--out", "{here}/p.json"], 2, "--mu = 5 is out of range"),
    ("optimize-box-mass-zero", ["optimize", "--gait", "C", "--box-mass", "0", "--out", "{here}/p.json"], 2,
     "--box-mass = 0 kg is out of range"),
    ("optimize-mu-box-ground-nan", ["optimize", "--gait", "C", "--mu-box-ground", "nan", "--out", "{here}/p.json"], 2,
     "--mu-box-ground = nan is not finite"),
    ("simulate-mu-box-ground-negative", ["simulate", "--mu-box-ground=-0.1", "--out", "{here}/r.npz"], 2,
     "--mu-box-ground = -0.1 is out of range"),
    ("optimize-goal-word", ["optimize", "--gait", "C", "--goal", "a,b", "--out", "{here}/p.json"], 2,
     "--goal X = 'a' is not a number"),
    ("optimize-goal-far", ["optimize", "--gait", "C", "--goal", "9,0", "--out", "{here}/p.json"], 1,
     "is unreachable"),
    ("optimize-goal-nan", ["optimize", "--gait", "C", "--goal", "nan,0", "--out", "{here}/p.json"], 2,
     "--goal X = nan is not finite"),
    ("optimize-maxiter-negative", ["optimize", "--gait", "C", "--maxiter=-1", "--out", "{here}/p.json"], 2,
     "--maxiter = -1 is out of range (allowed: an integer [0, 10000])"),
    ("optimize-maxiter-fraction", ["optimize", "--gait", "C", "--maxiter", "2.5", "--out", "{here}/p.json"], 2,
     "--maxiter = '2.5' is not an integer"),
    ("optimize-workers-zero", ["optimize", "--gait", "C", "--workers", "0", "--out", "{here}/p.json"], 2,
     "--workers = 0 is out of range"),
    ("optimize-seed-negative", ["optimize", "--gait", "C", "--seed=-1", "--out", "{here}/p.json"], 2,
     "--seed = -1 is out of range"),
    ("optimize-popsize-zero", ["optimize", "--gait", "C", "--popsize", "0", "--out", "{here}/p.json"], 2,
     "--popsize = 0 is out of range"),
    ("optimize-box-gap", ["optimize", "--gait", "C", "--box-gap=-1", "--out", "{here}/p.json"], 2,
     "--box-gap = -1 m is out of range"),
    ("optimize-duration-nan", ["optimize", "--gait", "C", "--duration", "nan", "--out", "{here}/p.json"], 2,
     "--duration = nan is not finite"),
    ("optimize-ramp-negative", ["optimize", "--gait", "C", "--ramp-time=-1", "--out", "{here}/p.json"], 2,
     "--ramp-time = -1 s is out of range"),
    ("optimize-out-directory", ["optimize", "--gait", "C", "--out", "{here}/adir"], 1, "is a directory"),
    ("optimize-out-empty", ["optimize", "--gait", "C", "--out", ""], 1, "path is empty"),
    ("optimize-out-device", ["optimize", "--gait", "C", "--out", "/dev/null"], 1, "is a character device"),
    # --- bench
    ("bench-duration-zero", ["bench", "--duration", "0"], 2, "--duration = 0 s is out of range (allowed: (0, 60] s"),
    ("bench-duration-long", ["bench", "--duration", "100"], 2, "--duration = 100 s is out of range"),
    ("bench-duration-not-whole", ["bench", "--duration", "0.0105"], 1, "is not a whole number of steps"),
    ("bench-json-directory", ["bench", "--json", "{here}/adir"], 1, "is a directory"),
    ("bench-json-empty", ["bench", "--json", ""], 1, "--json path is empty"),
    ("bench-json-proc", ["bench", "--json", "/proc/bench.json"], 1, "cannot write in output directory /proc"),
    # --- figures (refused before any simulation)
    ("figures-members-zero", ["figures", "--members", "0"], 2, "--members = 0 is out of range (allowed: an integer [1, 256]"),
    ("figures-members-abc", ["figures", "--members", "abc"], 2, "--members = 'abc' is not an integer"),
    ("figures-members-float", ["figures", "--members", "2.5"], 2, "--members = '2.5' is not an integer"),
    ("figures-check-without-claims", ["figures", "--check", "--out", "{here}/adir"], 2,
     "--check compares with the committed claims report, but"),
    # --- render (the shared output check)
    ("render-out-directory", ["render", "{in}/straight.npz", "--out", "{here}/adir.gif"], 1, "is a directory"),
]


@pytest.fixture
def here(tmp_path, monkeypatch):
    """An empty working directory with a directory, a link to it and a link loop in it."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "adir").mkdir()
    (tmp_path / "adir.gif").mkdir()
    os.symlink(tmp_path / "adir", tmp_path / "dirlink")
    os.symlink(tmp_path / "loop", tmp_path / "loop")
    return tmp_path


def _listing(d):
    """Every file and directory under d (hidden ones too), relative to d."""
    return sorted(str(p.relative_to(d)) for p in d.rglob("*"))


def run_main(argv, capsys):
    """(exit status, message: the SystemExit's text and stderr) of ``main(argv)`` in this process."""
    try:
        code = main(argv)
    except SystemExit as exc:
        code = exc.code
    captured = capsys.readouterr()
    if isinstance(code, str):  # SystemExit("error: ..."): Python prints it and exits with 1
        return 1, code + "\n" + captured.err
    return code, captured.err


@pytest.mark.parametrize("case", REFUSED, ids=[c[0] for c in REFUSED])
def test_bad_input_is_refused_with_a_message_and_leaves_nothing(case, here, inputs, capsys):
    name, argv, status, message = case
    argv = [a.replace("{in}", str(inputs)).replace("{here}", str(here)) for a in argv]
    before = _listing(here)
    code, said = run_main(argv, capsys)
    assert code == status, f"{name}: exit {code}, expected {status}: {said}"
    assert message in said, f"{name}: {message!r} not in {said!r}"
    assert "Traceback" not in said
    assert _listing(here) == before, "bad input must leave nothing behind"
    assert "/dev/null" not in argv or os.path.exists("/dev/null") and not os.path.isfile("/dev/null")


# ------------------------------------------------------------------------------ runs that must start

def test_out_without_npz_suffix_is_written_under_exactly_that_name(here, capsys):
    code, said = run_main(["simulate", "--out", "run", *TINY], capsys)
    assert code == 0 and "exact name 'run'" in said
    assert _listing(here) == sorted(["adir", "adir.gif", "dirlink", "loop", "run"])
    with np.load(here / "run") as z:
        assert len(z["t"]) == 11 and z["q"].shape == (11, 25)


def test_out_through_a_symlink_writes_the_target_and_keeps_the_link(here, capsys):
    os.symlink("target.npz", here / "link.npz")  # dangling: the target is created
    assert run_main(["simulate", "--out", "link.npz", *TINY], capsys)[0] == 0
    assert os.path.islink(here / "link.npz") and os.readlink(here / "link.npz") == "target.npz"
    with np.load(here / "target.npz") as z:
        assert len(z["t"]) == 11


def test_export_mjcf_onto_a_symlink_writes_its_target_and_keeps_the_link(here, capsys):
    target = here / "adir" / "cobra.xml"
    target.write_text("old")
    os.symlink(target, here / "link.xml")
    assert run_main(["export-mjcf", str(here / "link.xml")], capsys)[0] == 0
    assert os.path.islink(here / "link.xml") and os.readlink(here / "link.xml") == str(target)
    assert target.read_text().startswith("<mujoco")
    assert sorted(os.listdir(here / "adir")) == ["cobra.xml"], "no temporary file left"


def test_export_mjcf_onto_a_character_device_refuses_without_writing_it(here, capsys):
    import stat

    before = os.stat("/dev/null")
    code, said = run_main(["export-mjcf", "/dev/null"], capsys)
    assert code == 1 and "character device" in said
    after = os.stat("/dev/null")
    assert stat.S_ISCHR(after.st_mode) and (after.st_ino, after.st_rdev) == (before.st_ino, before.st_rdev)
    # a link to the device is refused too, and stays a link
    os.symlink("/dev/null", here / "null.xml")
    code, said = run_main(["export-mjcf", str(here / "null.xml")], capsys)
    assert code == 1 and "the target of the link" in said and os.path.islink(here / "null.xml")


def test_a_straight_start_puts_the_box_beside_the_robot_and_runs(here, inputs, capsys):
    code, said = run_main(["simulate", "--reference", str(inputs / "straight.npz"), "--out", "s.npz", *TINY], capsys)
    assert code == 0, said
    with np.load(here / "s.npz") as z:
        assert float(z["max_penetration"].max()) < 1e-3


def test_fast_reference_warns_about_the_speed_limit_and_runs(here, inputs, capsys):
    code, said = run_main(["simulate", "--reference", str(inputs / "fast.npz"), "--out", "f.npz", *TINY], capsys)
    assert code == 0
    assert "warning:" in said and "joint J2 moves faster than" in said and "qd_max = 3.77 rad/s" in said and "A6" in said


def test_every_knob_is_recorded_in_the_npz_meta(here, capsys):
    argv = ["simulate", "--mu", "0.8", "--mu-robot-box", "0.4", "--box-mass", "0.7", "--box-offset=0.0,0.3",
            "--box-yaw", "0.2", "--param", "amplitude=0.4", "--param", "frequency=0.6", "--out", "k.npz", *TINY]
    code, said = run_main(argv, capsys)
    assert code == 0, said
    with np.load(here / "k.npz") as z:
        meta = json.loads(str(z["meta"]))
        box = z["box_pose"][0]
    options = meta["options"]
    assert (options["mu"], options["mu_robot_box"], options["box_mass"]) == (0.8, 0.4, 0.7)
    assert options["box_offset"] == [0.0, 0.3] and options["box_yaw"] == 0.2
    assert options["param"] == {"amplitude": 0.4, "frequency": 0.6} and options["duration"] == 0.01
    assert meta["gait_params"]["amplitude"] == 0.4 and meta["cobra_parameters"]["box_mass"] == 0.7
    assert (meta["mu"], meta["mu_robot_box"]) == (0.8, 0.4)
    assert 2 * np.arctan2(box[6], box[3]) == pytest.approx(0.2, abs=1e-3)  # settled: nearly the yaw asked


def test_params_replay_of_a_good_file_runs(here, inputs, capsys):
    code, said = run_main(["simulate", "--params", str(inputs / "good.json"), "--out", "p.npz", *TINY], capsys)
    assert code == 0, said
    assert (here / "p.npz").exists()


@pytest.fixture(scope="module")
def settled():
    """The settled start of the default run (computed before a test breaks the stepper)."""
    from cobra_ref.start import initial_state

    return initial_state(cobra_model(), gait("C"), StepSettings())


def _break_the_stepper_at(t_break, exception, monkeypatch, settled):
    from cobra_ref.fast.stepper import FastStepper

    real = FastStepper.step

    def breaks(self, q, qd, t, reference, tau_ext=None):
        if t >= t_break - 1e-12:
            raise exception
        return real(self, q, qd, t, reference, tau_ext)

    monkeypatch.setattr("cobra_ref.cli.simulate._start", lambda *args: settled)
    monkeypatch.setattr(FastStepper, "step", breaks)


def test_a_failure_mid_run_keeps_what_was_computed_for_any_exception(here, capsys, monkeypatch, settled):
    """An unexpected exception inside the step loop (here a RuntimeError at step 5): the command
    exits 1 naming the step and time, and OUT.failed.npz holds the 5 steps before it."""
    _break_the_stepper_at(0.005, RuntimeError("solver exploded"), monkeypatch, settled)
    code, said = run_main(["simulate", "--out", "run.npz", *TINY], capsys)
    assert code == 1 and "step failed at step 5, t = 0.0050 s: RuntimeError: solver exploded" in said
    assert "run.failed.npz" in said and "Traceback" not in said
    assert not (here / "run.npz").exists()
    with np.load(here / "run.failed.npz") as z:
        assert len(z["tau"]) == 5 and "RuntimeError" in str(z["error"])
        assert json.loads(str(z["meta"]))["options"]["duration"] == 0.01


def test_ctrl_c_mid_run_keeps_what_was_computed(here, capsys, monkeypatch, settled):
    _break_the_stepper_at(0.003, KeyboardInterrupt(), monkeypatch, settled)
    code, said = run_main(["simulate", "--out", "run", *TINY], capsys)
    assert code == 130 and "interrupted" in said and "run.failed.npz" in said
    with np.load(here / "run.failed.npz") as z:
        assert len(z["tau"]) == 3


# -------------------------------------------------------------------------- through a real process

SUBPROCESS = [
    (["simulate", "--dt", "0.1"], "--dt = 0.1 s is out of range"),
    (["simulate", "--out", "adir", "--duration", "0.01"], "is a directory"),
    (["export-mjcf", "/dev/null"], "is a character device"),
    (["simulate", "--reference", "{in}/ten.npz"], "joint J3 = 10 rad"),
    (["simulate", "--params", "{in}/nan_mu.json"], "mu = nan is not finite"),
    (["simulate", "--duration", "1", "--dt", "0.003"], "not a whole number of steps"),
]


@pytest.mark.parametrize("argv, message", SUBPROCESS, ids=[" ".join(a[:3]) for a, _ in SUBPROCESS])
def test_no_traceback_reaches_the_terminal(argv, message, here, inputs):
    argv = [a.replace("{in}", str(inputs)) for a in argv]
    before = _listing(here)
    p = subprocess.run([sys.executable, "-m", "cobra_ref", *argv], capture_output=True, text=True, cwd=here)
    assert p.returncode in (1, 2) and message in p.stderr and "Traceback" not in p.stderr
    assert p.stderr.strip().splitlines()[-1].startswith(("error:", "cobra-ref"))
    assert _listing(here) == before


# --------------------------------------------------------------------------------------------- API

@pytest.mark.parametrize("kwargs, message", [
    (dict(margin=-1.0), "margin = -1 m is out of range (allowed: [0, 1] m)"),
    (dict(margin=float("nan")), "margin = nan is not finite"),
    (dict(dt=float("nan")), "dt = nan is not finite"),
    (dict(dt=0.1), "dt = 0.1 s is out of range"),
    (dict(contact="soft"), "contact must be one of compliant, rigid; got contact = 'soft'"),
    (dict(servo=3), "servo must be one of position, prescribed"),
])
def test_step_settings_refuse_bad_values(kwargs, message):
    with pytest.raises(ValidationError) as err:
        StepSettings(**kwargs)
    assert message in str(err.value)


def test_step_settings_refuse_a_dt_that_is_not_a_number():
    # a string is the wrong type, not a wrong value: a TypeError (infra.arguments), as every door says
    with pytest.raises(TypeError, match="dt = '1e-3' is not a number"):
        StepSettings(dt="1e-3")


@pytest.mark.parametrize("kwargs, message", [
    (dict(box_size=-0.1), "box_size = -0.1 m is out of range (allowed: [0.001, 2] m)"),
    (dict(gravity=float("nan")), "gravity = nan is not finite"),
    (dict(mu="abc"), "mu = 'abc' is not a number"),
    (dict(mu=True), "mu = True is not a number"),
    (dict(mu_robot_box=-1), "mu_robot_box = -1 is out of range"),
    (dict(box_mass=0.0), "box_mass = 0 kg is out of range"),
    (dict(tau_max=0.0), "tau_max = 0 N m is out of range"),
    (dict(q_max=4.0), "q_max = 4 rad is out of range (allowed: (0, pi] rad)"),
    (dict(n_body_links=2.5), "n_body_links = 2.5 is not an integer"),
    (dict(inertia_link=(1e-3, 1e-3, 3e-3)), "triangle inequality"),
    (dict(inertia_link=(1e-3, -1e-3, 1e-3)), "inertia_link[1] = -0.001 kg m^2 is out of range"),
    (dict(inertia_head="big"), "expected three numbers"),
    (dict(stiction_velocity=0.0), "stiction_velocity = 0 m/s is out of range"),
    (dict(contact_damping=float("inf")), "contact_damping = inf is not finite"),
])
def test_cobra_parameters_refuse_bad_values(kwargs, message):
    with pytest.raises(ValidationError) as err:
        CobraParameters(**kwargs)
    assert message in str(err.value)
    import dataclasses

    with pytest.raises(ValidationError):  # dataclasses.replace checks too
        dataclasses.replace(CobraParameters(), **kwargs)


def test_good_parameters_build_the_model():
    params = CobraParameters(mu=0.8, mu_robot_box=0.4, box_mass=0.7, inertia_link=[7.167e-4, 8.704e-4, 8.626e-4])
    model = cobra_model(params)
    assert model.mu == 0.8 and model.mass[-1] == 0.7


def test_mjcf_refuses_a_bad_timestep():
    from cobra_ref.mjcf import to_mjcf

    for bad in (float("nan"), -1.0, 0.01):
        with pytest.raises(ValidationError, match="timestep"):
            to_mjcf(cobra_model(), timestep=bad)


@pytest.mark.parametrize("duration, dt, exact, result", [
    (1.0, 1e-3, True, 1000),
    (0.3, 1e-3, True, 300),
    (2.0 / 0.3, 1e-3, False, 6667),  # the API rounds
    (1.0, 3e-3, True, "not a whole number of steps"),
    (1e-4, 1e-3, False, "shorter than one step"),
    (1e4, 1e-3, False, "at most 1000000 steps"),
    (float("inf"), 1e-3, False, "must be positive and finite"),
    (-1.0, 1e-3, False, "must be positive and finite"),
    ("1", 1e-3, False, "is not a number"),
    (1.0, 0.0, False, "dt = 0 s is out of range"),
])
def test_time_grid(duration, dt, exact, result):
    if isinstance(result, int):
        assert time_grid(duration, dt, exact) == result
    else:
        with pytest.raises(ValidationError, match=result):
            time_grid(duration, dt, exact)


def test_simulate_refuses_a_huge_grid_before_allocating():
    with pytest.raises(ArgumentError, match="at most 1000000 steps"):
        simulate(cobra_model(), gait("C"), 1e9)
    with pytest.raises(ArgumentError, match="shorter than one step"):
        simulate(cobra_model(), gait("C"), 1e-4)


def test_simulate_turns_any_step_exception_into_a_failure_that_keeps_the_run():
    from cobra_ref.start import placed_state

    model, rolling = cobra_model(), gait("C")

    def breaks(t):
        if t > 0.0035:
            raise KeyError("lookup table")
        return rolling(t)

    q0 = placed_state(model, rolling)
    with pytest.raises(SimulationError, match=r"step failed at step 3, t = 0\.0030 s: KeyError") as err:
        simulate(model, breaks, 0.01, q0=q0, qd0=np.zeros(model.nv))
    assert len(err.value.trajectory.tau) == 3 and isinstance(err.value.__cause__, KeyError)


def test_straight_start_box_beside_the_middle_on_the_left_and_box_yaw():
    from cobra_ref.contact import find_contacts
    from cobra_ref.start import BoxPlacement, placed_state

    model = cobra_model()
    straight = lambda t: (np.zeros(11), np.zeros(11), np.zeros(11))  # noqa: E731
    q = placed_state(model, straight)
    box = q[model.q_idx[model.boxes[0].body]]
    # the head faces +x, so the left is +y: the box centre is r + a/2 + gap to the left of the middle
    assert box[1] == pytest.approx(0.0535 + 0.05 + 0.05) and box[1] > 0
    c = find_contacts(model, q, 0.0)
    assert not np.any(c.kind == 1), "the box must be clear of the robot"
    # nearly straight (a C of 1 mrad) too; a real C keeps its concave side
    q = placed_state(model, gait("C", amplitude=1e-3))
    assert q[model.q_idx[model.boxes[0].body]][1] > 0.15
    q = placed_state(model, straight, BoxPlacement(yaw=0.3))
    quat = q[model.q_idx[model.boxes[0].body]][3:]
    assert 2 * np.arctan2(quat[3], quat[0]) == pytest.approx(0.3)


def test_check_reference_warns_for_speed_and_refuses_angles():
    from cobra_ref.reference import ReferenceError, SplineReference, check_reference

    assert check_reference(gait("C"), 1.0) == []
    warnings = check_reference(gait("C", amplitude=0.75, frequency=1.0), 3.0)
    assert len(warnings) == 1 and "joints J0, J1" in warnings[0] and "speed limit qd_max = 3.77 rad/s" in warnings[0]
    t = np.linspace(0, 1, 5)
    with pytest.raises(ReferenceError, match=r"joint J0 = 2 rad at t = 0.5 s"):
        SplineReference(t, np.outer(np.array([0, 0, 2, 0, 0]), np.eye(11)[0]))


# ------------------------------------------------------------------------------------- the writer

def test_atomic_write_refuses_non_regular_targets_and_leaves_nothing(tmp_path):
    (tmp_path / "d").mkdir()
    for target, message in [(tmp_path / "d", "is a directory"), ("/dev/null", "character device"),
                            ("", "empty"), (tmp_path / "no" / "x", "does not exist")]:
        with pytest.raises(OutputError, match=message):
            write_text(str(target), "x")
    assert sorted(os.listdir(tmp_path)) == ["d"] and os.listdir(tmp_path / "d") == []


def test_a_writer_that_renames_its_file_cannot_lose_data(tmp_path):
    """np.save appends .npy to a name without it: nothing is replaced, nothing stray is left."""
    with pytest.raises(OutputError, match="did not write the file under its name"):
        atomic_write(str(tmp_path / "cache"), lambda tmp: np.save(tmp, np.zeros(3)))
    assert os.listdir(tmp_path) == []
    write_binary(str(tmp_path / "cache"), lambda f: np.save(f, np.arange(3)))
    assert np.load(tmp_path / "cache").tolist() == [0, 1, 2] and os.listdir(tmp_path) == ["cache"]


def test_a_failing_writer_leaves_the_old_file_and_no_temporary(tmp_path):
    path = tmp_path / "out.txt"
    path.write_text("old")

    def fails(tmp):
        with open(tmp, "w") as f:
            f.write("half")
        raise RuntimeError("disk full")

    with pytest.raises(RuntimeError, match="disk full"):
        atomic_write(str(path), fails)
    assert path.read_text() == "old" and os.listdir(tmp_path) == ["out.txt"]


def test_check_output_probes_the_directory_for_real(tmp_path, monkeypatch):
    import tempfile

    assert check_output(str(tmp_path / "x.npz")) == str(tmp_path / "x.npz") and os.listdir(tmp_path) == []

    def refuse(*args, **kwargs):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(tempfile, "mkstemp", refuse)
    with pytest.raises(OutputError, match=f"cannot write in output directory {tmp_path}.*Permission denied"):
        check_output(str(tmp_path / "x.npz"))


def test_trajectory_to_npz_keeps_the_exact_name(tmp_path):
    traj = simulate(cobra_model(), gait("C"), 0.002)
    traj.to_npz(str(tmp_path / "run"))
    assert os.listdir(tmp_path) == ["run"]
    from cobra_ref.trajectory import Trajectory

    assert len(Trajectory.from_npz(str(tmp_path / "run")).t) == 3


# ---------------------------------------------------------------------------- docs/cli.md's tables

def test_docs_cli_md_is_the_generated_one():
    with open(os.path.join(ROOT, CLI_DOC), encoding="utf-8") as f:
        committed = f.read()
    assert committed == cli_markdown(), "docs/cli.md is stale: run `python -m cobra_ref.cli.options_doc`"


def test_the_readme_links_the_option_tables_instead_of_holding_them():
    with open(os.path.join(ROOT, "README.md"), encoding="utf-8") as f:
        readme = f.read()
    assert "(docs/cli.md)" in readme and "| `--dt` |" not in readme


def test_the_option_table_names_every_option_with_unit_and_range():
    table = options_markdown()
    for row in ("| `--dt` | s | [1e-5, 0.005] | 0.001 |", "| `--mu` | - | [0, 2] | 1.0 |",
                "| `--box-mass` | kg | [0.001, 100] | 0.5 |", "| `--timestep` | s | [1e-6, 0.002] | 5e-5 |",
                "| `--box-offset` | m | DX,DY: each [-5, 5] | - |"):
        assert row in table, row
