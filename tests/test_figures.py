"""Every figure script runs on short simulations and writes real images (the house style).

The session fixture simulates 0.5 s of each paper gait into a temporary cache (about 15 s on two
cores), so the tests need nothing but a clean clone.
"""

import dataclasses
import importlib
import inspect
import json
import os
from types import SimpleNamespace

import numpy as np
import pytest
from matplotlib import image as mpimg
from PIL import Image

from cobra_ref.reproduce import analysis
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
    runs = run_all([RunSpec(g, duration=DURATION) for g in PAPER_GAITS], cache_dir, progress=False)
    return {spec.gait: traj for spec, traj in runs.items()}


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
    """One anim_<gait>.gif per gait, several frames, well under the 2 MB budget, and the note
    animations.json (last) with one record per GIF."""
    paths = animate.make(results, str(tmp_path), cobra)
    assert sorted(os.path.basename(p) for p in paths[:-1]) == sorted(f"anim_{g}.gif" for g in PAPER_GAITS)
    assert os.path.basename(paths[-1]) == animate.NOTE
    with open(paths[-1]) as f:
        assert sorted(json.load(f)) == sorted(os.path.basename(p) for p in paths[:-1])
    for p in paths[:-1]:
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
    assert stems == set(PAPER_FIGURES) | {"anim_J", "animations"}
    for p in paths:
        if not p.endswith(".json"):
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
    function has a docstring, every module a docstring, and a ``make`` says which figure of [COBRA]
    it implements ("Implements:")."""
    module = importlib.import_module("cobra_ref.reproduce.figures" if name == "__init__" else f"cobra_ref.reproduce.figures.{name}")
    assert (module.__doc__ or "").strip(), f"{name} has no module docstring"
    for fname, obj in vars(module).items():
        if fname.startswith("_") or not inspect.isfunction(obj) or obj.__module__ != module.__name__:
            continue
        doc = inspect.getdoc(obj) or ""
        assert doc.strip(), f"{name}.{fname}: no docstring"
        if fname == "make":
            assert "Implements:" in doc, f"{name}.make: no Implements: line"


# ----------------------------------------------------------------------------- the reviewer's fixes


@pytest.fixture
def figures(monkeypatch):
    """{stem: Figure} of every figure ``common.save`` writes while the test runs."""
    saved = {}
    real_save = common.save

    def save(fig, out_dir, stem):
        saved[stem] = fig
        return real_save(fig, out_dir, stem)

    monkeypatch.setattr(common, "save", save)
    return saved


def window_extents(fig):
    """The renderer and, per axes, the window extent of its data area."""
    renderer = fig.canvas.get_renderer()
    return renderer, [ax.get_window_extent(renderer) for ax in fig.axes]


def title_texts(fig):
    """Every non-empty title text of the figure: the three title slots of each axes and the suptitle."""
    texts = [t for ax in fig.axes for t in (ax._left_title, ax.title, ax._right_title) if t.get_text()]
    return texts + ([fig._suptitle] if fig._suptitle is not None else [])


def cielab(color):
    """CIELAB (D65) of a matplotlib colour, from sRGB by the standard formulas."""
    from matplotlib.colors import to_rgb

    rgb = np.array(to_rgb(color))
    linear = np.where(rgb > 0.04045, ((rgb + 0.055) / 1.055) ** 2.4, rgb / 12.92)
    xyz = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]]) @ linear
    f = np.cbrt(xyz / np.array([0.95047, 1.0, 1.08883]))
    return np.array([116 * f[1] - 16, 500 * (f[0] - f[1]), 200 * (f[1] - f[2])])


def min_color_distance(colors):
    """The smallest CIELAB distance (Delta E 1976) between two of ``colors``."""
    lab = [cielab(c) for c in colors]
    return min(np.linalg.norm(a - b) for i, a in enumerate(lab) for b in lab[i + 1:])


def test_fig04_tells_the_twelve_bodies_apart(results, cobra, tmp_path, figures):
    """Every body's colour differs from every other's by Delta E >= 20 (clearly different at a
    glance; 12 samples of viridis, the old palette, are only ~10 apart), the timeline paints each
    body in its colour, and one legend names all 12 bodies, head to tail."""
    from matplotlib import colormaps
    from matplotlib.colors import to_rgb

    from cobra_ref.reproduce.figures import fig04_robot_contacts as fig04

    names = [n for n, _ in common.robot_bodies(cobra)]
    colors = fig04.link_colors(len(names))
    assert len(names) == 12
    assert min_color_distance(colors) >= 20.0
    assert min_color_distance([colormaps["viridis"](x) for x in np.linspace(0, 0.9, 12)]) < 20.0  # the test can fail
    fig04.make(results, str(tmp_path), cobra)
    fig = figures["fig04_robot_contacts"]
    (legend,) = fig.legends
    assert [t.get_text() for t in legend.get_texts()] == names
    timeline = np.asarray(fig.axes[0].get_images()[0].get_array())  # (bodies, steps, 4) RGBA, first gait
    idx = [i for _, i in common.robot_bodies(cobra)]
    touching = analysis.contact_forces(results[PAPER_GAITS[0]], analysis.ROBOT_GROUND, cobra.nb).in_contact[:, idx]
    assert touching.any()
    for j, color in enumerate(colors):
        expected = np.where(touching[:, j, None], to_rgb(color), 1.0)
        np.testing.assert_allclose(timeline[j, :, :3], expected, err_msg=f"timeline row of {names[j]}")


@pytest.mark.parametrize("name", PAPER_FIGURES)
def test_titles_do_not_overlap_and_are_not_cut_off(name, results, cobra, tmp_path, figures):
    """Fig. 4's column titles used to overlap and fig. 5's right title ran off the page: every title
    (left, centre, right of each axes, and the suptitle) now lies inside the figure, and no two
    overlap."""
    module = importlib.import_module(f"cobra_ref.reproduce.figures.{name}")
    module.make(results, str(tmp_path), cobra)
    fig = figures[name]
    renderer, _ = window_extents(fig)
    page = fig.bbox
    boxes = [(t.get_text(), t.get_window_extent(renderer)) for t in title_texts(fig)]
    for text, box in boxes:
        assert page.x0 <= box.x0 and box.x1 <= page.x1 and page.y0 <= box.y0 and box.y1 <= page.y1, \
            f"{name}: title {text!r} is cut off: {box} outside {page}"
    for i, (a, box_a) in enumerate(boxes):
        for b, box_b in boxes[i + 1:]:
            assert not box_a.overlaps(box_b), f"{name}: titles {a!r} and {b!r} overlap"


@pytest.mark.parametrize("name, columns", (("fig04_robot_contacts", (1, 2)), ("fig05_box_contacts", (0, 1)),
                                           ("fig07_power", (0,)), ("fig08_torques", (0, 1))))
def test_gaits_share_one_y_scale(name, columns, results, cobra, tmp_path, figures):
    """The paper compares the gaits ("the large peaks in instantaneous power from sidewinding"): in
    each column of figs. 4, 5, 7 and 8 every gait's panel has the same y range (fig. 8: both
    joints too), although the gaits' values differ: C's torques and contact forces are made 10
    times larger (beyond the +-1.3 tau_max that fig. 8 always shows, and beyond the box's weight
    that the box-ground forces of fig. 5 are in the first 0.5 s)."""
    module = importlib.import_module(f"cobra_ref.reproduce.figures.{name}")
    c = results["C"]
    forces = {**c.contacts, "contact_force": 10.0 * c.contacts["contact_force"]}
    larger = dataclasses.replace(c, tau=10.0 * c.tau, contacts=forces)
    module.make({**results, "C": larger}, str(tmp_path), cobra)
    fig = figures[name]
    n_cols = len(fig.axes) // len(PAPER_GAITS)
    grid = np.array(fig.axes[: n_cols * len(PAPER_GAITS)]).reshape(len(PAPER_GAITS), n_cols)
    ranges = {c: {tuple(ax.get_ylim()) for ax in grid[:, c]} for c in columns}
    for c, distinct in ranges.items():
        assert len(distinct) == 1, f"{name}, column {c}: y ranges {distinct}"
    if name == "fig08_torques":
        assert ranges[0] == ranges[1]


def test_fig09_bar_labels_are_in_the_axis_unit_without_powers_of_ten(results, cobra, tmp_path, figures):
    """The bar labels read "1.55 m" or "6.92 mm", in the unit of the axis they stand on, never
    "2.2e+03 mm", with three significant digits of the largest, and parse back to the bar's height
    within half a unit of their last digit; for values from 1e-4 to 1e3."""
    from cobra_ref.reproduce.figures import fig09_box_distance as fig09

    for largest in (1e-4, 3e-3, 0.05, 0.33, 2.56, 42.0, 999.0):
        values = [largest, 0.31 * largest, 0.0]
        labels = fig09.distance_labels(values, "m")
        for label, d in zip(labels, values):
            assert "e" not in label and label.endswith(" m"), label
            number = label[:-2]
            decimals = len(number.split(".")[1]) if "." in number else 0
            assert abs(float(number) - d) <= 0.5 * 10.0 ** -decimals + 1e-12, (label, d)
        assert len(labels[0][:-2].replace(".", "").lstrip("0")) == 3, labels[0]  # 3 significant digits
    for pushed, expected_unit in ((0.0069, "mm"), (1.55, "m")):  # the box of C moved this far along x
        pose = results["C"].box_pose.copy()
        pose[:, 0] += np.linspace(0.0, pushed, len(pose))
        fig09.make({**results, "C": dataclasses.replace(results["C"], box_pose=pose)}, str(tmp_path), cobra)
        fig = figures["fig09_box_distance"]
        ax_bar = fig.axes[1]
        unit = ax_bar.get_ylabel().rsplit("[", 1)[1].rstrip("]")
        assert unit == expected_unit
        renderer, areas = window_extents(fig)
        bar_area = areas[1]
        assert len(ax_bar.texts) == 2 * len(PAPER_GAITS)  # net displacement and path length
        for text, bar in zip(ax_bar.texts, ax_bar.patches):
            number, label_unit = text.get_text().split(" ")
            assert "e" not in number and label_unit == unit, text.get_text()
            decimals = len(number.split(".")[1]) if "." in number else 0
            assert float(number) == pytest.approx(bar.get_height(), abs=0.5 * 10.0 ** -decimals)
            assert text.get_window_extent(renderer).y1 <= bar_area.y1, f"{text.get_text()} runs off the axes"


def test_fig03_j_mirror_is_the_mirror_image_of_j(results, cobra, tmp_path, figures):
    """J-mirror is J reflected about the start heading (y -> -y); on fig. 3's common axes (x to the
    right in both panels) its box path is J's reflected, and so is every face of its snapshots."""
    from cobra_ref.reproduce.figures import fig03_snapshots

    np.testing.assert_allclose(results["J-mirror"].box_pose[:, 1], -results["J"].box_pose[:, 1], atol=1e-9)
    fig03_snapshots.make({g: results[g] for g in ("J", "J-mirror")}, str(tmp_path), cobra)
    ax_j, ax_m = figures["fig03_snapshots"].axes[:2]
    assert ax_j.get_title(loc="left") == "J" and ax_m.get_title(loc="left") == "J-mirror"
    assert ax_m.get_xlim() == ax_j.get_xlim() and ax_m.get_xlim()[0] < ax_m.get_xlim()[1]
    path_j, path_m = ax_j.get_lines()[0].get_xydata(), ax_m.get_lines()[0].get_xydata()
    np.testing.assert_allclose(path_m, path_j * [1.0, -1.0], atol=1e-9)
    # each snapshot's extent, reflected (up to the facets of the cylinders, which a reflection turns)
    assert len(ax_j.collections) == len(ax_m.collections) == fig03_snapshots.N_INSTANTS
    for faces_j, faces_m in zip(ax_j.collections, ax_m.collections):
        xy_j, xy_m = (np.concatenate([p.vertices for p in c.get_paths()]) for c in (faces_j, faces_m))
        np.testing.assert_allclose([xy_m[:, 0].min(), xy_m[:, 0].max()], [xy_j[:, 0].min(), xy_j[:, 0].max()], atol=3e-3)
        np.testing.assert_allclose([xy_m[:, 1].min(), xy_m[:, 1].max()], [-xy_j[:, 1].max(), -xy_j[:, 1].min()], atol=3e-3)


