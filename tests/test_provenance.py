"""Which edits invalidate a cached run and an optimum's stamp (cobra_ref.provenance): only the physics.

Worked example: a copy of the package with one more sentence in the docstring of
``cli/simulate.py`` (or of ``reproduce/claims.py``) has the same ``physics_hash()``, so every
cache key (``RunSpec.key()``) and every optimum's stamp (``code_version(planning=True)``) stays
valid; the same copy with one line of ``step.py`` changed has another hash, and another key.
"""

from __future__ import annotations

import ast
import os
import shutil

import pytest

from cobra_ref import provenance
from cobra_ref.reproduce.runs import RunSpec

PACKAGE = os.path.dirname(os.path.abspath(provenance.__file__))
ROOTS = ("cobra_ref.step", "cobra_ref.fast.stepper", "cobra_ref.simulate", "cobra_ref.start")


@pytest.fixture
def copy(tmp_path, monkeypatch):
    """A copy of the package's source that ``physics_hash`` reads (``provenance._PACKAGE``)."""
    target = tmp_path / "cobra_ref"
    shutil.copytree(PACKAGE, target, ignore=shutil.ignore_patterns("__pycache__", "*.json", "*.npz"))
    monkeypatch.setattr(provenance, "_PACKAGE", str(target))
    return target


def stamps() -> tuple:
    """What a cache entry and an optimum record of the code, read from ``provenance._PACKAGE``."""
    return provenance.physics_hash(), provenance.code_version(planning=True), RunSpec("C", duration=1.0).key()


def add_to_module_docstring(path, sentence: str) -> None:
    """Append ``sentence`` to the first line of the module docstring of ``path``; the code stays the same."""
    source = path.read_text()
    before = ast.get_docstring(ast.parse(source))
    end = source.index("\n", source.index('"""'))
    path.write_text(source[:end] + " " + sentence + source[end:])
    after = ast.parse(path.read_text())
    assert ast.get_docstring(after) != before
    assert [ast.dump(n) for n in after.body[1:]] == [ast.dump(n) for n in ast.parse(source).body[1:]]  # only the docstring


@pytest.mark.parametrize("name", ["cli/simulate.py", "reproduce/claims.py"])
def test_a_docstring_outside_the_physics_leaves_the_cache_and_the_optima_valid(copy, name):
    assert provenance.PHYSICS_MODULES and name not in provenance.PHYSICS_MODULES + provenance.PLANNING_MODULES
    before = stamps()
    add_to_module_docstring(copy / name, "An edited sentence.")
    assert stamps() == before


def test_one_line_of_the_step_changes_the_cache_keys_and_the_optima_stamps(copy):
    before = stamps()
    path = copy / "step.py"
    lines = path.read_text().splitlines(keepends=True)
    k = next(i for i, line in enumerate(lines) if line.startswith("def step("))
    lines[k] = lines[k].rstrip("\n") + "  # edited\n"
    path.write_text("".join(lines))
    after = stamps()
    assert all(a != b for a, b in zip(after, before))


def package_imports(dotted: str) -> set:
    """The modules of the package that module ``dotted`` imports, at any depth of its code
    (function-level imports included), from its source (AST)."""
    parts = dotted.split(".")
    path = os.path.join(PACKAGE, *parts[1:]) + ".py"
    is_package = not os.path.isfile(path)
    path = os.path.join(PACKAGE, *parts[1:], "__init__.py") if is_package else path
    here = parts if is_package else parts[:-1]
    found = set()
    for node in ast.walk(ast.parse(open(path).read())):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names if a.name.startswith("cobra_ref.")}
        elif isinstance(node, ast.ImportFrom):
            base = here[:len(here) - node.level + 1] if node.level else []
            target = ".".join(base + ([node.module] if node.module else []))
            if target.startswith("cobra_ref"):
                for a in node.names:  # a submodule, or a name from the module (package) itself
                    sub = f"{target}.{a.name}"
                    where = os.path.join(PACKAGE, *sub.split(".")[1:])
                    exists = os.path.isfile(where + ".py") or os.path.isfile(os.path.join(where, "__init__.py"))
                    found.add(sub if exists else target)
    return {m for m in found if m != dotted}


def test_every_module_a_simulation_imports_is_hashed():
    """Every module the steppers, the simulation and the start import (transitively, within the
    package, infra excepted: the checks and the executors do not change a result) is in
    ``PHYSICS_MODULES``, so that editing it invalidates the cache."""
    seen, todo = set(), list(ROOTS)
    while todo:
        m = todo.pop()
        if m not in seen and not m.startswith("cobra_ref.infra"):
            seen.add(m)
            todo += sorted(package_imports(m))
    listed = {"cobra_ref." + p[:-3].replace("/", ".") for p in provenance.PHYSICS_MODULES}
    assert set(ROOTS) <= seen
    assert not seen - listed, f"imported by a simulation but not hashed: {sorted(seen - listed)}"
