"""Every public function has a docstring, and the README's equation map is true: each function it
names for an equation of [COBRA] exists and its docstring's ``Implements:`` line names that
equation (house style: one function per formula, the equation in its docstring).

Worked example: the map's row ``eq. (5)`` names ``least_action.delassus``, whose docstring says
"Implements: [COBRA] eq. (5), G = J_c M^-1 J_c^T ..."; a range such as "eq. (1)-(6)" covers
every equation from 1 to 6.
"""

import importlib
import inspect
import os
import pkgutil
import re

import pytest

import cobra_ref

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MODULES = sorted(m.name for m in pkgutil.walk_packages(cobra_ref.__path__, "cobra_ref.")
                 if not m.name.endswith("__main__"))
IMPLEMENTS = re.compile(r"Implements:[^\n]*?\[COBRA\] eq\. \((\d)\)(?:\s*-\s*\((\d)\))?")


def test_every_module_is_found():
    """The list is found, not typed: the core, the fast wing and the other wings are all in it."""
    for name in ("cobra_ref.dynamics", "cobra_ref.gaps", "cobra_ref.fast.chain", "cobra_ref.planning.search",
                 "cobra_ref.reproduce.claims", "cobra_ref.cli.simulate"):
        assert name in MODULES


@pytest.mark.parametrize("name", MODULES)
def test_public_functions_have_docstrings(name):
    module = importlib.import_module(name)
    assert inspect.getdoc(module), f"{name} has no module docstring"
    for fname, obj in vars(module).items():
        if fname.startswith("_") or not inspect.isfunction(obj) or obj.__module__ != module.__name__:
            continue
        assert inspect.getdoc(obj), f"{name}.{fname} has no docstring"


def implemented(doc: str) -> set:
    """The equation numbers a docstring's ``Implements:`` lines name ("eq. (2)-(4)" is 2, 3, 4)."""
    out = set()
    for first, last in IMPLEMENTS.findall(doc or ""):
        out |= set(range(int(first), int(last or first) + 1))
    return out


def test_implemented_reads_ranges():
    assert implemented("Implements: [COBRA] eq. (1)-(6) over one step") == {1, 2, 3, 4, 5, 6}
    assert implemented("Implements: [COBRA] eq. (5), G = J M^-1 J^T") == {5}
    assert implemented("Helper: nothing") == set()


def equation_map() -> list:
    """[(equation number, [dotted names of functions or modules], [test files])] from the README."""
    rows = []
    for line in open(os.path.join(ROOT, "README.md"), encoding="utf-8"):
        m = re.match(r"\|\s*eq\. \((\d)\)\s*\|", line)
        if m:
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            code = re.findall(r"`([A-Za-z_][\w.]*)`", cells[2])
            tests = re.findall(r"`(tests/[\w./]+\.py)", cells[3]) if len(cells) > 3 else []
            rows.append((int(m.group(1)), code, tests))
    return rows


def test_the_readme_maps_every_equation():
    assert sorted({n for n, _, _ in equation_map()}) == [1, 2, 3, 4, 5, 6]


@pytest.mark.parametrize("number,names,tests", equation_map())
def test_each_mapped_function_implements_its_equation(number, names, tests):
    assert names, f"eq. ({number}) names no function"
    for name in names:
        module_name, _, attr = f"cobra_ref.{name}".rpartition(".")
        try:  # a module named alone ("compliance") is the row's context, not its function
            importlib.import_module(f"cobra_ref.{name}")
            continue
        except ImportError:
            obj = getattr(importlib.import_module(module_name), attr)
        assert number in implemented(inspect.getdoc(obj)), \
            f"the README maps eq. ({number}) to {name}, whose docstring does not say it implements it"
    for path in tests:
        assert os.path.isfile(os.path.join(ROOT, path)), path