def truncated(traj, n_steps):
    """The first ``n_steps`` steps of a trajectory (states 0..n_steps, the contact rows of those steps)."""
    rows = traj.contacts["contact_step"] < n_steps
    return dataclasses.replace(traj, t=traj.t[: n_steps + 1], q=traj.q[: n_steps + 1], qd=traj.qd[: n_steps + 1],
                               tau=traj.tau[:n_steps], box_pose=traj.box_pose[: n_steps + 1],
                               steps={k: v[:n_steps] for k, v in traj.steps.items()},
                               contacts={k: v[rows] for k, v in traj.contacts.items()})


N_MEMBERS = 8


@pytest.fixture(scope="module")
def ensemble(results):
    """A made-up ensemble of N_MEMBERS per gait: member 0 is the summary of the nominal run, member
    i the summary of the run cut 5 i steps short (small changes of every number). The 0.5 s runs
    never reach the box, so the slopes are made up: 2 + 0.1 i J/J, and member 3 of sidewinding
    did no work on the box (an infinite slope)."""
    out = {}
    for gait, traj in results.items():
        members = [analysis.summary(truncated(traj, len(traj.tau) - 5 * i)) for i in range(N_MEMBERS)]
        for i, m in enumerate(members):
            m["efficiency_slope"] = float("inf") if (gait, i) == ("sidewinding", 3) else 2.0 + 0.1 * i
        out[gait] = members
    return out


