"""A full disk: every writer and every command that writes ends in one line naming the file and the
cause, leaves no temporary file and the previous file as it was; an optimization keeps its rollouts.

The disk is filled by injection (``full_disk``): a file opened for writing under the "disk"
directory is created, but its first write fails with ENOSPC (errno 28, "No space left on device"),
as on a filled file system, where an empty file can still be made. Writing through
``builtins.open`` reaches every writer here: ``open`` in cobra_ref, Pillow's ``Image.save``,
matplotlib's ``savefig`` to a path.
"""

import builtins
import errno
import io
import json
import os
import tempfile

import numpy as np
import pytest

from cobra_ref.cli import main
from cobra_ref.infra.output import OutputError, write_text
from cobra_ref.planning import search
from cobra_ref.planning.results import load_result

def one_by_one(evaluate):
    """A made-up ``evaluate(problem, x)`` as the search's ``evaluate_batch(problem, xs)``."""
    return lambda problem, xs: [evaluate(problem, x) for x in xs]


NO_SPACE = os.strerror(errno.ENOSPC)
PREVIOUS = "the previous content\n"


class _FullFile(io.FileIO):
    """A file on a full disk: it opens, every write fails."""

    def write(self, data):
        raise OSError(errno.ENOSPC, NO_SPACE)


@pytest.fixture
def full_disk(monkeypatch):
    """``fill(directory, writes_left=0)``: from now on, files opened for writing under
    ``directory`` fail at their first write, after ``writes_left`` more opens that succeed."""
    real_open, disks = builtins.open, []

    def on_disk(file):
        if not isinstance(file, (str, os.PathLike)):
            return None
        where = os.path.abspath(os.fspath(file))
        return next((d for d in disks if where.startswith(d["root"] + os.sep)), None)

    def fake_open(file, mode="r", buffering=-1, encoding=None, errors=None, newline=None, closefd=True, opener=None):
        disk = on_disk(file) if any(c in mode for c in "wax+") else None
        if disk is None or disk["left"] > 0:
            if disk is not None:
                disk["left"] -= 1
            return real_open(file, mode, buffering, encoding, errors, newline, closefd, opener)
        raw = _FullFile(file, next(c for c in mode if c in "wax") + ("+" if "+" in mode else ""))
        if "b" in mode:
            return io.BufferedRandom(raw) if "+" in mode else io.BufferedWriter(raw)
        return io.TextIOWrapper(io.BufferedWriter(raw), encoding=encoding or "utf-8", errors=errors, newline=newline)

    def fill(directory, writes_left=0):
        disks.append({"root": os.path.abspath(directory), "left": writes_left})

    monkeypatch.setattr(builtins, "open", fake_open)
    return fill


def test_the_injected_full_disk_fails_like_a_real_one(tmp_path, full_disk):
    full_disk(tmp_path)
    with pytest.raises(OSError) as info:
        with open(tmp_path / "x.txt", "w") as f:
            f.write("hello")
    assert info.value.errno == errno.ENOSPC
    assert (tmp_path / "x.txt").read_bytes() == b""  # created, nothing in it (reading still works)


def leftovers(directory) -> list:
    """The temporary directories and files of the atomic writes left under ``directory``."""
    return sorted(os.path.relpath(os.path.join(d, n), directory) for d, dirs, files in os.walk(directory)
                  for n in dirs + files if n.startswith((".tmp_", ".cobra_ref_probe_")))


# ------------------------------------------------------------------------------ the writers

def _npz(path):
    from cobra_ref.trajectory import Trajectory

    Trajectory(dt=0.001, t=np.zeros(1), q=np.zeros((1, 25)), qd=np.zeros((1, 23)), tau=np.zeros((0, 11)),
               box_pose=np.zeros((1, 7)), steps={}, contacts={}).to_npz(path)


def _png(path):
    from cobra_ref.viz.encode import write_png

    write_png(path, np.zeros((8, 8, 3), np.uint8))


def _gif(path):
    from cobra_ref.viz.encode import write_gif

    write_gif(path, (np.full((8, 8, 3), k, np.uint8) for k in (0, 255)), 2, 10.0)


def _figure(path):
    from cobra_ref.reproduce.figures import common

    fig = common.new_figure(2.0, 2.0)
    fig.add_subplot().plot([0, 1], [0, 1])
    common.save(fig, os.path.dirname(path), os.path.splitext(os.path.basename(path))[0])


