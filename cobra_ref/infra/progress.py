"""Progress of a long simulation on stderr: which run, how far, how long is left."""

from __future__ import annotations

import sys
import time


def progress_printer(label: str):
    """A ``progress(done, total)`` callback that rewrites one stderr line: label, percentage,
    steps done, and the time left extrapolated from the time so far.

    Passed to ``simulate(..., progress=...)`` by the commands and the figure runs.
    """
    start = time.perf_counter()

    def show(done: int, total: int) -> None:
        elapsed = time.perf_counter() - start
        left = elapsed / done * (total - done)
        sys.stderr.write(f"\r{label}: {100 * done / total:5.1f} % ({done}/{total} steps), "
                         f"{left:5.0f} s left ")
        if done == total:
            sys.stderr.write("\n")
        sys.stderr.flush()

    return show
