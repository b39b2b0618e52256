"""What the figure command keeps between runs: the figures' stamps, plain JSON for its caches, its
progress lines.

A figure whose inputs are unchanged since it was last written is kept: ``.stamps.json`` in the
output directory holds, per figure, a stamp (``figure_stamp``: a hash of the simulations' cache
keys, the figure module's name and the drawing source), the files it wrote and each file's SHA-256
(``Stamps``): a file whose content changed since is drawn again.
"""

from __future__ import annotations

import hashlib
import json
import os
import sys

from ..infra.output import write_text
from .cache import CacheDamage, file_sha256, verified

STAMPS = ".stamps.json"
HERE = os.path.dirname(os.path.abspath(__file__))
# the drawing source every figure's stamp covers: the figures package and the scene drawing it shares
# with the renderer (fig. 3 and the GIFs draw with cobra_ref/viz)
DRAWING_SOURCES = (os.path.join(HERE, "figures"), os.path.join(os.path.dirname(HERE), "viz"))


def figure_stamp(keys: dict, module) -> str:
    """Hash of the simulations' cache keys, the figure module's name and the source of every module
    in ``DRAWING_SOURCES`` (figures share drawing code)."""
    h = hashlib.sha256((json.dumps(keys, sort_keys=True) + module.__name__).encode())
    for here in DRAWING_SOURCES:
        for name in sorted(os.listdir(here)):
            if name.endswith(".py"):
                with open(os.path.join(here, name), "rb") as f:
                    h.update(f.read())
    return h.hexdigest()


class Stamps:
    """The stamps of one output directory (``STAMPS``), read once (none with ``force``), written
    after every figure."""

    def __init__(self, out_dir: str, force: bool = False):
        self.path = os.path.join(out_dir, STAMPS)
        # a stamps file that is not a JSON object is named (``cache.verified``): every figure is drawn again
        stamps = None if force or not os.path.isfile(self.path) else verified(self.path, _read_stamps)
        self.stamps = stamps or {}

    def kept(self, name: str, stamp: str) -> list | None:
        """The files of figure ``name`` if they were written under ``stamp`` and each still has the
        content it was written with (its SHA-256), else None: a file changed since is named on stderr
        and the figure is drawn again."""
        old = self.stamps.get(name)
        if not isinstance(old, dict) or old.get("stamp") != stamp:
            return None
        files, digests = old.get("files"), old.get("sha256")
        # a stamp written without the files' hashes, or naming files that are gone: draw again
        if not isinstance(files, list) or not files or not isinstance(digests, dict) \
                or not all(isinstance(f, str) and os.path.isfile(f) for f in files):
            return None
        changed = [f for f in files if digests.get(f) != file_sha256(f)]
        if changed:
            sys.stderr.write(f"output {changed[0]} does not match its stamp (changed since it was written): "
                             f"drawing {name} again\n")
            return None
        return list(files)

    def record(self, name: str, stamp: str, files: list) -> None:
        """Figure ``name`` was written under ``stamp``: keep it with each file's SHA-256, and write the stamps file."""
        self.stamps[name] = {"stamp": stamp, "files": files, "sha256": {f: file_sha256(f) for f in files}}
        write_text(self.path, json.dumps(self.stamps, indent=1))


def _read_stamps(path: str) -> dict:
    """The stamps in ``path``; ``CacheDamage`` unless it is a JSON object."""
    with open(path, encoding="utf-8") as f:
        stamps = json.load(f)
    if not isinstance(stamps, dict):
        raise CacheDamage(f"not a JSON object of stamps but a {type(stamps).__name__}")
    return stamps


def clean(x):
    """Plain JSON: numpy values to Python ones, inf and nan to null (strict JSON has neither)."""
    if isinstance(x, dict):
        return {str(k): clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [clean(v) for v in x]
    if hasattr(x, "tolist"):
        return clean(x.tolist())
    if isinstance(x, float) and not (x == x and abs(x) != float("inf")):
        return None
    return x


def say(progress: bool, text: str) -> None:
    """One progress line on stderr, if ``progress``."""
    if progress:
        sys.stderr.write(text + "\n")
        sys.stderr.flush()
