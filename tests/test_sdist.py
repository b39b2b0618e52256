"""The source distribution carries what its own tests read: the tests and their data, the
tutorials, the docs, the committed figures, README, LICENSE, CITATION.cff and CHANGELOG.md.

The first test applies MANIFEST.in with setuptools' own reader (no build); the second builds the
sdist with ``python -m build`` (skipped, saying why, without it or without network access to its
build dependencies) and reads its file list.
"""

import glob
import os
import shutil
import subprocess
import sys
import tarfile

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TOP = ("README.md", "LICENSE", "CITATION.cff", "CHANGELOG.md")
PATTERNS = ("tests/*.py", "tests/data/*.npz", "tutorials/*.py", "docs/*.md",
            "figures/*.png", "figures/*.gif", "figures/*.json", "figures/*.md")


def needed() -> set:
    """The files (relative to the repository) that the sdist must carry."""
    files = set(TOP)
    for pattern in PATTERNS:
        files |= {os.path.relpath(p, ROOT) for p in glob.glob(os.path.join(ROOT, pattern))}
    return files


def test_the_manifest_takes_every_file_the_tests_read(monkeypatch):
    from setuptools.command.egg_info import FileList

    monkeypatch.chdir(ROOT)
    files = FileList()
    files.findall(".")
    with open("MANIFEST.in", encoding="utf-8") as f:
        for line in f:
            if line.strip() and not line.lstrip().startswith("#"):
                files.process_template_line(line.strip())
    taken = {os.path.normpath(p) for p in files.files}
    assert {d.split("/")[0] for d in needed()} >= {"tests", "tutorials", "docs", "figures"}
    assert needed() <= taken, f"left out of the sdist: {sorted(needed() - taken)}"
    assert not [p for p in taken if "__pycache__" in p or p.endswith(".pyc")]


def test_the_built_sdist_lists_them(tmp_path):
    pytest.importorskip("build", reason="`python -m build` is not installed (pip install build)")
    source = tmp_path / "src"
    shutil.copytree(ROOT, source, ignore=shutil.ignore_patterns(
        ".git", "__pycache__", "*.egg-info", ".pytest_cache", ".cache", "out", ".venv", "build", "dist"))
    child = subprocess.run([sys.executable, "-m", "build", "--sdist", "--outdir", str(tmp_path / "dist"), str(source)],
                           capture_output=True, text=True, timeout=600)
    if child.returncode != 0 and "Installing build dependencies" in child.stdout and \
            "Getting build dependencies" not in child.stdout:
        pytest.skip(f"build could not install its build dependencies: {child.stderr.strip()[-300:]}")
    assert child.returncode == 0, child.stderr[-2000:]
    (archive,) = (tmp_path / "dist").glob("*.tar.gz")
    with tarfile.open(archive) as tar:
        listed = {name.split("/", 1)[1] for name in tar.getnames() if "/" in name}
    assert needed() <= listed, f"left out of the sdist: {sorted(needed() - listed)}"
