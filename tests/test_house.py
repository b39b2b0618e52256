"""The house's rules, read from the source by an AST walk: floors without cycles, small modules and
functions, one default dt, no mode strings compared inside a step.

Worked example of the floors: ``cobra_ref.step`` (floor "model") may import ``cobra_ref.infra``
(floor "base") but not ``cobra_ref.simulate`` (floor "run"); an import inside a function counts
as much as one at the top of the module.
"""

from __future__ import annotations

import ast
import os
import subprocess
import sys

import pytest

PACKAGE = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "cobra_ref")

# floors, low to high: a module may import from its own floor or a lower one
FLOORS = (
    ("base", ("provenance", "quaternion", "spatial", "infra")),
    ("model", ("params", "joints", "model", "robots", "kinematics", "dynamics", "gaps", "contact",
               "compliance", "qp", "coulomb_newton", "least_action", "step", "touchdown", "trajectory", "gaits",
               "reference", "mjcf")),
    ("fast", ("fast",)),
    ("run", ("steppers", "start", "placement", "simulate", "batch")),
    ("use", ("planning", "viz")),
    ("reproduce", ("reproduce",)),
    ("door", ("cli", "__main__", "")),
)
MAX_MODULE_LINES = 450
MAX_FUNCTION_LINES = 60
MAX_PARAMETERS = 8


def modules() -> dict:
    """{dotted name: path} of every module of the package."""
    out = {}
    for folder, _, files in os.walk(PACKAGE):
        for name in files:
            if name.endswith(".py"):
                path = os.path.join(folder, name)
                dotted = "cobra_ref." + os.path.relpath(path, PACKAGE)[:-3].replace(os.sep, ".")
                out[dotted.removesuffix(".__init__")] = path
    return out


def floor(dotted: str) -> int:
    """The floor of a module: the floor that lists its first name below the package."""
    first = dotted.split(".")[1] if "." in dotted else ""
    for i, (_, names) in enumerate(FLOORS):
        if first in names:
            return i
    raise AssertionError(f"{dotted} is on no floor: add it to tests/test_house.py's FLOORS")


def imports(dotted: str, path: str, known: dict) -> set:
    """The package modules ``dotted`` imports, at any depth of its code (function-level included)."""
    is_package = path.endswith("__init__.py")
    here = dotted if is_package else dotted.rsplit(".", 1)[0]
    found = set()
    for node in ast.walk(ast.parse(open(path).read())):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names if a.name in known}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                parts = here.split(".")
                base = ".".join(parts[:len(parts) - node.level + 1])
                target = base + ("." + node.module if node.module else "")
            else:
                target = node.module or ""
            if not target.startswith("cobra_ref"):
                continue
            subs = {f"{target}.{a.name}" for a in node.names} & set(known)
            found |= subs
            if len(subs) < len(node.names):  # a name from the module itself (or a package's __init__)
                while target not in known:
                    target = target.rsplit(".", 1)[0]
                found.add(target)
    found.discard(dotted)
    return found


def graph() -> dict:
    known = modules()
    return {m: imports(m, p, known) for m, p in known.items()}


def test_every_module_is_on_a_floor():
    for m in modules():
        floor(m)


def test_no_import_goes_up_a_floor():
    # e.g. cobra_ref.infra.validation importing cobra_ref.cli (to render option tables) would go up
    upward = [f"{m} ({FLOORS[floor(m)][0]}) imports {t} ({FLOORS[floor(t)][0]})"
              for m, targets in graph().items() for t in targets if floor(t) > floor(m)]
    assert not upward, "\n".join(upward)


