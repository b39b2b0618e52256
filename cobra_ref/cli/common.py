"""What every ``cobra-ref`` subcommand shares: argument types, output checks, quiet C libraries.

Conventions of the command line. Every input is checked before the long run, by the
rules of :mod:`cobra_ref.infra.validation` (an option's ``type=``, or ``fail`` with the rule's
message: exit status 2 for a malformed option, 1 for input refused after parsing, never a
traceback); every output by :func:`cobra_ref.infra.output.check_output` (exact name, regular files
only, a real write probe). Progress and summaries go to stderr, stdout carries one JSON line;
files are written atomically. A run that fails part-way keeps what was computed in
``OUT.failed.npz`` (``OUT`` without its extension), named in the error message.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import sys
import warnings
from dataclasses import dataclass

import numpy as np

from ..infra.output import OutputError, check_output
from ..infra.progress import progress_printer


def fail(message) -> SystemExit:
    """The ``SystemExit`` that prints ``error: MESSAGE`` and exits with status 1 (raise it).
    """
    return SystemExit(f"error: {message}")


def check_out(path, what: str = "--out") -> str:
    """``output.check_output`` for a command: the checked path, or exit with the reason.

    Shared by every cobra-ref subcommand (before the long run).
    """
    try:
        check_output(path, what)
    except OutputError as exc:
        raise fail(exc) from None
    return path


def check_writable(path: str) -> None:
    """Exit with a clear error if ``path`` cannot be written (``check_out``).
    """
    check_out(path, "output")


def write_text_atomic(path: str, text: str, what: str = "output") -> None:
    """Check the target (a clear error), then write through a temporary file and a rename.
    """
    from ..infra.output import write_text

    check_out(path, what)
    try:
        write_text(path, text, what)
    except OutputError as exc:
        raise fail(exc) from None


@contextlib.contextmanager
def c_stdout_silenced():
    """Discard what C libraries print on file descriptor 1 while the block runs: OSQP prints
    "Polishing not needed ..." once per solve even with verbose off, thousands of lines per run.
    stdout then carries only the command's own output (its JSON line, printed after the block);
    progress goes to stderr.
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


def failed_path(out: str) -> str:
    """Where a run that fails part-way is kept: ``OUT`` without its extension + ``.failed.npz``.

    Shared by every cobra-ref subcommand (``run.npz`` -> ``run.failed.npz``, ``run`` ->
    ``run.failed.npz``).
    """
    return os.path.splitext(out)[0] + ".failed.npz"


def _keep_partial(traj, out: str, until: str = "the failure") -> str:
    """Write a partial run to ``failed_path(out)``; the sentence that says where it is (or why not)."""
    failed = failed_path(out)
    try:
        traj.to_npz(failed)
    except (OSError, ValueError) as exc:
        return f"what was computed could not be kept: {exc}"
    return f"what was computed up to {until} is in {failed}"


def say_interrupted(exc: BaseException | None, kept: str) -> int:
    """Print the one line of a command stopped by Ctrl-C or SIGTERM on stderr,
    ``interrupted (SIGTERM): KEPT``, on a line of its own after a progress line; return the exit
    status, 130 for Ctrl-C and 143 for SIGTERM (``signals.exit_status``).
    """
    from ..infra.progress import end_line
    from ..infra.signals import exit_status, signal_name

    end_line()
    print(f"interrupted ({signal_name(exc)}): {kept}", file=sys.stderr, flush=True)
    return exit_status(exc)


def interrupted_exit(exc: BaseException | None, kept: str) -> SystemExit:
    """The ``SystemExit`` of a command stopped by Ctrl-C or SIGTERM (raise it), after
    ``say_interrupted``'s line."""
    return SystemExit(say_interrupted(exc, kept))


@dataclass(frozen=True)
class Job:
    """One simulation for ``run_and_write``: the model, the reference, ``duration`` [s] on the grid of
    ``settings.dt`` (both checked by the command before), the start (None: ``start.initial_state``),
    the stepper."""

    model: object
    reference: object
    duration: float
    settings: object
    q0: object = None
    qd0: object = None
    stepper: str = "fast"


