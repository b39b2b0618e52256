"""`cobra-ref figures --quick`: the outputs exist, the claims' numbers are computed (one is
recomputed here by hand from the cached NPZ), the cache is reused, and bad input is refused."""

import glob
import json
import os

import numpy as np
import pytest

from cobra_ref.cli import main
from cobra_ref.reproduce.claims import paper_claims
from cobra_ref.quaternion import quat_to_rot
from cobra_ref.simulate import Trajectory


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    """One quick regeneration (5 gaits x 1 s at their default parameters on both cores, figures,
    claims; no MuJoCo here: tests/test_mujoco_rollout.py covers it, and the optimization figure is
    tested in tests/test_shooting.py)."""
    out = str(tmp_path_factory.mktemp("figures"))
    assert main(["figures", "--quick", "--no-mujoco", "--defaults", "--quiet", "--out", out]) == 0
    return out


def test_every_output_is_written(quick_run):
    names = [f"fig0{i}_{s}" for i, s in zip(range(3, 10), ("snapshots", "robot_contacts", "box_contacts",
                                                              "work_efficiency", "power", "torques", "box_distance"))]
    for name in names:
        for ext, magic in ((".png", b"\x89PNG"), (".pdf", b"%PDF")):
            with open(os.path.join(quick_run, name + ext), "rb") as f:
                assert f.read(4) == magic, name + ext
    for gait in ("C", "S", "J", "J-mirror", "sidewinding"):
        with open(os.path.join(quick_run, f"anim_{gait}.gif"), "rb") as f:
            assert f.read(6) == b"GIF89a"
    assert not glob.glob(os.path.join(quick_run, ".tmp_*")), "a temporary file was left behind"


def test_claims_json_has_the_issue_keys(quick_run):
    with open(os.path.join(quick_run, "claims.json")) as f:
        claims = json.load(f)
    assert [c["id"] for c in claims] == ["E", "WB", "EN", "PP", "SL", "MJ"]
    for c in claims:
        assert set(c) == {"id", "claim", "values", "holds"}
        assert c["holds"] in (True, False, None)
    with open(os.path.join(quick_run, "claims.md")) as f:
        assert "| WB |" in f.read()


def test_work_on_the_box_recomputed_by_hand_from_the_npz(quick_run):
    """Claim WB's number for J, recomputed from the cached trajectory with an explicit loop:
    W_box = sum over robot-box rows of (-f) . (v + omega x (p - x_box)) dt (assumption A18)."""
    with open(os.path.join(quick_run, "claims.json")) as f:
        wb = next(c for c in json.load(f) if c["id"] == "WB")
    path, = glob.glob(os.path.join(quick_run, ".cache", "J-" + "?" * 16 + ".npz"))  # not J-mirror-...
    traj = Trajectory.from_npz(path)
    c, total = traj.contacts, 0.0
    for k, kind, point, force in zip(c["contact_step"], c["contact_kind"], c["contact_point"], c["contact_force"]):
        if kind == 1:
            u = 0.5 * (traj.qd[k, -6:] + traj.qd[k + 1, -6:])
            omega = quat_to_rot(traj.box_pose[k, 3:]) @ u[3:]
            total -= force @ (u[:3] + np.cross(omega, point - traj.box_pose[k, :3])) * traj.dt
    assert total > 0, "the J hook reaches the box within the quick run's 1 s"
    assert wb["values"]["J"] == pytest.approx(total, rel=1e-9)


def test_a_warm_run_reuses_the_simulations_and_the_figures(quick_run):
    before = {p: os.path.getmtime(p) for p in glob.glob(os.path.join(quick_run, "fig0*.png"))}
    assert main(["figures", "--quick", "--no-mujoco", "--defaults", "--quiet", "--out", quick_run]) == 0
    after = {p: os.path.getmtime(p) for p in before}
    assert after == before, "unchanged inputs must keep the figures"


def test_claim_verdicts_follow_the_numbers():
    """Hand-made summaries: sidewinding largest everywhere, S and J with the lowest slopes."""
    base = {"efficiency_slope": 10.0, "box_work": 1.0, "locomotion_work": 5.0, "peak_abs_power": 3.0,
            "box_distance": 0.1, "box_displacement": [0.1, 0.0], "error": ""}
    s = {g: dict(base) for g in ("C", "S", "J", "J-mirror", "sidewinding")}
    s["S"]["efficiency_slope"] = s["J"]["efficiency_slope"] = 5.0
    for key in ("box_work", "locomotion_work", "peak_abs_power", "box_distance"):
        s["sidewinding"][key] = 2 * base[key]
    s["J"]["box_displacement"], s["J-mirror"]["box_displacement"] = [0.1, -0.02], [0.1, 0.02]
    assert all(c["holds"] for c in paper_claims(s))
    s["J"]["efficiency_slope"] = 12.0  # J now less efficient than C and sidewinding (10), S still better
    assert {c["id"]: c["holds"] for c in paper_claims(s)}["E"] is False, "both S and J must beat both"
    s["J"]["efficiency_slope"] = 5.0
    s["C"]["efficiency_slope"] = 4.0  # C now beats S and J
    s["J-mirror"]["box_displacement"] = [0.1, -0.01]  # same side as J
    verdicts = {c["id"]: c["holds"] for c in paper_claims(s)}
    assert verdicts["E"] is False and verdicts["MJ"] is False
    del s["sidewinding"]
    assert {c["id"]: c["holds"] for c in paper_claims(s)}["WB"] is None


@pytest.mark.parametrize("args, message", [
    (["--gaits", "C,crawl"], "unknown gait(s) crawl"),
    (["--out", "/proc/cobra_figures"], "output directory"),
])
def test_bad_input_is_refused_before_any_work(args, message, capsys, tmp_path):
    argv = ["figures", "--quick", "--quiet"] + (args if "--out" in args else args + ["--out", str(tmp_path / "o")])
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert message in str(exc.value)
    assert not os.path.exists(tmp_path / "o") or not os.listdir(tmp_path / "o")