# each writer, the file it writes in the directory it is given
WRITERS = {
    "text (MJCF, JSON, claims)": (lambda path: write_text(path, "<mujoco/>\n"), "cobra.xml"),
    "NPZ of a run": (_npz, "run.npz"),
    "PNG still": (_png, "still.png"),
    "GIF": (_gif, "anim.gif"),
    "figure (PNG + PDF)": (_figure, "fig.png"),
}


@pytest.mark.parametrize("name", WRITERS)
def test_each_writer_on_a_full_disk_names_the_file_and_keeps_the_previous_one(name, tmp_path, full_disk):
    write, filename = WRITERS[name]
    target = tmp_path / filename
    target.write_text(PREVIOUS)
    full_disk(tmp_path)
    with pytest.raises(OutputError) as info:
        write(str(target))
    message = str(info.value)  # "cannot write <what> '<target>': No space left on device; ..."
    assert message.startswith("cannot write ")
    assert message.endswith(f" {str(target)!r}: {NO_SPACE}; its previous content is unchanged")
    assert target.read_text() == PREVIOUS
    assert leftovers(tmp_path) == []


def test_the_figure_cache_names_its_file_when_its_directory_cannot_be_made(tmp_path, monkeypatch):
    from cobra_ref.reproduce import runs

    def no_space(path, exist_ok=False):
        raise OSError(errno.ENOSPC, NO_SPACE)

    monkeypatch.setattr(runs.os, "makedirs", no_space)
    spec = runs.RunSpec("C", duration=0.1)
    with pytest.raises(OutputError, match=f"cannot write cache entry .*{spec.filename()}.*: {NO_SPACE}"):
        runs.store(spec, str(tmp_path / "cache"), None, failed=False)


# ------------------------------------------------------------------------------ the commands

def run_cli(argv, capsys):
    """(exit status, the error line or None, stderr) of ``cobra-ref ARGV`` run here: a
    ``SystemExit`` with a message exits with status 1 after printing it (Python's rule)."""
    try:
        code, line = main(argv), None
    except SystemExit as exc:
        code, line = (1, exc.code) if isinstance(exc.code, str) else (exc.code, None)
    return code, line, capsys.readouterr().err


@pytest.fixture(scope="module")
def run_npz(tmp_path_factory):
    """A 0.1 s run of the C gait, for render."""
    path = str(tmp_path_factory.mktemp("run") / "run.npz")
    assert main(["simulate", "--duration", "0.1", "--dt", "0.002", "--out", path, "--quiet"]) == 0
    return path


def made_up_rollout(problem, x):
    """A rollout without a simulation: its cost falls towards amplitude 0.5, frequency 0.8."""
    x = np.asarray(x, dtype=float)
    return {"params": dict(zip(problem.names, map(float, x))), "error": None,
            "cost": 1.0 + float(np.sum((x - (0.5, 0.8)) ** 2)), "box_distance_to_goal": 0.01,
            "terms": {"effort": 0.1, "goal": 0.9}, "contact": None}


OPTIMIZE = ["optimize", "--gait", "C", "--goal", "0.03,0", "--duration", "0.1", "--dt", "0.002", "--maxiter", "2",
            "--workers", "1", "--no-companion", "--quiet"]

# command line ({disk}: the full directory, {run}: a run to render), the file it writes
COMMANDS = {
    "simulate": (["simulate", "--duration", "0.02", "--dt", "0.002", "--quiet", "--out", "{disk}/run.npz"], "run.npz"),
    "export-mjcf": (["export-mjcf", "{disk}/cobra.xml"], "cobra.xml"),
    "bench --json": (["bench", "--duration", "0.02", "--no-mujoco", "--quiet", "--json", "{disk}/bench.json"],
                     "bench.json"),
    "sweep --json": (["sweep", "--n", "1", "--duration", "0.02", "--jobs", "1", "--quiet", "--json",
                      "{disk}/sweep.json"], "sweep.json"),
    "render GIF": (["render", "{run}", "--renderer", "matplotlib", "--width", "64", "--height", "48", "--quiet",
                    "--out", "{disk}/anim.gif"], "anim.gif"),
    "render PNG": (["render", "{run}", "--renderer", "matplotlib", "--width", "64", "--height", "48", "--quiet",
                    "--at", "0.05", "--out", "{disk}/still.png"], "still.png"),
    "optimize --out": (OPTIMIZE + ["--out", "{disk}/C.json"], "C.json"),
}


