"""The cobra-ref command as a user runs it (in-process, and once as a real subprocess)."""

import json
import subprocess
import sys

import numpy as np
import pytest

from cobra_ref.cli import main
from cobra_ref.trajectory import STEP_KEYS


def test_info_prints_every_body_and_the_sources(capsys):
    assert main(["info"]) == 0
    out = capsys.readouterr().out
    for name in ["head", "L1", "L10", "tail", "box", "J10", "1.695 m", "9.2 N m", "XH540-W270"]:
        assert name in out
    assert "(A23)" in out and "A12" in out  # the typos read, with their assumption ids


def test_export_mjcf_writes_a_loadable_file(tmp_path):
    mujoco = pytest.importorskip("mujoco")
    out = tmp_path / "cobra.xml"
    assert main(["export-mjcf", str(out)]) == 0
    assert mujoco.MjModel.from_xml_path(str(out)).nv == 23


def test_export_mjcf_into_a_missing_directory_fails_clearly_and_writes_nothing(tmp_path):
    with pytest.raises(SystemExit, match="output directory does not exist"):
        main(["export-mjcf", str(tmp_path / "nope" / "cobra.xml")])
    assert not (tmp_path / "nope").exists()


def test_python_dash_m_help_lists_the_subcommands():
    out = subprocess.run([sys.executable, "-m", "cobra_ref", "--help"], capture_output=True, text=True, check=True)
    assert "info" in out.stdout and "export-mjcf" in out.stdout


# ------------------------------------------------------------------------------ simulate

SUMMARY_KEYS = {"box_displacement", "max_penetration", "max_cone_residual", "max_coulomb_residual",
                "fixed_point_converged", "max_abs_tau", "impacts_per_second", "substepped", "real_time_factor",
                "tau_beyond_limit", "contact_force_beyond_bound"}


@pytest.mark.parametrize("option, n", [([], 2), (["--touchdown-substeps", "1"], 1), (["--contact", "rigid"], 1)])
def test_simulate_records_the_touchdown_substeps_it_took(tmp_path, option, n):
    """The compliant law's touch-downs in two substeps by default, whole steps with
    --touchdown-substeps 1 or the rigid law (A33): the NPZ's options record the n taken, and no
    step of the run took more."""
    out = tmp_path / "run.npz"
    assert main(["simulate", "--duration", "0.05", "--out", str(out), "--quiet", *option]) == 0
    with np.load(out) as run:
        assert json.loads(str(run["meta"]))["options"]["touchdown_substeps"] == n
        assert set(np.unique(run["substeps"])) <= {1, n}


def test_simulate_writes_the_npz_and_prints_one_json_line(tmp_path, capfd):
    out = tmp_path / "run.npz"
    assert main(["simulate", "--duration", "0.05", "--out", str(out), "--quiet"]) == 0
    lines = capfd.readouterr().out.strip().splitlines()
    assert len(lines) == 1, f"stdout must carry only the JSON summary (OSQP's C output goes to stderr): {lines}"
    summary = json.loads(lines[0])
    assert SUMMARY_KEYS <= set(summary) and len(summary["box_displacement"]) == 2
    with np.load(out) as run:
        n = len(run["t"])
        assert n == 51 and run["q"].shape == (n, 25) and run["qd"].shape == (n, 23)
        assert run["tau"].shape == (n - 1, 11) and run["box_pose"].shape == (n, 7)
        for key in STEP_KEYS:
            assert run[key].shape == (n - 1,), key
        m = len(run["contact_step"])
        assert m > 0 and run["contact_kind"].shape == (m,) and run["contact_force"].shape == (m, 3)
        assert set(np.unique(run["contact_kind"])) <= {0, 1, 2}
        # the summary is computed from these arrays
        assert summary["max_penetration"] == float(run["max_penetration"].max())


def _bad(argv, tmp_path, message, capsys=None):
    """Bad input: exit with a message naming the problem (argparse's on stderr, status 2, or the
    command's own, status 1), and nothing written."""
    out = tmp_path / "run.npz"
    with pytest.raises(SystemExit) as err:
        main(["simulate", *argv, "--out", str(out), "--quiet"])
    said = str(err.value.code) + (capsys.readouterr().err if capsys is not None else "")
    assert err.value.code != 0 and message in said
    assert not out.exists() and list(tmp_path.iterdir()) == [], "bad input must write nothing"


