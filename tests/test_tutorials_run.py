"""Every tutorial runs top to bottom (they end in asserts, so running them checks them)."""

import pathlib
import runpy

import matplotlib
import pytest

TUTORIALS = sorted((pathlib.Path(__file__).parent.parent / "tutorials").glob("[0-9][0-9]_*.py"))


def test_there_are_tutorials():
    assert len(TUTORIALS) >= 2


@pytest.mark.parametrize("path", TUTORIALS, ids=lambda p: p.name)
def test_tutorial_runs(path, tmp_path, monkeypatch):
    """Run in a temporary directory with the Agg backend (plt.show() is then a no-op); pictures go
    to that directory too, nothing into the repository."""
    matplotlib.use("Agg")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("COBRA_REF_OUT", str(tmp_path))
    runpy.run_path(str(path), run_name="__main__")
    import matplotlib.pyplot as plt

    plt.close("all")


def test_tutorials_start_with_a_title_cell():
    """The house style of tutorials: line 1 is a markdown cell with the title."""
    for path in TUTORIALS:
        lines = path.read_text().splitlines()
        assert lines[0] == "# %% [markdown]", path.name
        assert lines[1].startswith("# # "), path.name
