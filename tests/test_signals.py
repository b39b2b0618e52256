"""SIGTERM and Ctrl-C stop a long command cleanly, as a batch scheduler or a person at a terminal would.

Each row starts a real ``python -m cobra_ref`` process in a session of its own, waits for its first
progress line on stderr (the work has started, and for optimize and figures the worker processes
too), then sends the signal: SIGTERM to the command's process (``kill PID``, ``docker stop``) or
to its whole process group (``timeout``), SIGINT to the group (Ctrl-C at a terminal) or to the
process alone. Every row asserts what an operator relies on: the exit status (143 after SIGTERM,
130 after Ctrl-C), one last stderr line that says what was kept, no traceback, no process of the
session left within 10 s (workers, the figures' queue server), and that what was kept is readable.
"""

import glob
import json
import os
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

from cobra_ref.cli import main
from cobra_ref.infra.signals import Terminated, exit_status, received, signal_name, stop_signals

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def simulate(tmp):
    return ["simulate", "--duration", "4", "--dt", "0.002", "--out", str(tmp / "run.npz")]


def optimize(tmp):
    return ["optimize", "--gait", "C", "--goal", "0.05,-0.01", "--duration", "0.3", "--ramp-time", "0.1",
            "--box-gap", "0.005", "--maxiter", "40", "--workers", "2", "--out", str(tmp / "p.json")]


def figures(tmp):
    return ["figures", "--quick", "--gaits", "C,S,J", "--jobs", "2", "--out", str(tmp / "fig"),
            "--cache", str(tmp / "cache")]


def simulate_kept(tmp, line):
    """The partial run, named in the line: some steps, fewer than the 2000 asked for."""
    assert "run.failed.npz" in line and not (tmp / "run.npz").exists()
    with np.load(tmp / "run.failed.npz") as run:
        assert 0 < len(run["tau"]) < 2000 and "interrupted" in str(run["error"])


def optimize_kept(tmp, line):
    """The best rollout so far, in the params JSON named in the line, flagged interrupted."""
    record = json.loads((tmp / "p.json").read_text())
    assert str(tmp / "p.json") in line and record["interrupted"] is True
    assert f"the best of {len(record['history'])} rollouts" in line and record["params"]


def figures_kept(tmp, line):
    """The finished runs, counted in the line, each a readable cache entry."""
    cached = sorted(glob.glob(str(tmp / "cache" / "*.npz")))
    assert cached and f"{len(cached)} of the 3 simulations" in line and str(tmp / "cache") in line
    for path in cached:
        with np.load(path) as run:
            assert len(run["t"]) > 1


# (command, its argv, the stderr text that shows the work has started, the check of what was kept,
#  the signal, whom it is sent to: "process" or "group", the exit status); the figures rows wait for
#  a finished 1 s run (10-20 s on a shared 2-core machine)
ROWS = [
    ("simulate", simulate, b"steps)", simulate_kept, signal.SIGTERM, "process", 143),
    ("simulate", simulate, b"steps)", simulate_kept, signal.SIGINT, "group", 130),
    ("optimize", optimize, b"iteration  0/", optimize_kept, signal.SIGTERM, "process", 143),
    ("optimize", optimize, b"iteration  0/", optimize_kept, signal.SIGTERM, "group", 143),
    ("optimize", optimize, b"iteration  0/", optimize_kept, signal.SIGINT, "group", 130),
    ("figures", figures, b"runs done: 1/", figures_kept, signal.SIGTERM, "process", 143),
    ("figures", figures, b"runs done: 1/", figures_kept, signal.SIGINT, "group", 130),
]
PARAMS = [pytest.param(*row, id=f"{row[0]}-{row[4].name}-to-{row[5]}",
                       marks=[pytest.mark.slow] if row[0] == "figures" else []) for row in ROWS]


def session(sid: int) -> list:
    """The processes of session ``sid`` still running (zombies have ended: left out)."""
    out = []
    for stat in glob.glob("/proc/[0-9]*/stat"):
        try:
            with open(stat) as f:
                fields = f.read().rsplit(")", 1)[1].split()
        except OSError:  # ended while we looked
            continue
        if int(fields[3]) == sid and fields[0] != "Z":
            out.append(int(stat.split("/")[2]))
    return out


class Reader(threading.Thread):
    """Collects a process's stderr as it comes."""

    def __init__(self, stream):
        super().__init__(daemon=True)
        self.stream, self.data = stream, b""

    def run(self):
        for chunk in iter(lambda: self.stream.read1(4096), b""):
            self.data += chunk

    def wait_for(self, text: bytes, process, timeout: float) -> None:
        deadline = time.monotonic() + timeout
        while text not in self.data:
            assert process.poll() is None, f"ended before {text!r}: {self.data.decode()[-2000:]}"
            assert time.monotonic() < deadline, f"no {text!r} within {timeout} s: {self.data.decode()[-2000:]}"
            time.sleep(0.05)


