"""The figures read back: what each figure plots, as a referee would check it on the page.

Every test draws a figure from short runs (0.1 s of each paper gait, C's 0.5 s, at dt = 2 ms,
simulated into a temporary cache) or from made-up data, and reads the matplotlib artists back:
the lines' data and styles, the axes' limits, the labels and titles. Each fails on the figures
before they were fixed (the issue's list of figure defects).
"""

import dataclasses
import importlib

import numpy as np
import pytest

from cobra_ref.contact import BOX_GROUND, ROBOT_BOX
from cobra_ref.reproduce import analysis
from cobra_ref.reproduce.figures import common
from cobra_ref.reproduce.runs import PAPER_GAITS, RunSpec, run_all


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """{gait: Trajectory} of 0.1 s runs of the paper gaits at dt = 2 ms, C's 0.5 s (250 steps: enough
    that a one-step spike stands out of the 99.5th percentile)."""
    cache = str(tmp_path_factory.mktemp("cache"))
    specs = [RunSpec(g, duration=0.5 if g == "C" else 0.1, dt=0.002) for g in PAPER_GAITS]
    out = run_all(specs, cache, progress=False)
    return {spec.gait: traj for spec, traj in out.items()}


@pytest.fixture
def drawn(monkeypatch):
    """{stem: Figure} of every figure ``common.save`` is given while the test runs (nothing written)."""
    saved = {}
    monkeypatch.setattr(common, "save", lambda fig, out_dir, stem: saved.setdefault(stem, fig) and [])
    return saved


def draw(name, results, model, drawn, **kwargs):
    """The Figure of module ``name`` drawn from ``results``."""
    importlib.import_module(f"cobra_ref.reproduce.figures.{name}").make(results, "unused", model, **kwargs)
    return drawn[name]


