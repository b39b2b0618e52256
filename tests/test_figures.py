"""Every figure script runs on short simulations and writes real images (the house style).

The session fixture simulates 0.5 s of each paper gait into a temporary cache (about 15 s on two
cores), so the tests need nothing but a clean clone.
"""

import dataclasses
import importlib
import inspect
import os
from types import SimpleNamespace

import numpy as np
import pytest
from matplotlib import image as mpimg
from PIL import Image

from cobra_ref.reproduce.figures import FIGURES, PAPER_FIGURES, animate, common, make_all
from cobra_ref.reproduce.runs import PAPER_GAITS, RunSpec, run_all

DURATION = 0.5
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="session")
def cache_dir(tmp_path_factory):
    return str(tmp_path_factory.mktemp("cobra_cache"))


@pytest.fixture(scope="session")
def results(cache_dir):
    """{gait: Trajectory} of 0.5 s runs of the five paper gaits."""
    return run_all([RunSpec(g, duration=DURATION) for g in PAPER_GAITS], cache_dir, progress=False)


def assert_real_image(path):
    """A non-empty PNG that decodes to an RGB(A) raster, a PDF with its header, or a GIF89a."""
    assert os.path.getsize(path) > 0, f"{path} is empty"
    with open(path, "rb") as f:
        head = f.read(8)
    if path.endswith(".png"):
        assert head == PNG_SIGNATURE, f"{path}: not a PNG"
        img = mpimg.imread(path)
        assert img.ndim == 3 and img.shape[2] in (3, 4) and min(img.shape[:2]) > 100, f"{path}: {img.shape}"
    elif path.endswith(".pdf"):
        assert head.startswith(b"%PDF"), f"{path}: not a PDF"
    elif path.endswith(".gif"):
        assert head[:6] == b"GIF89a", f"{path}: not a GIF89a"
    else:
        raise AssertionError(f"unexpected output {path}")


def no_temp_files(out_dir):
    return [f for f in os.listdir(out_dir) if f.startswith(".tmp_")]


@pytest.mark.parametrize("name", PAPER_FIGURES)
def test_figure_module_writes_png_and_pdf(name, results, cobra, tmp_path):
    """make() writes <stem>.png (a decodable raster) and <stem>.pdf, atomically (no temp files left)."""
    module = importlib.import_module(f"cobra_ref.reproduce.figures.{name}")
    paths = module.make(results, str(tmp_path), cobra)
    assert sorted(os.path.splitext(p)[1] for p in paths) == [".pdf", ".png"]
    assert all(os.path.basename(p).startswith(name) for p in paths)
    for p in paths:
        assert_real_image(p)
    assert not no_temp_files(tmp_path)


def test_animate_writes_one_small_gif_per_gait(results, cobra, tmp_path):
    """One anim_<gait>.gif per gait, several frames, well under the 2 MB budget."""
    paths = animate.make(results, str(tmp_path), cobra)
    assert sorted(os.path.basename(p) for p in paths) == sorted(f"anim_{g}.gif" for g in PAPER_GAITS)
    for p in paths:
        assert_real_image(p)
        assert os.path.getsize(p) < 2e6
        with Image.open(p) as im:
            assert im.n_frames >= 2
    assert not no_temp_files(tmp_path)


def test_missing_gaits_and_an_empty_contact_log_do_not_crash(results, cobra, tmp_path, monkeypatch):
    """With one gait only, whose contact log is empty, make_all still writes every figure and
    the contact panels say "no contact"."""
    traj = results["J"]
    empty = dataclasses.replace(traj, contacts={k: v[:0] for k, v in traj.contacts.items()})
    said = []
    real_empty_panel = common.empty_panel
    monkeypatch.setattr(common, "empty_panel", lambda ax, text=common.NO_CONTACT: (said.append(text),
                                                                                    real_empty_panel(ax, text)))
    paths = make_all({"J": empty}, str(tmp_path), cobra)
    stems = {os.path.splitext(os.path.basename(p))[0] for p in paths}
    assert stems == set(PAPER_FIGURES) | {"anim_J"}
    for p in paths:
        assert_real_image(p)
    assert said.count(common.NO_CONTACT) >= 4  # fig. 4: f_N, f_T, timeline; fig. 5: both panels


def test_script_entry_point_uses_the_cache(cache_dir, tmp_path, capsys):
    """common.main (the `python -m cobra_ref.reproduce.figures.<module>` path) reads the cached runs and
    prints the paths it wrote."""
    from cobra_ref.reproduce.figures import fig06_work_efficiency

    argv = ["--out", str(tmp_path), "--cache", cache_dir, "--duration", str(DURATION)]
    paths = common.main(fig06_work_efficiency.make, argv)
    assert capsys.readouterr().out.split() == paths
    for p in paths:
        assert_real_image(p)


def test_gif_frames_are_capped_for_a_long_run():
    """A 10 s run at dt = 1 ms gets MAX_FRAMES frames; a 0.5 s run FPS frames per second (+ 1)."""
    for duration, expected in ((10.0, animate.MAX_FRAMES), (0.5, int(0.5 * animate.FPS) + 1)):
        t = np.linspace(0.0, duration, int(round(duration / 1e-3)) + 1)
        steps = animate.frame_steps(SimpleNamespace(t=t, q=np.zeros((len(t), 25)), dt=1e-3))
        assert len(steps) == expected and steps[0] == 0 and steps[-1] == len(t) - 1


def test_minmax_decimation_keeps_the_extremes():
    """Thinning a long series keeps its global maximum and minimum (peaks stay visible)."""
    t = np.arange(100_000) * 1e-3
    y = np.sin(t) + (t == 12.345) * 50.0 - (t == 77.7) * 30.0
    t_d, y_d = common.minmax_decimate(t, y, max_points=1000)
    assert len(t_d) <= 1000 and np.all(np.diff(t_d) > 0)
    assert y_d.max() == y.max() and y_d.min() == y.min()


@pytest.mark.parametrize("name", ("__init__", "common") + FIGURES)
def test_figure_functions_say_what_they_implement(name):
    """The rule of tests/test_docstrings_cite.py, applied to the figure package: every public
    function has an "Implements:" or "Helper:" line, and every module a docstring."""
    module = importlib.import_module("cobra_ref.reproduce.figures" if name == "__init__" else f"cobra_ref.reproduce.figures.{name}")
    assert (module.__doc__ or "").strip(), f"{name} has no module docstring"
    for fname, obj in vars(module).items():
        if fname.startswith("_") or not inspect.isfunction(obj) or obj.__module__ != module.__name__:
            continue
        doc = inspect.getdoc(obj) or ""
        assert "Implements:" in doc or "Helper:" in doc, f"{name}.{fname}: no Implements: or Helper: line"