def by_gid(fig, prefix):
    """{gait: artist} of the artists whose gid is "<prefix>:<gait>"."""
    found = fig.findobj(lambda a: (a.get_gid() or "").startswith(prefix + ":"))
    return {a.get_gid().split(":", 1)[1]: a for a in found}


def hand_quantile(values, q):
    """The q-quantile of ``values`` by hand: rank r = q (n - 1) in the sorted values, linear between
    its neighbours."""
    s = sorted(values)
    r = q * (len(s) - 1)
    i = int(np.floor(r))
    return s[i] + (r - i) * (s[min(i + 1, len(s) - 1)] - s[i])


@pytest.mark.parametrize("name, key", (("fig06_work_efficiency", "efficiency_slope"),
                                       ("fig09_box_distance", "box_distance")))
def test_ensemble_draws_one_marker_per_member_and_its_range(name, key, results, ensemble, cobra, tmp_path, figures):
    """With ``ensemble``, figs. 6 (the slope) and 9 (the final distance) draw, per gait, one dot per
    member at the member's value (a member without a finite value is left out and counted) and a
    bar from the 10th to the 90th percentile of the members; without it, none of that is drawn."""
    module = importlib.import_module(f"cobra_ref.reproduce.figures.{name}")
    module.make(results, str(tmp_path), cobra, ensemble=ensemble)
    fig = figures[name]
    dots, bars = by_gid(fig, common.MEMBERS_GID), by_gid(fig, common.RANGE_GID)
    assert sorted(dots) == sorted(bars) == sorted(PAPER_GAITS)
    for gait in PAPER_GAITS:
        values = [m[key] for m in ensemble[gait] if np.isfinite(m[key])]
        left_out = (gait, key) == ("sidewinding", "efficiency_slope")
        assert len(dots[gait].get_ydata()) == len(values) == N_MEMBERS - left_out
        np.testing.assert_allclose(dots[gait].get_ydata(), values, err_msg=gait)
        np.testing.assert_allclose(bars[gait].get_ydata(), [hand_quantile(values, 0.1), hand_quantile(values, 0.9)])
    if name == "fig06_work_efficiency":
        from cobra_ref.reproduce.figures import fig06_work_efficiency

        ticks = [t.get_text() for t in fig.axes[1].get_xticklabels()]
        assert "1 no push" in ticks[PAPER_GAITS.index("sidewinding")]
    figures.clear()
    module.make(results, str(tmp_path), cobra)
    assert not by_gid(figures[name], common.MEMBERS_GID) and not by_gid(figures[name], common.RANGE_GID)