def spiked(traj, factor=50.0):
    """``traj`` with one step's joint torques (where the joints move most: a power spike too) and
    one step's contact forces multiplied by ``factor``."""
    rates = np.abs(traj.qd[1:, 6:17] + traj.qd[:-1, 6:17]).sum(axis=1)
    tau = traj.tau.copy()
    tau[int(np.argmax(rates))] *= factor
    c = dict(traj.contacts)
    rows = c["contact_step"] == c["contact_step"][len(c["contact_step"]) // 2]
    c["contact_force"] = np.where(rows[:, None], factor * c["contact_force"], c["contact_force"])
    return dataclasses.replace(traj, tau=tau, contacts=c)


def data_lines(ax):
    """The lines of ``ax`` that carry data (not the horizontal reference lines, which span the axes)."""
    return [ln for ln in ax.get_lines() if ln.get_transform() == ax.transData and len(ln.get_xdata()) > 1]


@pytest.mark.parametrize("name", ("fig04_robot_contacts", "fig05_box_contacts", "fig07_power", "fig08_torques"))
def test_the_y_limits_hold_every_plotted_peak(name, runs, cobra, drawn, monkeypatch):
    """With a spike 50 times a step's torques and contact forces in one gait (forces drawn per
    step, not as 20 ms means), every panel's y range holds every value it plots: the peak a claim
    is about (sidewinding's power peaks, PP) is on the page, not only in a note."""
    monkeypatch.setattr(common, "window_mean", lambda t, y, window=None: (t, y))
    fig = draw(name, {**runs, "C": spiked(runs["C"])}, cobra, drawn)
    checked = 0
    for ax in fig.axes:
        for line in data_lines(ax):
            y = np.asarray(line.get_ydata(), dtype=float)
            lo, hi = ax.get_ylim()
            assert lo <= y.min() and y.max() <= hi, f"{name}: {y.min():.3g}..{y.max():.3g} outside {lo:.3g}..{hi:.3g}"
            checked += 1
    assert checked >= len(PAPER_GAITS)


def coinciding_pairs(ax):
    """Pairs of data lines of ``ax`` whose data are the same (to 1e-9 of their scale)."""
    lines = [ln for ln in data_lines(ax) if not (ln.get_gid() or "").startswith(common.MEMBERS_GID)]
    pairs = []
    for i, a in enumerate(lines):
        for b in lines[i + 1:]:
            xa, xb = a.get_xydata(), b.get_xydata()
            if xa.shape == xb.shape and np.allclose(xa, xb, rtol=0, atol=1e-9 * (1 + np.abs(xa).max())):
                pairs.append((a, b))
    return pairs


def style(line):
    """(line style, dash pattern, marker): custom dash patterns all report the linestyle "--"."""
    offset, dashes = line._unscaled_dash_pattern
    return line.get_linestyle(), tuple(dashes or ()), line.get_marker()


def all_texts(fig):
    """Every text of the figure (titles, labels, legends) as one string."""
    return " ".join(t.get_text() for t in fig.findobj(lambda a: hasattr(a, "get_text")))


@pytest.mark.parametrize("name", ("fig06_work_efficiency", "fig09_box_distance"))
def test_no_gait_hides_another(name, runs, cobra, drawn):
    """J-mirror's work and box distance are J's (it is J's mirror image): where the two lines
    coincide they differ in line style or marker, not only in colour (one drawn exactly over
    the other hides it whatever its colour), and the figure says that they coincide."""
    assert np.allclose(analysis.box_distance(runs["J"]), analysis.box_distance(runs["J-mirror"]), atol=1e-12)
    fig = draw(name, runs, cobra, drawn)
    pairs = [p for ax in fig.axes for p in coinciding_pairs(ax)]
    assert pairs, f"{name}: J's and J-mirror's lines should coincide"
    for a, b in pairs:
        assert style(a) != style(b), f"{name}: two coinciding lines drawn alike, {style(a)}"
    assert common.MIRROR_NOTE in all_texts(fig)


def test_the_optimization_figure_tells_j_mirror_from_j(cobra, drawn, tmp_path):
    """The optimization figure: J-mirror's costs are J's, its box path J's reflected; its cost line
    and dots are drawn in another line style and marker, and the title says that they coincide
    (only when they do)."""
    from cobra_ref.reproduce.figures import fig_optimization

    history = [{"cost": c, "box_final": [0.1 * c, 0.0]} for c in (3.0, 2.0, 2.5, 1.0)]
    box_xy = np.array([[0.0, 0.0], [0.1, -0.05], [0.2, -0.1]])
    runs = [{"label": g, "gait": g, "box_xy": box_xy * [1.0, sign],
             "record": {"history": history, "settings": {"goal_world": [0.3, -0.1 * sign]}}}
            for g, sign in (("J", 1.0), ("J-mirror", -1.0))]
    fig_optimization.make(runs, str(tmp_path), "optimization", "title")
    fig = drawn["optimization"]
    pairs = coinciding_pairs(fig.axes[0])
    assert len(pairs) == 2  # the rollouts' dots and the best-so-far lines
    assert all(style(a) != style(b) for a, b in pairs)
    assert common.MIRROR_NOTE in fig._suptitle.get_text()
    # two optimizations of their own (fig_directions: J ahead, J-mirror to the left) do not coincide
    runs[1]["record"] = {**runs[1]["record"], "history": [{**h, "cost": 2 * h["cost"]} for h in history]}
    fig_optimization.make(runs, str(tmp_path), "directions", "title")
    assert common.MIRROR_NOTE not in drawn["directions"]._suptitle.get_text()


def test_fig03_gaits_share_one_top_view_with_their_goals(runs, cobra, drawn):
    """Fig. 3: every gait's panel has the same x and y limits at equal scale, x increasing to the
    right (J-mirror's too), and each gait's goal (relative to the box's start) is marked."""
    goals = {"C": (0.16, -0.03), "J": (0.31, -0.05), "J-mirror": (0.31, 0.05)}
    fig = draw("fig03_snapshots", runs, cobra, drawn, goals=goals)
    panels = [ax for ax in fig.axes if ax.get_title(loc="left") in PAPER_GAITS]
    assert [ax.get_title(loc="left") for ax in panels] == list(PAPER_GAITS)
    assert len({ax.get_xlim() for ax in panels}) == 1 and len({ax.get_ylim() for ax in panels}) == 1
    x0, x1 = panels[0].get_xlim()
    assert x0 < x1 and all(ax.get_aspect() == 1.0 for ax in panels)
    for ax in panels:
        gait = ax.get_title(loc="left")
        stars = [ln for ln in ax.get_lines() if ln.get_gid() == f"goal:{gait}"]
        if gait not in goals:
            assert not stars
            continue
        (star,) = stars
        expected = runs[gait].box_pose[0, :2] + goals[gait]
        np.testing.assert_allclose(star.get_xydata()[0], expected)


def test_fig08_draws_every_joint_with_its_phase_lag(runs, cobra, drawn, monkeypatch):
    """Fig. 8: per gait, one line per joint (11: pitch joints left, yaw joints right), each joint's
    legend entry with its phase lag behind J0 as analysis.joint_phase_correlation gives it."""
    from cobra_ref.reproduce.figures import fig08_torques

    lags = [0.0, 0.26, -0.05, 0.16, float("nan"), 0.08, -0.18, -0.01, -0.26, -0.06, -0.27]
    monkeypatch.setattr(fig08_torques, "joint_phase_correlation", lambda traj: ([1.0] * 11, lags))
    fig = draw("fig08_torques", runs, cobra, drawn)
    grid = np.array(fig.axes).reshape(len(PAPER_GAITS), 2)
    for r, gait in enumerate(PAPER_GAITS):
        labels = [ln.get_label() for ax in grid[r] for ln in data_lines(ax)]
        assert len(labels) == 11, gait
        assert sorted(labels) == sorted(["J0 (reference)", "J1 +0.26 T", "J2 -0.05 T", "J3 +0.16 T", "J4 lag n/a",
                                         "J5 +0.08 T", "J6 -0.18 T", "J7 -0.01 T", "J8 -0.26 T", "J9 -0.06 T",
                                         "J10 -0.27 T"])
        tau = {ln.get_label().split()[0]: ln for ax in grid[r] for ln in data_lines(ax)}
        column = fig08_torques.tau_column(cobra, "J3")
        np.testing.assert_allclose(tau["J3"].get_ydata(), runs[gait].tau[:, column])


def test_fig09_names_what_it_plots(runs, cobra, drawn):
    """Fig. 9 plots the net displacement |x_box(t) - x_box(0)| and the path length sum |dx_box|,
    and every label says which: the time panel's axis, the bars' legend and the title."""
    from cobra_ref.reproduce.figures import fig09_box_distance as fig09

    pose = runs["C"].box_pose.copy()
    pose[:, 0] += 0.2 * np.sin(np.linspace(0.0, np.pi, len(pose)))  # out and back: net 0, path 0.4 m
    results = {**runs, "C": dataclasses.replace(runs["C"], box_pose=pose)}
    fig = draw("fig09_box_distance", results, cobra, drawn)
    ax_t, ax_bar = fig.axes[:2]
    assert "net displacement" in ax_t.get_ylabel()
    assert [t.get_text() for t in ax_bar.get_legend().get_texts()] == ["net displacement", "path length"]
    assert "net displacement" in fig._suptitle.get_text() and "path length" in fig._suptitle.get_text()
    net, path = ax_bar.containers[0], ax_bar.containers[1]
    c = PAPER_GAITS.index("C")
    hand_net = np.linalg.norm(pose[-1, :2] - pose[0, :2])
    hand_path = np.sum(np.linalg.norm(np.diff(pose[:, :2], axis=0), axis=1))
    assert net[c].get_height() == pytest.approx(hand_net, abs=1e-9)
    assert path[c].get_height() == pytest.approx(hand_path, rel=1e-9) and hand_path > 0.39


def made_up_ensemble(runs):
    """Two members per gait: the run's summary, and it with 10 % more of everything."""
    out = {}
    for gait, traj in runs.items():
        s = analysis.summary(traj)
        s["efficiency_slope"], s["duration"] = 2.0, 0.06
        out[gait] = [s, {**s, "efficiency_slope": 2.2, "box_distance": 1.1 * s["box_distance"]}]
    return out


@pytest.mark.parametrize("name", ("fig06_work_efficiency", "fig09_box_distance"))
def test_members_and_the_nominal_runs_never_share_an_axis(name, runs, cobra, drawn, monkeypatch):
    """The ensemble's members (their own, shorter window) are on an axes of their own: the axes
    that holds their dots holds nothing of the nominal runs (no bar, no curve, no nominal marker;
    the nominal runs given a finite slope of 2, as if they had pushed the box)."""
    from cobra_ref.reproduce.figures import fig06_work_efficiency

    monkeypatch.setattr(fig06_work_efficiency, "efficiency_fit", lambda traj: (2.0, 0.0))
    fig = draw(name, runs, cobra, drawn, ensemble=made_up_ensemble(runs))
    holders = [ax for ax in fig.axes
               if any((ln.get_gid() or "").startswith(common.MEMBERS_GID) for ln in ax.get_lines())]
    assert len(holders) == 1
    (ax,) = holders
    assert not ax.patches, f"{name}: bars beside the members"
    others = [ln.get_gid() for ln in ax.get_lines()
              if not (ln.get_gid() or "").startswith((common.MEMBERS_GID, common.RANGE_GID))]
    assert not others, f"{name}: {others} beside the members"
    assert "0.06 s" in all_texts(fig)  # the members' window is named


def contact_log(rows):
    """A contact log of ``rows`` = [(step, kind, body, point, normal force)], normals along +z."""
    rows = list(rows)
    n = len(rows)
    return {"contact_step": np.array([r[0] for r in rows]), "contact_kind": np.array([r[1] for r in rows]),
            "contact_body": np.array([r[2] for r in rows]), "contact_point": np.array([r[3] for r in rows], float),
            "contact_normal": np.tile([0.0, 0.0, 1.0], (n, 1)),
            "contact_force": np.array([[0.0, 0.0, r[4]] for r in rows], float),
            "contact_onset_speed": np.zeros(n), "contact_gap": np.zeros(n), "contact_gap_end": np.zeros(n)}


def test_fig05_says_how_hard_the_box_presses_the_ground(runs, cobra, drawn):
    """Fig. 5's title gives the mean box-ground normal force over the steps in which a link pushes
    the box, in units of the box's weight: 3.0 for a box pressed with 3 m g while pushed (its
    weight alone before), from the contact log."""
    traj = runs["C"]
    box = common.box_body(cobra)
    weight = -cobra.mass[box] * cobra.gravity[2]
    n = len(traj.tau)
    log = [(k, BOX_GROUND, box, traj.box_pose[k, :3], weight * (3.0 if k >= n // 2 else 1.0)) for k in range(n)]
    log += [(k, ROBOT_BOX, 5, traj.box_pose[k, :3], 10.0) for k in range(n // 2, n)]
    fig = draw("fig05_box_contacts", {"C": dataclasses.replace(traj, contacts=contact_log(log))}, cobra, drawn)
    assert "C 3.0" in all_texts(fig) and "A22" in all_texts(fig)


def test_fig04_names_the_bodies_that_never_touch_the_ground(runs, cobra, drawn):
    """Fig. 4's title names, per gait, the bodies without any robot-ground row in the contact log."""
    from cobra_ref.reproduce.figures import fig04_robot_contacts as fig04

    fig = draw("fig04_robot_contacts", runs, cobra, drawn)
    title = fig._suptitle.get_text().replace("\n", " ")
    for gait, traj in runs.items():
        touched = set(traj.contacts["contact_body"][traj.contacts["contact_kind"] == 0].astype(int))
        lifted = [n for n, i in common.robot_bodies(cobra) if i not in touched]
        assert f"{gait}: {fig04.name_ranges(lifted, [n for n, _ in common.robot_bodies(cobra)]) or 'none'}" in title
    assert fig04.name_ranges(["head", "L8", "L9", "L10"], ["head"] + [f"L{i}" for i in range(1, 11)]) == "head, L8-L10"


@pytest.mark.parametrize("point, face", [((0.0, -1.0, 0.0), "-y"), ((1.0, 0.0, 0.0), "+x"), ((0.0, 1.0, 0.0), "+y"),
                                         ((-1.0, 0.0, 0.0), "-x"), ((0.0, 0.0, 1.0), "top"),
                                         ((0.0, 0.0, -1.0), "bottom"), ((1.0, 1.0, -1.0), "bottom")])
def test_a_contact_point_lands_on_its_face_of_the_unfolded_box(point, face, cobra, drawn):
    """A point at the centre of a face of the box (a corner: the bottom, where the box-ground
    contacts are) lands inside that face's outline on the unfolded box, named as the face."""
    from cobra_ref.reproduce.figures import fig_contact_points as fcp
    from matplotlib.figure import Figure

    half = np.asarray(cobra.boxes[0].half, dtype=float)
    ax = Figure().add_subplot()
    fcp.draw_box_net(ax, half)
    uv = fcp.face_coordinates(np.array([point]) * half, half)[0]
    inside = [t.get_text() for t, rect in zip(ax.texts, ax.patches)
              if rect.get_bbox().x0 - 1e-12 <= uv[0] <= rect.get_bbox().x1 + 1e-12
              and rect.get_bbox().y0 - 1e-12 <= uv[1] <= rect.get_bbox().y1 + 1e-12]
    assert face in inside


def test_the_contact_points_are_the_logs(runs, cobra, drawn):
    """The ground panel's points are the robot-ground rows' points (every STRIDE-th step)."""
    from cobra_ref.reproduce.figures import fig_contact_points as fcp

    fig = draw("fig_contact_points", runs, cobra, drawn)
    c = runs["S"].contacts
    keep = (c["contact_kind"] == 0) & (c["contact_step"] % fcp.STRIDE == 0)
    ax = fig.axes[PAPER_GAITS.index("S")]
    np.testing.assert_allclose(ax.collections[0].get_offsets(), c["contact_point"][keep, :2])


def test_the_figure_command_marks_each_optimums_goal_on_fig03(runs, cobra, drawn, tmp_path, monkeypatch):
    """``regenerate`` hands fig. 3 the goal of each params JSON (``settings.goal``, relative to the
    box's start; ``goal_offsets``), which it marks; a JSON without a goal gives none."""
    import json
    from types import SimpleNamespace

    from cobra_ref.reproduce import figures, regenerate

    (tmp_path / "J.json").write_text(json.dumps({"settings": {"goal": [0.3, -0.4]}}))
    (tmp_path / "C.json").write_text(json.dumps({"settings": {}}))
    files = {g: str(tmp_path / f"{g}.json") for g in ("J", "C")}
    assert regenerate.goal_offsets(files) == {"J": [0.3, -0.4]}
    monkeypatch.setattr(figures, "FIGURES", ("fig03_snapshots",))
    job = SimpleNamespace(every=[], window=0.1, out_dir=str(tmp_path), options=SimpleNamespace(force=True),
                          progress=False, files_opt=files)
    regenerate._paper_figures(job, {g: runs[g] for g in ("J", "C")}, {})
    (star,) = drawn["fig03_snapshots"].findobj(lambda a: a.get_gid() == "goal:J")
    np.testing.assert_allclose(star.get_xydata()[0], runs["J"].box_pose[0, :2] + [0.3, -0.4])
    assert not drawn["fig03_snapshots"].findobj(lambda a: a.get_gid() == "goal:C")