@pytest.mark.parametrize("name", COMMANDS)
def test_each_command_on_a_full_disk_fails_in_one_line_and_keeps_the_previous_file(
        name, tmp_path, full_disk, run_npz, capsys, monkeypatch):
    argv, filename = COMMANDS[name]
    disk, elsewhere = tmp_path / "disk", tmp_path / "elsewhere"
    disk.mkdir()
    elsewhere.mkdir()
    target = disk / filename
    target.write_text(PREVIOUS)
    monkeypatch.setattr(search, "evaluate_batch", one_by_one(made_up_rollout))
    monkeypatch.setattr(tempfile, "tempdir", str(elsewhere))  # where optimize keeps what OUT cannot take
    full_disk(disk)
    code, line, err = run_cli([a.format(disk=disk, run=run_npz) for a in argv], capsys)
    assert code == 1
    assert line.startswith(f"error: cannot write ") and "\n" not in line, line
    assert f"{str(target)!r}: {NO_SPACE}; its previous content is unchanged" in line
    assert "Traceback" not in err
    assert target.read_text() == PREVIOUS
    assert leftovers(tmp_path) == []


def test_figures_on_a_full_disk_names_the_cache_entry_it_could_not_write(tmp_path, full_disk, run_npz, capsys,
                                                                          monkeypatch):
    from cobra_ref.reproduce import runs
    from cobra_ref.trajectory import Trajectory

    # the figures' runs without their simulations: each is the short run of run_npz
    monkeypatch.setattr(runs, "simulate_specs", lambda specs, progress=None: [
        (Trajectory.from_npz(run_npz), False) for _ in specs])
    out = tmp_path / "figures"
    full_disk(tmp_path)
    code, line, err = run_cli(["figures", "--quick", "--gaits", "C", "--no-mujoco", "--jobs", "1", "--quiet",
                               "--out", str(out)], capsys)
    cache = out / ".cache"
    assert code == 1 and "\n" not in line and "Traceback" not in err
    assert line.startswith(f"error: cannot write NPZ '{cache}{os.sep}C-") and f".npz': {NO_SPACE}; " in line
    assert line.endswith(f"the runs finished before are kept in the cache {cache} (the next run reads them)")
    assert leftovers(tmp_path) == []


# ------------------------------------------------------------------------------ optimize keeps its rollouts

def optimize_on(tmp_path, full_disk, capsys, monkeypatch, writes_left: int, fallback_full: bool = False):
    """Run the made-up optimization into DISK/C.json, the disk full after ``writes_left`` writes;
    return (exit status, error line, stderr, target, fallback directory)."""
    disk, elsewhere = tmp_path / "disk", tmp_path / "elsewhere"
    disk.mkdir()
    elsewhere.mkdir()
    monkeypatch.setattr(search, "evaluate_batch", one_by_one(made_up_rollout))
    monkeypatch.setattr(tempfile, "tempdir", str(elsewhere))
    full_disk(disk, writes_left)
    if fallback_full:
        full_disk(elsewhere)
    code, line, err = run_cli(OPTIMIZE + ["--out", str(disk / "C.json")], capsys)
    return code, line, err, disk / "C.json", elsewhere


def test_optimize_checkpoints_as_it_goes_and_keeps_the_whole_result_in_a_named_fallback(
        tmp_path, full_disk, capsys, monkeypatch):
    # 3 batches: x0, a poll of 4 points, a poll of 3 new points (the fourth is x0): 8 rollouts; the first
    # checkpoint is written, then the disk is full
    code, line, err, target, elsewhere = optimize_on(tmp_path, full_disk, capsys, monkeypatch, writes_left=1)
    (fallback,) = elsewhere.iterdir()
    assert code == 1 and "Traceback" not in err and "\n" not in line
    assert line == (f"error: cannot write params JSON {str(target)!r}: {NO_SPACE}; its previous content is "
                    f"unchanged; the result (8 rollouts) is kept in {fallback}")
    # the summary is printed before the final write, a failing checkpoint is said once
    assert "C: 8 rollouts in" in err and "optimum: amplitude = " in err
    assert err.count("warning: checkpoint not written: cannot write params JSON") == 1
    # the target holds the first checkpoint: x0's rollout, marked as a checkpoint, readable by simulate --params
    checkpoint = json.loads(target.read_text())
    assert checkpoint["checkpoint"] is True and len(checkpoint["history"]) == 1
    assert load_result(str(target))["params"]["amplitude"] == checkpoint["history"][0]["params"]["amplitude"]
    # the fallback holds every rollout and the best of them as the optimum
    final = json.loads(fallback.read_text())
    best = min(final["history"], key=lambda e: e["cost"])
    assert "checkpoint" not in final and len(final["history"]) == 8
    assert final["cost"] == best["cost"] < final["history"][0]["cost"]
    assert {n: final["params"][n] for n in best["params"]} == best["params"]
    assert leftovers(tmp_path) == []


