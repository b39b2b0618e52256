"""Signals that stop a command: SIGTERM handled as Ctrl-C, and the exit status of each.

A batch scheduler ends a job with SIGTERM (``timeout``, Slurm, systemd, ``docker stop``), a person
with Ctrl-C (SIGINT). Inside ``stop_signals()`` both raise a ``KeyboardInterrupt`` in the main
thread (``Terminated`` for SIGTERM), so every path that keeps partial work on Ctrl-C keeps it on
SIGTERM too. The first signal is raised; a repeat while it is handled is ignored, so the clean-up
(ending the worker processes, writing what was kept) runs to its end; SIGKILL still ends
everything. On leaving, the previous handlers are back: importing the library changes nothing.

The exit status is the shell's convention, 128 + the signal's number: 130 after Ctrl-C, 143
after SIGTERM.
"""

from __future__ import annotations

import signal
import threading
from contextlib import contextmanager

NAMES = {signal.SIGINT: "Ctrl-C", signal.SIGTERM: "SIGTERM"}

# the signal that stopped the command running in ``stop_signals`` (None: none yet)
_received: dict = {"signum": None}


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised as a ``KeyboardInterrupt`` so that whatever handles Ctrl-C handles it too."""

    signum = signal.SIGTERM


def _raise_once(signum, frame) -> None:
    """The handler: raise the first signal in the main thread, ignore the ones after it."""
    if _received["signum"] is not None:
        return
    _received["signum"] = signum
    raise Terminated("SIGTERM") if signum == signal.SIGTERM else KeyboardInterrupt()


@contextmanager
def stop_signals():
    """Handle SIGTERM and SIGINT as described in the module docstring while the block runs.

    A signal that this process was started ignoring (SIG_IGN, e.g. SIGINT of a background job) or
    that another handler owns stays as it was; outside the main thread nothing is installed."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    defaults = {signal.SIGINT: signal.default_int_handler, signal.SIGTERM: signal.SIG_DFL}
    previous = {s: signal.getsignal(s) for s in defaults}
    _received["signum"] = None
    for s, handler in previous.items():
        if handler is defaults[s]:
            signal.signal(s, _raise_once)
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, signal.SIG_DFL if handler is None else handler)


def received() -> int | None:
    """The number of the signal that stopped the command (``stop_signals``), or None."""
    return _received["signum"]


def interrupted(exc: BaseException) -> bool:
    """Whether ``exc`` ends the command because of a signal: a ``KeyboardInterrupt``, or any other
    error raised after a signal arrived (a worker or helper process that the same signal ended)."""
    return isinstance(exc, KeyboardInterrupt) or (received() is not None and not isinstance(exc, SystemExit))


def signum_of(exc: BaseException | None = None) -> int:
    """The signal behind ``exc`` (``Terminated``: SIGTERM, another ``KeyboardInterrupt``: SIGINT),
    else the one received, else SIGINT."""
    if isinstance(exc, KeyboardInterrupt):
        return getattr(exc, "signum", signal.SIGINT)
    return received() or signal.SIGINT


def signal_name(exc: BaseException | None = None) -> str:
    """"SIGTERM" or "Ctrl-C": what stopped the command (``signum_of``)."""
    return NAMES.get(signum_of(exc), f"signal {signum_of(exc)}")


def exit_status(exc: BaseException | None = None) -> int:
    """128 + the signal's number (``signum_of``): 130 for Ctrl-C, 143 for SIGTERM."""
    return 128 + int(signum_of(exc))
