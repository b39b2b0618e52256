"""What every ``cobra-ref`` subcommand shares: argument types, output checks, quiet C libraries.

Helper: conventions of the command line. Every input is checked before the long run; progress
and summaries go to stderr, stdout carries one JSON line; files are written atomically.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import sys

import numpy as np

from ..progress import progress_printer


def write_text_atomic(path: str, text: str) -> None:
    """Check the directory (a clear error), then write through a temporary file and a rename.

    Helper: shared by every cobra-ref subcommand.
    """
    from ..output import write_text

    check_writable(path)
    write_text(path, text)


@contextlib.contextmanager
def c_stdout_silenced():
    """Discard what C libraries print on file descriptor 1 while the block runs: OSQP prints
    "Polishing not needed ..." once per solve even with verbose off, thousands of lines per run.
    stdout then carries only the command's own output (its JSON line, printed after the block);
    progress goes to stderr.

    Helper: shared by every cobra-ref subcommand.
    """
    sys.stdout.flush()
    saved, devnull = os.dup(1), os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, 1)
        yield
    finally:
        sys.stdout.flush()
        os.dup2(saved, 1)
        os.close(saved)
        os.close(devnull)


def check_writable(path: str) -> None:
    """Exit with a clear error if the directory of ``path`` is missing or not writable.

    Helper: shared by every cobra-ref subcommand.
    """
    directory = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(directory):
        raise SystemExit(f"error: output directory does not exist: {directory}")
    if not os.access(directory, os.W_OK):
        raise SystemExit(f"error: output directory is not writable: {directory}")


def run_and_write(model, reference, duration, settings, out, label, quiet=False, q0=None, qd0=None,
                  meta=None, summary=None, stepper="fast"):
    """Simulate, write the NPZ and print the one-line JSON summary (plus ``summary(traj)``'s keys);
    a failure mid-run writes what was computed to OUT.failed.npz and exits with the error.

    Helper: shared by every cobra-ref subcommand.
    """
    from ..simulate import simulate
    from ..step import SimulationError

    progress = None if quiet else progress_printer(label)
    try:
        with c_stdout_silenced():
            traj = simulate(model, reference, duration, settings, q0, qd0, progress=progress, stepper=stepper)
    except SimulationError as exc:
        if exc.trajectory is None:  # bad input: nothing was computed, nothing is written
            raise SystemExit(f"error: {exc}") from None
        failed = os.path.splitext(out)[0] + ".failed.npz"
        exc.trajectory.to_npz(failed)
        print(json.dumps(exc.trajectory.summary()))
        raise SystemExit(f"error: {exc}\nwhat was computed up to the failure is in {failed}") from None
    traj.meta.update(meta or {})
    traj.to_npz(out)
    print(json.dumps({**traj.summary(), **(summary(traj) if summary else {})}))
    return traj


def finite_float(text: str) -> float:
    """argparse type: a float, rejected if not finite (the message names the value).

    Helper: shared by every cobra-ref subcommand.
    """
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not np.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be finite, got {text}")
    return value
