"""Progress of a long simulation on stderr: which run, how far, how long is left."""

from __future__ import annotations

import sys
import time

# whether the last thing written to stderr is a progress line without its end (``rewrite``)
_open = {"line": False}


def rewrite(text: str) -> None:
    """Rewrite the progress line in place ("\\r" + text, no newline) on stderr."""
    sys.stderr.write("\r" + text)
    sys.stderr.flush()
    _open["line"] = True


def end_line() -> None:
    """End the progress line that ``rewrite`` left open, if any, so the next message starts on a
    line of its own."""
    if _open["line"]:
        sys.stderr.write("\n")
        sys.stderr.flush()
        _open["line"] = False


def progress_printer(label: str):
    """A ``progress(done, total)`` callback that rewrites one stderr line: label, percentage,
    steps done, and the time left extrapolated from the time so far.

    Passed to ``simulate(..., progress=...)`` by the commands and the figure runs.
    """
    start = time.perf_counter()

    def show(done: int, total: int) -> None:
        elapsed = time.perf_counter() - start
        left = elapsed / done * (total - done)
        rewrite(f"{label}: {100 * done / total:5.1f} % ({done}/{total} steps), {left:5.0f} s left ")
        if done == total:
            end_line()

    return show