def run_and_write(job: Job, out: str, label: str, quiet: bool = False, meta=None, summary=None):
    """Simulate ``job``, write the NPZ to ``out`` and print the one-line JSON summary (plus
    ``summary(traj)``'s keys); a failure mid-run (any exception of the step, or Ctrl-C) writes what
    was computed to OUT.failed.npz and exits with the error, which names the step and the time.
    ``meta`` is added to the trajectory's meta; ``label`` names the progress line (none if ``quiet``).
    A run that left physics (``simulate.LeftPhysicsWarning``) prints ``warning: ...`` as one line
    on stderr, after the run.
    """
    from ..simulate import LeftPhysicsWarning, simulate
    from ..step import SimulationError

    progress = None if quiet else progress_printer(label)
    try:
        with c_stdout_silenced(), warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", LeftPhysicsWarning)
            traj = simulate(job.model, job.reference, job.duration, job.settings, job.q0, job.qd0,
                            progress=progress, stepper=job.stepper)
        for w in caught:
            if issubclass(w.category, LeftPhysicsWarning):
                print(f"warning: {w.message}", file=sys.stderr)
            else:
                warnings.showwarning(w.message, w.category, w.filename, w.lineno)
    except SimulationError as exc:
        if exc.trajectory is None:  # bad input: nothing was computed, nothing is written
            raise fail(exc) from None
        exc.trajectory.meta.update(meta or {})
        where = _keep_partial(exc.trajectory, out)
        print(json.dumps(exc.trajectory.summary()))
        raise fail(f"{exc}\n{where}") from None
    except KeyboardInterrupt as exc:  # Ctrl-C or SIGTERM (signals.stop_signals)
        traj = getattr(exc, "trajectory", None)
        if traj is None:
            raise
        traj.meta.update(meta or {})
        where = traj.error.rsplit(": ", 1)[0]  # "step k (t = ... s)"
        raise interrupted_exit(exc, f"stopped at {where}; {_keep_partial(traj, out, 'the interrupt')}") from None
    traj.meta.update(meta or {})
    try:
        traj.to_npz(out)
    except OSError as exc:  # a full disk, or the target changed during the run (checked before it)
        raise fail(f"{exc}; {_keep_partial(traj, out)}") from None
    print(json.dumps({**traj.summary(), **(summary(traj) if summary else {})}))
    return traj


def finite_float(text: str) -> float:
    """argparse type: a float, rejected if not finite (the message names the value).
    """
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not np.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be finite, got {text}")
    return value


def gait_param(text: str) -> tuple:
    """argparse type: ``NAME=VALUE``, a gait parameter and a finite number (the gait checks its
    range when the reference is built).
    """
    from ..infra.validation import RULES, ValidationError

    name, sep, value = str(text).partition("=")
    name = name.strip()
    if not sep or not name:
        raise argparse.ArgumentTypeError(f"--param = {text!r}: expected NAME=VALUE, e.g. amplitude=0.4 "
                                         "(a parameter of the gait)")
    try:
        return name, RULES["gait_param"].parse(value.strip(), f"--param {name}")
    except ValidationError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


gait_param.allowed = "NAME=VALUE: a parameter of the gait, a finite number in the gait's range"


# CobraParameters that simulate and optimize take as options (each checked by its rule)
MODEL_PARAMETERS = ("mu", "mu_robot_box", "mu_box_ground", "box_mass")


def add_model_options(p) -> None:
    """--mu, --mu-robot-box, --mu-box-ground and --box-mass on parser ``p``.
    """
    from ..infra.validation import RULES

    p.add_argument("--mu", type=RULES["mu"].arg("--mu"), default=None,
                   help="friction coefficient robot-ground, and box-ground unless --mu-box-ground (default 1.0; A13)")
    p.add_argument("--mu-robot-box", type=RULES["mu_robot_box"].arg("--mu-robot-box"), default=None,
                   help="friction coefficient of robot-box contacts (default 0.5; assumption A22)")
    p.add_argument("--mu-box-ground", type=RULES["mu_box_ground"].arg("--mu-box-ground"), default=None,
                   help="friction coefficient of box-ground contacts (default: the same as --mu; A13)")
    p.add_argument("--box-mass", type=RULES["box_mass"].arg("--box-mass"), default=None,
                   help="mass of the box [kg] (default 0.5)")


def model_parameters(args):
    """``CobraParameters`` with the model options given on the command line (``add_model_options``).
    """
    from ..params import CobraParameters

    return CobraParameters(**{name: getattr(args, name) for name in MODEL_PARAMETERS if getattr(args, name) is not None})