def _sigint_as_at_a_terminal():
    """In the child before it runs: SIGINT's default disposition, as a command started at a terminal
    has it (a test run started in the background inherits SIGINT ignored, which the command keeps)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def start(argv, tmp_path):
    """``python -m cobra_ref ARGV`` in a session of its own, in ``tmp_path``; (process, stderr reader)."""
    env = dict(os.environ, PYTHONPATH=REPO + os.pathsep + os.environ.get("PYTHONPATH", ""), MPLBACKEND="Agg")
    process = subprocess.Popen([sys.executable, "-m", "cobra_ref", *argv], cwd=tmp_path, env=env,
                               stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, start_new_session=True,
                               preexec_fn=_sigint_as_at_a_terminal)
    reader = Reader(process.stderr)
    reader.start()
    return process, reader


def wait_for_session_end(sid: int, seconds: float = 10.0) -> list:
    """The processes of session ``sid`` still running after at most ``seconds`` (then killed, so a
    failing test leaves nothing behind)."""
    deadline = time.monotonic() + seconds
    while session(sid) and time.monotonic() < deadline:
        time.sleep(0.1)
    left = session(sid)
    for pid in left:
        os.kill(pid, signal.SIGKILL)
    return left


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
@pytest.mark.parametrize("command, argv, started, check_kept, signum, target, status", PARAMS)
def test_a_signal_ends_the_command_its_workers_and_keeps_what_was_computed(
        tmp_path, command, argv, started, check_kept, signum, target, status):
    process, reader = start(argv(tmp_path), tmp_path)
    try:
        reader.wait_for(started, process, timeout=120)
        helpers = [pid for pid in session(process.pid) if pid != process.pid]
        assert command == "simulate" or len(helpers) >= 2, "the workers run before the signal"
        (os.kill if target == "process" else os.killpg)(process.pid, signum)
        assert process.wait(timeout=10) == status  # within seconds: the workers are not waited for
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()
    reader.join(5)
    assert wait_for_session_end(process.pid) == [], "a worker or helper process outlived the command"
    said = reader.data.decode()
    name = "SIGTERM" if signum == signal.SIGTERM else "Ctrl-C"
    last = said.rstrip("\n").split("\n")[-1]
    assert "Traceback" not in said and last.startswith(f"interrupted ({name}): "), said[-2000:]
    check_kept(tmp_path, last)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="PR_SET_PDEATHSIG is Linux's")
def test_the_workers_die_with_the_command_even_when_it_is_killed(tmp_path):
    """SIGKILL cannot be handled: the kernel ends the workers (executors.helper_init) instead."""
    process, reader = start(optimize(tmp_path), tmp_path)
    try:
        reader.wait_for(b"iteration  0/", process, timeout=120)
        workers = [pid for pid in session(process.pid) if pid != process.pid]
        assert len(workers) >= 2
        os.kill(process.pid, signal.SIGKILL)
        assert process.wait(timeout=10) == -signal.SIGKILL
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()
    assert wait_for_session_end(process.pid) == [], "a worker outlived the killed command"


# ------------------------------------------------------------------ the handler, in this process

@pytest.fixture
def sigint_as_at_a_terminal():
    """Python's own Ctrl-C handler while the test runs, as at a terminal (a test run started in the
    background inherits SIGINT ignored, which ``stop_signals`` leaves as it is); the inherited one after."""
    inherited = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, inherited)


@pytest.mark.usefixtures("sigint_as_at_a_terminal")
@pytest.mark.parametrize("signum, raised, status, name", [
    (signal.SIGTERM, Terminated, 143, "SIGTERM"),
    (signal.SIGINT, KeyboardInterrupt, 130, "Ctrl-C"),
])
def test_inside_stop_signals_a_signal_raises_once_and_names_its_exit_status(signum, raised, status, name):
    before = {s: signal.getsignal(s) for s in (signal.SIGTERM, signal.SIGINT)}
    with stop_signals():
        with pytest.raises(raised) as caught:
            signal.raise_signal(signum)
            time.sleep(5)  # not reached: the handler raises first
        signal.raise_signal(signum)  # a repeat while the first is handled: ignored
        signal.raise_signal(signal.SIGTERM)
        assert received() == signum
    assert type(caught.value) is raised and exit_status(caught.value) == status
    assert signal_name(caught.value) == name
    assert {s: signal.getsignal(s) for s in before} == before  # the library's handlers are back


def test_the_command_line_leaves_the_handlers_as_it_found_them(capsys):
    before = {s: signal.getsignal(s) for s in (signal.SIGTERM, signal.SIGINT)}
    assert main(["info"]) == 0
    assert {s: signal.getsignal(s) for s in before} == before
