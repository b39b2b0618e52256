"""The documentation names only what exists: every dotted ``cobra_ref.`` name and every repository
path that the README, the docs, the tutorials, the tests and the package's docstrings mention
resolves (a module, an attribute of one, or a file).

Worked example: ``cobra_ref.reproduce.analysis.box_work`` resolves (module ``cobra_ref.reproduce.analysis``,
attribute ``box_work``); ``cobra_ref.analysis`` does not, since that module moved.
"""

from __future__ import annotations

import glob
import importlib
import os
import re

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DOTTED = re.compile(r"\bcobra_ref(?:\.[A-Za-z_][A-Za-z0-9_]*)+")
PATH = re.compile(r"\b(?:cobra_ref|tests|tutorials|docs|figures)/[A-Za-z0-9_./-]+\.(?:py|md|json|png|gif)\b")


def documents() -> list:
    """The files whose text names the code: README, CHANGELOG, docs, tutorials, tests and the package."""
    found = ["README.md", "CHANGELOG.md", *glob.glob("docs/*.md", root_dir=ROOT),
             *glob.glob("tutorials/*.py", root_dir=ROOT),
             *[t for t in glob.glob("tests/*.py", root_dir=ROOT) if not t.endswith("test_docs_names.py")],
             *glob.glob("cobra_ref/**/*.py", root_dir=ROOT, recursive=True)]
    return sorted(f for f in found if os.path.isfile(os.path.join(ROOT, f)))


def resolves(name: str) -> bool:
    """True if ``name`` is a module of the package or an attribute reached from one."""
    parts = name.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        for attr in parts[i:]:
            if hasattr(obj, attr):
                obj = getattr(obj, attr)
            elif hasattr(obj, "__path__"):  # a subpackage's module not imported yet
                try:
                    obj = importlib.import_module(f"{obj.__name__}.{attr}")
                except ImportError:
                    return False
            else:
                return False
        return True
    return False


def test_a_moved_module_does_not_resolve():
    assert resolves("cobra_ref.reproduce.analysis.box_work")
    assert not resolves("cobra_ref.analysis")


@pytest.mark.parametrize("document", documents())
def test_every_dotted_name_resolves(document):
    text = open(os.path.join(ROOT, document), encoding="utf-8").read()
    stale = sorted({m.group(0) for m in DOTTED.finditer(text) if not resolves(m.group(0))})
    assert not stale, f"{document} names what does not exist: {stale}"


@pytest.mark.parametrize("document", documents())
def test_every_repository_path_exists(document):
    text = open(os.path.join(ROOT, document), encoding="utf-8").read()
    missing = sorted({p for p in PATH.findall(text) if not os.path.exists(os.path.join(ROOT, p))})
    assert not missing, f"{document} names files that do not exist: {missing}"