def test_when_the_fallback_cannot_be_written_either_the_error_says_what_the_checkpoint_holds(
        tmp_path, full_disk, capsys, monkeypatch):
    code, line, err, target, elsewhere = optimize_on(tmp_path, full_disk, capsys, monkeypatch, writes_left=2,
                                                     fallback_full=True)
    assert code == 1 and "Traceback" not in err
    assert line.endswith(f"; {target} holds the checkpoint after 5 of the 8 rollouts")
    checkpoint = json.loads(target.read_text())
    best = min(checkpoint["history"], key=lambda e: e["cost"])
    assert len(checkpoint["history"]) == 5 and checkpoint["cost"] == best["cost"]
    assert leftovers(tmp_path) == []


def test_optimize_with_room_ends_with_the_result_and_no_checkpoint_mark(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(search, "evaluate_batch", one_by_one(made_up_rollout))
    target = tmp_path / "C.json"
    code, line, err = run_cli(OPTIMIZE + ["--out", str(target)], capsys)
    record = json.loads(target.read_text())
    assert code == 0 and line is None and "warning" not in err
    assert "checkpoint" not in record and len(record["history"]) == 8


def test_the_optimizations_of_figures_reoptimize_keep_their_rollouts_the_same_way(tmp_path, full_disk, monkeypatch):
    from cobra_ref.planning import SerialExecutor, optimize_gait
    from cobra_ref.step import StepSettings

    monkeypatch.setattr(search, "evaluate_batch", one_by_one(made_up_rollout))
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    target, lines = tmp_path / "optimized" / "C.json", []
    full_disk(target.parent, writes_left=1)
    with pytest.raises(OutputError) as info:
        optimize_gait("C", goal=(0.03, 0.0), out=str(target), executor=SerialExecutor(), progress=lines.append,
                      check_dt=None, search=search.SearchOptions(maxiter=2, companion=False), duration=0.1,
                      settings=StepSettings(dt=0.002))
    (fallback,) = tmp_path.glob("cobra-ref-C-*.json")
    assert str(info.value).endswith(f"; the result (8 rollouts) is kept in {fallback}")
    assert json.loads(target.read_text())["checkpoint"] is True
    assert len(json.loads(fallback.read_text())["history"]) == 8
    assert sum(line.startswith("warning: checkpoint not written") for line in lines) == 1


def test_a_writer_that_fails_with_a_long_message_is_reported_by_its_first_line(tmp_path):
    from cobra_ref.infra.output import atomic_write

    def ffmpeg_like(tmp):  # imageio-ffmpeg reports a broken pipe to ffmpeg as one OSError over many lines
        raise OSError("[Errno 32] Broken pipe\n\nFFMPEG COMMAND:\nffmpeg -y ...\n\nFFMPEG STDERR OUTPUT:\n")

    with pytest.raises(OutputError) as info:
        atomic_write(tmp_path / "run.mp4", ffmpeg_like)
    target = str(tmp_path / "run.mp4")
    assert str(info.value) == f"cannot write output {target!r}: [Errno 32] Broken pipe; nothing was written"
    assert leftovers(tmp_path) == []


def test_a_gif_the_disk_cannot_take_is_not_drawn_again_with_the_other_renderer(tmp_path, monkeypatch):
    from cobra_ref.reproduce.figures import animate

    target, drawn = str(tmp_path / "anim_C.gif"), []

    def mujoco_gif(gait, traj, path):
        raise OutputError(f"cannot write output {path!r}: {NO_SPACE}; nothing was written")

    monkeypatch.setattr(animate, "mujoco_gif", mujoco_gif)
    monkeypatch.setattr(animate, "matplotlib_gif", lambda *args: drawn.append(args))
    with pytest.raises(OutputError, match=NO_SPACE):
        animate.animate_one(None, "C", None, target, problem=None)
    assert drawn == []
