"""Atomic output: write to a temporary file beside the target, then rename it over the target.

A reader (or an interrupted run) never sees half a file: the target holds the old content or
the new, nothing in between. Every file cobra_ref writes goes through ``atomic_write``.
"""

from __future__ import annotations

import os
import tempfile


def atomic_write(path: str, write) -> None:
    """Call ``write(tmp_path)`` for a temporary file next to ``path``, then rename it to ``path``.

    Helper: atomic output (module docstring). The file gets the permissions of an ordinary new
    file (mkstemp's are 0600).
    """
    directory = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(dir=directory, prefix=".tmp_", suffix=os.path.splitext(path)[1])
    os.close(fd)
    try:
        write(tmp)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def write_text(path: str, text: str) -> None:
    """Write ``text`` to ``path`` atomically.

    Helper: atomic text output (claims, summaries, MJCF).
    """

    def write(tmp):
        with open(tmp, "w") as f:
            f.write(text)

    atomic_write(path, write)
