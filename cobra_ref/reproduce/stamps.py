"""What the figure command keeps between runs: the figures' stamps, plain JSON for its caches, its
progress lines.

A figure whose inputs are unchanged since it was last written is kept: ``.stamps.json`` in the
output directory holds, per figure, a stamp (``figure_stamp``: a hash of the simulations' cache
keys, the figure module's name and the drawing source) and the files it wrote (``Stamps``).
"""

from __future__ import annotations

import hashlib
import json
import os
import sys

from ..infra.output import write_text

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
        self.stamps = {} if force else read_json(self.path)

    def kept(self, name: str, stamp: str) -> list | None:
        """The files of figure ``name`` if they were written under ``stamp`` and are all there, else None."""
        old = self.stamps.get(name, {})
        if old.get("stamp") == stamp and old.get("files") and all(os.path.isfile(f) for f in old["files"]):
            return list(old["files"])
        return None

    def record(self, name: str, stamp: str, files: list) -> None:
        """Figure ``name`` was written under ``stamp``: keep it, and write the stamps file."""
        self.stamps[name] = {"stamp": stamp, "files": files}
        write_text(self.path, json.dumps(self.stamps, indent=1))


def read_json(path: str) -> dict:
    """The JSON object in ``path``, or {} if there is none or it is not readable."""
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return {}


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
