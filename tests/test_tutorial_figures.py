"""Every figure a tutorial draws is saved as a PNG (headless, a figure only shown is lost), and a
tutorial opens a window only on an interactive matplotlib backend. Read from the source;
tests/test_tutorials_run.py runs them."""

import ast
import pathlib

import pytest

TUTORIALS = sorted((pathlib.Path(__file__).parent.parent / "tutorials").glob("[0-9][0-9]_*.py"))


def calls(tree, name):
    """The calls of ``something.name(...)`` in ``tree``."""
    return [node for node in ast.walk(tree)
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == name]


@pytest.mark.parametrize("path", TUTORIALS, ids=lambda p: p.name)
def test_every_figure_is_saved_and_shown_only_on_an_interactive_backend(path):
    tree = ast.parse(path.read_text())
    figures = len(calls(tree, "subplots")) + len(calls(tree, "figure"))
    saved = calls(tree, "savefig")
    assert len(saved) >= figures, f"{path.name}: {figures} figures, {len(saved)} savefig calls"
    for call in saved:
        target = ast.unparse(call.args[0])
        assert target.startswith("OUT /") and target.endswith(".png'"), f"{path.name}: saves to {target}"
    shows = calls(tree, "show")
    guarded = [call for node in ast.walk(tree) if isinstance(node, ast.If) and "get_backend" in ast.unparse(node.test)
               for call in calls(node, "show")]
    assert len(shows) == len(guarded), f"{path.name}: plt.show() outside the interactive-backend check"
