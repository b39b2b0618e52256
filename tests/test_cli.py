"""The cobra-ref command as a user runs it (in-process, and once as a real subprocess)."""

import subprocess
import sys

import pytest

from cobra_ref.cli import main


def test_info_prints_every_body_and_the_sources(capsys):
    assert main(["info"]) == 0
    out = capsys.readouterr().out
    for name in ["head", "L1", "L10", "tail", "box", "J10", "1.695 m", "9.2 N m", "XH540-W270"]:
        assert name in out
    assert "seed typo" in out


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
