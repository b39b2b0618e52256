"""cobra_ref as a library: the main names import from the package, its docstring's example runs (a
doctest), ``help(cobra_ref)`` points onwards, ``plot_run`` draws what it says, and the README's Python
snippets run as they are written (the Dask one as a script, when dask is installed)."""

import doctest
import importlib.util
import os
import re
import subprocess
import sys

import numpy as np
import pytest

import cobra_ref

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
README = os.path.join(ROOT, "README.md")


def readme() -> str:
    with open(README, encoding="utf-8") as f:
        return f.read()


def python_block(containing: str) -> str:
    """The README's ```python block that contains ``containing``."""
    blocks = [b for b in re.findall(r"```python\n(.*?)```", readme(), re.S) if containing in b]
    assert len(blocks) == 1, f"one python block with {containing!r} in README.md, found {len(blocks)}"
    return blocks[0]


def run_script(source: str, cwd, timeout: float) -> subprocess.CompletedProcess:
    """``source`` written to cwd/script.py and run as a script, this checkout first on the path."""
    path = os.path.join(cwd, "script.py")
    with open(path, "w", encoding="utf-8") as f:
        f.write(source)
    env = dict(os.environ, PYTHONPATH=ROOT + os.pathsep + os.environ.get("PYTHONPATH", ""), MPLBACKEND="Agg")
    return subprocess.run([sys.executable, path], cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)


def test_the_main_names_import_from_the_package():
    from cobra_ref import (BoxPlacement, StepSettings, Trajectory, cobra_model, gait, initial_state,  # noqa: F401
                           make_stepper, simulate)

    assert set(cobra_ref.__all__) >= {"simulate", "gait", "initial_state", "cobra_model", "BoxPlacement",
                                      "StepSettings", "make_stepper", "Trajectory"}
    assert all(hasattr(cobra_ref, name) for name in cobra_ref.__all__)


def test_the_package_docstring_example_runs():
    # build the model, a gait, simulate 0.2 s and read the box's displacement (a few seconds)
    result = doctest.testmod(cobra_ref, verbose=False)
    assert result.attempted >= 5 and result.failed == 0


def test_help_points_to_the_readme_the_tutorials_and_the_entry_points():
    doc = cobra_ref.__doc__
    for name in ("README", "tutorials/", "simulate", "initial_state", "plot_run", "cobra-ref --help",
                 "planning", "regenerate"):
        assert name in doc, name


def test_the_readme_stays_short_with_the_equation_map_near_the_top():
    lines = readme().splitlines()
    assert len(lines) <= 200, f"README.md has {len(lines)} lines"
    assert any(line.startswith("## Where each equation lives") for line in lines[:120])


def test_the_readme_holds_the_two_set_up_commands_ci_runs():
    """.ci/run runs the README's lines that start with ``python3 -m venv .venv && ``: exactly two, the
    figures' check and the tests, each from a fresh virtual environment."""
    commands = [line for line in readme().splitlines() if line.startswith("python3 -m venv .venv && ")]
    assert len(commands) == 2, commands
    assert commands[0].endswith("cobra-ref figures --check") and commands[1].endswith("python -m pytest -n auto")


# ------------------------------------------------------------------------------------------- plot_run

@pytest.fixture(scope="module")
def run():
    """0.1 s of J rolling at full speed from t = 0: the box is met, so every panel has data."""
    return cobra_ref.simulate(cobra_ref.cobra_model(), cobra_ref.gait("J", ramp_time=0.0), 0.1)


def test_plot_run_draws_the_box_path_the_forces_and_the_torques(run):
    from cobra_ref.viz.plot import KIND_NAMES, normal_forces, plot_run

    fig = plot_run(run)
    box, forces, torques = fig.axes[:3]
    np.testing.assert_array_equal(box.lines[0].get_xydata(), run.box_pose[:, :2])
    per_kind = normal_forces(run)
    assert [line.get_label() for line in forces.lines] == list(KIND_NAMES)
    for line, name in zip(forces.lines, KIND_NAMES):
        np.testing.assert_array_equal(line.get_ydata(), per_kind[name])
    assert per_kind["robot-ground"].max() > 0, "the robot stands on the ground"
    assert len(torques.lines) == run.tau.shape[1]
    for j, line in enumerate(torques.lines):
        np.testing.assert_array_equal(line.get_xdata(), run.t[:len(run.tau)])
        np.testing.assert_array_equal(line.get_ydata(), run.tau[:, j])


def test_plot_run_sums_the_contact_log_by_hand(run):
    from cobra_ref.viz.plot import normal_forces

    c, total = run.contacts, np.zeros(len(run.tau))
    for k, kind, f, n in zip(c["contact_step"], c["contact_kind"], c["contact_force"], c["contact_normal"]):
        if kind == 0:
            total[k] += f @ n
    np.testing.assert_allclose(normal_forces(run)["robot-ground"], total, rtol=1e-12, atol=1e-12)


def test_plot_run_reads_an_npz_and_draws_into_given_axes(run, tmp_path):
    import matplotlib.pyplot as plt

    from cobra_ref.viz.plot import plot_run

    path = tmp_path / "run.npz"
    run.to_npz(str(path))
    fig, ax = plt.subplots()
    assert plot_run(path, what="box", ax=ax) is fig
    np.testing.assert_array_equal(ax.lines[0].get_xydata(), run.box_pose[:, :2])
    with pytest.raises(ValueError, match="what must name panels"):
        plot_run(run, what=("box", "speed"))
    with pytest.raises(ValueError, match="2 panel"):
        plot_run(run, what=("box", "forces"), ax=ax)
    plt.close("all")


# ------------------------------------------------------------------------- the README's Python, as written

def test_the_readme_first_five_minutes_python_runs(tmp_path):
    source = python_block("plot_run(traj)")
    assert 3 <= len([line for line in source.splitlines() if line.strip()]) <= 6
    short = source.replace("3.0)", "0.05)")  # the same lines on a shorter run
    assert short != source
    out = run_script(short, tmp_path, timeout=300)
    assert out.returncode == 0, out.stderr
    assert (tmp_path / "J.png").read_bytes()[:4] == b"\x89PNG"


@pytest.mark.skipif(importlib.util.find_spec("distributed") is None,
                    reason="dask.distributed is not installed (pip install '.[dask]')")
def test_the_readme_dask_snippet_runs_as_a_script(tmp_path):
    """The snippet as written (its __main__ guard, a local Client, a quick figure run) as a script:
    without the guard, a local cluster's worker processes fail to start ("Nanny failed to start")."""
    source = python_block("dask.distributed")
    assert 'if __name__ == "__main__":' in source and "FiguresOptions(quick=True)" in source
    out = run_script(source, tmp_path, timeout=600)
    assert out.returncode == 0, out.stderr[-3000:]
    with open(tmp_path / "figures-dask" / "claims.json", encoding="utf-8") as f:
        assert f.readline().startswith('{"smoke run": "SMOKE RUN')
