"""Every public function of the package says what it implements: an ``Implements:`` line naming the
equation or algorithm, or a ``Helper:`` line saying what it serves (the house style)."""

import importlib
import inspect
import pkgutil

import pytest

import cobra_ref

MODULES = sorted(m.name for m in pkgutil.walk_packages(cobra_ref.__path__, "cobra_ref.")
                 if not m.name.endswith("__main__"))


def test_every_module_is_found():
    """The list is found, not typed: the core, the fast wing and the other wings are all in it."""
    for name in ("cobra_ref.dynamics", "cobra_ref.gaps", "cobra_ref.fast.chain", "cobra_ref.planning.search",
                 "cobra_ref.reproduce.claims", "cobra_ref.cli.simulate"):
        assert name in MODULES


@pytest.mark.parametrize("name", MODULES)
def test_public_functions_name_what_they_implement(name):
    module = importlib.import_module(name)
    for fname, obj in vars(module).items():
        if fname.startswith("_") or not inspect.isfunction(obj) or obj.__module__ != module.__name__:
            continue
        doc = inspect.getdoc(obj) or ""
        assert doc, f"{name}.{fname} has no docstring"
        assert "Implements:" in doc or "Helper:" in doc, \
            f"{name}.{fname}: docstring has no Implements: or Helper: line"
