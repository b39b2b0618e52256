"""An optimization's params JSON written as the search goes, so that no completed rollout is lost.

``Checkpoint(path)`` is what ``search.optimize`` takes as ``checkpoint``: after every batch of
rollouts it writes every rollout so far and the best of them to ``path`` (atomically, marked
``"checkpoint": true``). A checkpoint that cannot be written (a full disk) is said once and the
search goes on; the next batch tries again. ``Checkpoint.final`` writes the finished result to
``path``; when that fails, to a fallback file in the system's temporary directory, and the
``OutputError`` it raises says, in one line, why and where the result is.
"""

from __future__ import annotations

import os
import tempfile

from ..infra.output import OutputError
from .results import write_result


def fallback_path(path: str) -> str:
    """Where ``Checkpoint.final`` keeps a result that ``path`` cannot take: the system's temporary
    directory (usually another file system than the target's), a name from ``path`` and this
    process's id (``/tmp/cobra-ref-J-4242.json`` for ``runs/J.json``)."""
    stem = os.path.splitext(os.path.basename(os.fspath(path)))[0] or "optimize"
    return os.path.join(tempfile.gettempdir(), f"cobra-ref-{stem}-{os.getpid()}.json")


class Checkpoint:
    """Writes an optimization's result to ``path`` after every batch and at the end (module
    docstring); ``warn(line)`` says a checkpoint that could not be written (once until one is
    written again). ``kept``: the rollouts in the last checkpoint written; ``kept_in``: the file
    that holds the finished result once ``final`` has run (``path``, the fallback, or None)."""

    def __init__(self, path: str, warn=None):
        self.path, self.warn = path, warn
        self.kept, self.failing, self.kept_in = 0, False, None

    def __call__(self, result) -> None:
        """Write the rollouts so far (a ``ShootingResult`` with ``checkpoint`` true) to ``path``."""
        try:
            write_result(result, self.path)
        except OutputError as exc:
            if not self.failing and self.warn is not None:
                self.warn(f"warning: checkpoint not written: {exc}; the search goes on")
            self.failing = True
            return
        self.kept, self.failing = len(result.history), False

    def final(self, result) -> dict:
        """Write the finished ``result`` to ``path`` and return the record written; else keep it in
        ``fallback_path(path)`` and raise an ``OutputError`` naming both files and the reason."""
        try:
            record = write_result(result, self.path)
        except OutputError as exc:
            failure = exc
        else:
            self.kept_in = self.path
            return record
        n, fallback = len(result.history), fallback_path(self.path)
        try:
            write_result(result, fallback)
        except OutputError:
            # nowhere to write: say what the last checkpoint kept
            where = (f"{self.path} holds the checkpoint after {self.kept} of the {n} rollouts" if self.kept
                     else f"none of the {n} rollouts could be kept")
        else:
            self.kept_in, where = fallback, f"the result ({n} rollouts) is kept in {fallback}"
        raise OutputError(f"{failure}; {where}")