def test_every_make_takes_an_ensemble(results, ensemble, cobra, tmp_path):
    """Every module's ``make`` has the keyword ``ensemble=None``; make_all passes one to all of them
    (the figures other than 6 and 9 draw the nominal runs only)."""
    for name in FIGURES:
        module = importlib.import_module(f"cobra_ref.reproduce.figures.{name}")
        assert inspect.signature(module.make).parameters["ensemble"].default is None, name
    paths = make_all({"J": results["J"]}, str(tmp_path), cobra, animations=False, ensemble={"J": ensemble["J"]})
    assert len(paths) == 2 * len(PAPER_FIGURES)


def test_fig07_and_fig08_report_the_99th_percentile_beside_the_peak(results, cobra, tmp_path, figures):
    """The numbers above each panel are the 99th percentile and the peak of |P|_loc (fig. 7) and of
    the largest |tau_j| per step of the panel's joints (fig. 8: pitch, yaw), each as
    analysis.percentile_99 and max give them, p99 <= peak."""
    from cobra_ref.reproduce.figures import fig07_power, fig08_torques

    fig07_power.make(results, str(tmp_path), cobra)
    fig08_torques.make(results, str(tmp_path), cobra)
    for r, gait in enumerate(PAPER_GAITS):
        P_abs = analysis.locomotion_power(results[gait])[1]
        note = figures["fig07_power"].axes[r]._right_title.get_text()
        assert f"p99 {np.percentile(P_abs, 99):.3g}," in note and f"peak {P_abs.max():.3g} W" in note
        for c, joints in enumerate(fig08_torques.joints_by_axis(cobra).values()):
            columns = [fig08_torques.tau_column(cobra, j) for j in joints]
            tau = np.abs(results[gait].tau[:, columns]).max(axis=1)
            note = figures["fig08_torques"].axes[2 * r + c]._right_title.get_text()
            assert f"p99 {np.percentile(tau, 99):.3g}," in note and f"peak {tau.max():.3g} N m" in note
            assert np.percentile(tau, 99) <= tau.max()