def test_no_import_cycle():
    # Tarjan's strongly connected components over the import graph; any component of two or more
    # modules is a cycle
    g, index, low, stack, on, cycles = graph(), {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in g[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                cycles.append(sorted(component))

    for v in g:
        if v not in index:
            visit(v)
    assert not cycles, cycles


def code_lines(node, source: list) -> int:
    """Lines of a function's body that hold code: no docstring, blank or comment lines."""
    body = node.body
    if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant) \
            and isinstance(body[0].value.value, str):
        body = body[1:]
    lines = set()
    for b in body:
        for n in ast.walk(b):
            if isinstance(n, ast.Expr) and isinstance(getattr(n, "value", None), ast.Constant) \
                    and isinstance(n.value.value, str):
                continue  # a nested docstring
            if hasattr(n, "lineno"):
                lines.add(n.lineno)
    return sum(1 for ln in lines if source[ln - 1].strip() and not source[ln - 1].strip().startswith("#"))


def parameters(node) -> int:
    a = node.args
    names = [x.arg for x in a.posonlyargs + a.args + a.kwonlyargs]
    if names and names[0] in ("self", "cls"):
        names = names[1:]
    return len(names) + (a.vararg is not None) + (a.kwarg is not None)


def test_modules_and_functions_are_small():
    too_big = []
    for m, path in modules().items():
        source = open(path).read().splitlines()
        if len(source) > MAX_MODULE_LINES:
            too_big.append(f"{m}: {len(source)} lines")
        for node in ast.walk(ast.parse("\n".join(source))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                n, k = code_lines(node, source), parameters(node)
                if n > MAX_FUNCTION_LINES or k > MAX_PARAMETERS:
                    too_big.append(f"{m}.{node.name}: {n} code lines, {k} parameters")
    assert not too_big, "\n".join(too_big)


@pytest.mark.parametrize("name", ["step.py", "fast/stepper.py"])
def test_no_mode_string_is_compared_in_a_step(name):
    # the contact law and the servo are objects resolved once (StepSettings), not strings
    tree = ast.parse(open(os.path.join(PACKAGE, name)).read())
    compared = [ast.unparse(n) for n in ast.walk(tree) if isinstance(n, ast.Compare)
                and any(isinstance(x, ast.Constant) and isinstance(x.value, str) for x in [n.left, *n.comparators])]
    assert not compared, compared


def test_the_default_time_step_is_written_once():
    # DEFAULT_DT is the one place 1 ms is written as a time step; every other default refers to it
    written = []
    for m, path in modules().items():
        for node in ast.walk(ast.parse(open(path).read())):
            pairs = []
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                a = node.args
                pos = a.posonlyargs + a.args
                pairs += list(zip([x.arg for x in pos[len(pos) - len(a.defaults):]], a.defaults))
                pairs += [(x.arg, d) for x, d in zip(a.kwonlyargs, a.kw_defaults) if d is not None]
            elif isinstance(node, ast.keyword) and node.arg:
                pairs.append((node.arg, node.value))
            elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name) and node.value:
                pairs.append((node.target.id, node.value))
            elif isinstance(node, ast.Assign):
                pairs += [(t.id, node.value) for t in node.targets if isinstance(t, ast.Name)]
            for name, value in pairs:
                if "dt" in name.lower() and name != "DEFAULT_DT" and isinstance(value, ast.Constant) \
                        and value.value == 1e-3:
                    written.append(f"{m}: {name} = 1e-3")
    assert not written, written


def test_a_reference_run_imports_no_module_of_the_fast_wing():
    # settle included: initial_state steps with the stepper it is given
    code = ("import sys\n"
            "from cobra_ref.robots import cobra_model\n"
            "from cobra_ref.gaits import gait\n"
            "from cobra_ref.simulate import simulate\n"
            "from cobra_ref.steppers import make_stepper\n"
            "from cobra_ref.step import StepSettings\n"
            "model = cobra_model()\n"
            "traj = simulate(model, gait('C'), 0.01, StepSettings(dt=0.002), stepper='reference')\n"
            "assert traj.t[-1] > 0\n"
            "print(sorted(m for m in sys.modules if m.startswith('cobra_ref.fast')))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]", out.stdout