def test_simulate_unknown_gait_names_it(tmp_path, capsys):
    _bad(["--gait", "slithering"], tmp_path, "unknown gait 'slithering'", capsys)


@pytest.mark.parametrize("content, message", [
    ("t,J0,J1\n0,0,0\n", "CSV header must be"),
    ("t," + ",".join(f"J{i}" for i in range(11)) + "\n0,1,2\n1,x,3\n", "malformed reference file"),
    ("t," + ",".join(f"J{i}" for i in range(11)) + "\n" + ",".join(["0"] * 12) + "\n", "at least 4 samples"),
    ("t," + ",".join(f"J{i}" for i in range(11)) + "\n" + "\n".join(
        ",".join(["0"] * 12) for _ in range(5)) + "\n", "strictly increasing"),
])
def test_simulate_malformed_reference_file_names_the_problem(tmp_path, content, message):
    ref_dir = tmp_path / "in"
    ref_dir.mkdir()
    ref = ref_dir / "ref.csv"
    ref.write_text(content)
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    _bad(["--reference", str(ref)], out_dir, message)


@pytest.mark.parametrize("dt", ["0", "-1e-3"])
def test_simulate_rejects_dt_not_positive(tmp_path, dt, capsys):
    _bad([f"--dt={dt}"], tmp_path, f"--dt = {dt.replace('1e-3', '0.001')} s is out of range (allowed: [1e-5, 0.005] s)",
         capsys)


@pytest.mark.parametrize("duration", ["inf", "nan"])
def test_simulate_rejects_a_duration_that_is_not_finite(tmp_path, duration, capsys):
    _bad(["--duration", duration], tmp_path, "2")  # argparse exits with status 2 ...
    assert f"--duration = {duration} is not finite" in capsys.readouterr().err  # ... and names the problem


def test_simulate_into_a_missing_directory_fails_before_running(tmp_path):
    with pytest.raises(SystemExit, match="output directory does not exist"):
        main(["simulate", "--out", str(tmp_path / "nope" / "run.npz"), "--quiet"])


def test_bench_json_has_the_documented_keys(tmp_path, capfd):
    out = tmp_path / "bench.json"
    assert main(["bench", "--duration", "0.02", "--json", str(out), "--quiet"]) == 0
    record = json.loads(out.read_text())
    assert {"us_per_step", "real_time_factor", "breakdown_us", "mujoco_us_per_step", "ratio_vs_mujoco"} <= set(record)
    assert set(record["breakdown_us"]) == {"dynamics", "contacts", "qp", "rest"}
    assert record["us_per_step"] > 0 and record["real_time_factor"] > 0
    # OSQP solves every step's first QP; the readable reference step is timed too
    assert record["qp_solves_per_step"] >= 1.0 and record["reference_us_per_step"] > record["us_per_step"]
    assert "us/step" in capfd.readouterr().out
    # the batched engine per member-step at K = 1, 4, 16, 64 (JSON keys are strings)
    assert set(record["batched_us_per_member_step"]) == {"1", "4", "16", "64"} and not record["mujoco_skipped"]
    assert all(us > 0 for us in record["batched_us_per_member_step"].values())
    # MuJoCo side by side at our dt (per step), at 0.1 ms and at the export's 0.05 ms (accuracy-matched),
    # where installed
    if record["mujoco"] is not None:
        same, tenth, accurate = (record["mujoco"][k] for k in ("same_dt", "tenth_ms", "accurate"))
        assert (same["timestep_s"], tenth["timestep_s"], accurate["timestep_s"]) == (0.001, 0.0001, 0.00005)
        # twenty of MuJoCo's steps per step of ours cost more than ten, and ten more than one
        assert accurate["us_per_step"] > tenth["us_per_step"] > same["us_per_step"] > 0
        assert record["ratio_vs_mujoco"] == accurate["ratio"]
        assert same["ratio"] == pytest.approx(record["us_per_step"] / same["us_per_step"], rel=0.01)