# ----------------------------------------------------------------------------- animations


def test_animations_use_mujoco_when_it_renders_and_say_so(results, cobra, tmp_path, capsys):
    """Where an OpenGL backend renders, every GIF is MuJoCo's: the note and stderr say so, and the
    frames are one per 1 / GIF_FPS s of GIF (a 0.5 s run plays in real time: 6 frames)."""
    from cobra_ref.viz import render

    if render.choose_gl()["gl"] is None:
        pytest.skip(f"no OpenGL backend for MuJoCo here: {render.choose_gl()['tried']}")
    runs = {g: results[g] for g in ("J", "J-mirror")}
    paths = animate.make(runs, str(tmp_path), cobra)
    with open(paths[-1]) as f:
        note = json.load(f)
    err = capsys.readouterr().err
    for gait in runs:
        record = note[f"anim_{gait}.gif"]
        assert record["renderer"] == "mujoco" and record["fallback_reason"] is None and record["speed"] == 1.0
        assert record["frames"] == int(DURATION * animate.GIF_FPS) + 1
        assert (record["width"], record["height"]) == animate.GIF_SIZE
        assert f"anim_{gait}.gif: mujoco" in err
        with Image.open(tmp_path / f"anim_{gait}.gif") as im:
            assert im.n_frames == record["frames"] and im.size == animate.GIF_SIZE


def test_animations_fall_back_to_matplotlib_and_say_why(results, cobra, tmp_path, capsys, monkeypatch):
    """Without a working OpenGL backend (or when the MuJoCo rendering fails), the GIF is the
    matplotlib drawing; the note and stderr name the renderer and the reason."""
    from cobra_ref.viz import render

    monkeypatch.setattr(render, "choose_gl", lambda refresh=False: {"gl": None, "process": None,
                                                                      "tried": {"egl": "no EGL here (test)"}})
    paths = animate.make({"S": results["S"]}, str(tmp_path / "no_gl"), cobra)
    monkeypatch.setattr(render, "choose_gl", lambda refresh=False: {"gl": "egl", "process": "this", "tried": {}})

    def broken(*args, **kwargs):
        raise render.RenderError("the GL context died (test)")

    monkeypatch.setattr(render, "render_gif", broken)
    paths += animate.make({"S": results["S"]}, str(tmp_path / "failed"), cobra)
    err = capsys.readouterr().err
    for note_path, reason in ((paths[1], "no EGL here (test)"), (paths[3], "the GL context died (test)")):
        with open(note_path) as f:
            record = json.load(f)["anim_S.gif"]
        assert record["renderer"] == "matplotlib" and reason in record["fallback_reason"]
        assert record["frames"] == len(animate.frame_steps(results["S"]))
        assert reason in err
    assert err.count("anim_S.gif: matplotlib") == 2
    assert_real_image(paths[0])
    assert_real_image(paths[2])


def test_a_long_run_plays_faster_than_real_time_in_gif_seconds():
    """A 10 s run plays in GIF_SECONDS at GIF_FPS (GIF_SECONDS * GIF_FPS + 1 frames, a fraction of a
    30 fps real-time render's 301); a run up to GIF_SECONDS long plays in real time."""
    from cobra_ref.viz import scene

    for duration in (10.0, animate.GIF_SECONDS, 0.5):
        t = np.linspace(0.0, duration, int(round(duration / 1e-3)) + 1)
        traj = SimpleNamespace(t=t, duration=duration)
        speed = animate.playback_speed(traj)
        frames = scene.frame_times(traj, animate.GIF_FPS, speed)
        assert speed == pytest.approx(max(1.0, duration / animate.GIF_SECONDS))
        assert frames[0] == 0.0 and frames[-1] == pytest.approx(duration)
        assert len(frames) == round(min(duration, animate.GIF_SECONDS) * animate.GIF_FPS) + 1


def test_a_child_process_renders_the_same_animation(results, cobra, tmp_path, monkeypatch):
    """The path taken when mujoco was imported here with a backend that cannot render: the GIF is
    rendered by a fresh process, with the same title and the same multisampling setting, so its
    frames equal this process's (same OpenGL; a GIF palette entry may differ for a pixel that
    differs by one level, so 0.1 % of the pixels may differ; without the title and with
    multisampling, 1.6 % do)."""
    from cobra_ref.viz import render

    choice = render.choose_gl()
    if choice["gl"] is None:
        pytest.skip(f"no OpenGL backend for MuJoCo here: {choice['tried']}")
    here = animate.make({"C": results["C"]}, str(tmp_path / "here"), cobra)[0]
    monkeypatch.setattr(render, "choose_gl", lambda refresh=False: {**choice, "process": "child"})
    child = animate.make({"C": results["C"]}, str(tmp_path / "child"), cobra)[0]
    with Image.open(here) as a, Image.open(child) as b:
        assert a.n_frames == b.n_frames
        for i in (0, a.n_frames - 1):
            a.seek(i)
            b.seek(i)
            diff = np.abs(np.asarray(a.convert("RGB"), int) - np.asarray(b.convert("RGB"), int))
            assert np.mean(diff > 8) < 1e-3, f"frame {i} differs"


@pytest.mark.parametrize("gaits", [PAPER_GAITS, ("J",)], ids=["five gaits", "one gait"])
def test_nothing_is_cut_at_the_figures_edge(gaits, results, ensemble, cobra, tmp_path):
    """Every paper figure, drawn for the five gaits with their ensembles and for one gait alone, has
    no ink on its outermost two pixels: a title, label or legend cut by the page's edge would leave
    some there (a legend wider than the page, for instance)."""
    paths = make_all({g: results[g] for g in gaits}, str(tmp_path), cobra, animations=False,
                     ensemble={g: ensemble[g] for g in gaits})
    for path in [p for p in paths if p.endswith(".png")]:
        grey = np.asarray(Image.open(path).convert("L"))
        border = np.concatenate([grey[:2].ravel(), grey[-2:].ravel(), grey[:, :2].ravel(), grey[:, -2:].ravel()])
        assert (border < 200).sum() == 0, f"{os.path.basename(path)}: {(border < 200).sum()} dark pixels on the edge"


def test_a_smoke_run_marks_each_figure_and_writes_the_png_only(tmp_path):
    """Inside ``common.smoke_run(note)`` (``cobra-ref figures --quick``) the note is the title's first
    line and only the PNG is written; outside it, the title is untouched and both files are written."""
    fig = common.new_figure(common.ONE_COLUMN, 2.0)
    fig.subplots().plot([0, 1], [0, 1])
    fig.suptitle("Instantaneous locomotion power")
    with common.smoke_run("SMOKE RUN: not the paper's results"):
        paths = common.save(fig, str(tmp_path / "smoke"), "f")
    assert [os.path.basename(p) for p in paths] == ["f.png"] and os.listdir(tmp_path / "smoke") == ["f.png"]
    assert fig._suptitle.get_text() == "SMOKE RUN: not the paper's results\nInstantaneous locomotion power"
    plain = common.new_figure(common.ONE_COLUMN, 2.0)
    plain.suptitle("power")
    assert [os.path.basename(p) for p in common.save(plain, str(tmp_path / "full"), "f")] == ["f.png", "f.pdf"]
    assert plain._suptitle.get_text() == "power"
