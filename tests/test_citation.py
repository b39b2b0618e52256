"""The repository's citation, licence, changelog and version: one version string, a valid CITATION.cff
that cites the paper, the BSD-3-Clause text."""

import os
import re

import pytest

import cobra_ref
from cobra_ref.cli import main

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PAPER_AUTHORS = ["Salagame", "Gangaraju", "Nallaguntla", "Sihite", "Schirner", "Ramezani"]


def read(name: str) -> str:
    with open(os.path.join(ROOT, name), encoding="utf-8") as f:
        return f.read()


def citation():
    """CITATION.cff through cffconvert, which bundles the Citation File Format's JSON schemas."""
    cffconvert = pytest.importorskip(
        "cffconvert.citation",
        reason="cffconvert (it bundles the CFF 1.2.0 JSON schema) is not installed: pip install '.[test]'")
    return cffconvert.Citation


def test_citation_cff_validates_against_the_cff_1_2_0_schema():
    Citation = citation()
    cff = Citation(read("CITATION.cff"))
    assert cff.cffversion == "1.2.0"
    cff.validate()  # raises on any schema violation


def test_the_validator_rejects_a_citation_without_authors():
    """The check above can fail: the same file without its authors is refused."""
    Citation = citation()
    text = read("CITATION.cff")
    broken = re.sub(r"^authors:\n  - name: .*\n", "", text, count=1, flags=re.MULTILINE)
    assert broken != text
    with pytest.raises(Exception):
        Citation(broken).validate()


def test_citation_cites_the_paper_with_its_six_authors_in_order():
    Citation = citation()
    cff = Citation(read("CITATION.cff")).cffobj
    assert cff["type"] == "software" and cff["authors"] == [{"name": "cobra_ref contributors"}]
    (paper,) = cff["references"]
    assert paper["title"] == "Non-impulsive Contact-Implicit Motion Planning for Morpho-functional Loco-manipulation"
    assert [a["family-names"] for a in paper["authors"]] == PAPER_AUTHORS
    assert paper["year"] == 2024
    assert "arXiv:2404.08714" in [i["value"] for i in paper["identifiers"]]


def test_one_version_string_everywhere():
    """provenance.__version__ is the only place the version is written; pyproject reads it, CITATION.cff and
    the changelog repeat it."""
    version = cobra_ref.__version__
    assert version == "0.2.0.dev0"
    pyproject = read("pyproject.toml")
    assert re.search(r'^dynamic = \["version"\]', pyproject, re.MULTILINE)
    assert re.search(r'^version = \{ attr = "cobra_ref.provenance.__version__" \}', pyproject, re.MULTILINE)
    assert not re.search(r'^version = "', pyproject, re.MULTILINE), "a second, static version in pyproject.toml"
    assert re.search(rf"^version: {re.escape(version)}$", read("CITATION.cff"), re.MULTILINE)
    assert f"({version})" in read("CHANGELOG.md")


def test_cobra_ref_version_prints_the_version(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert capsys.readouterr().out.strip() == f"cobra-ref {cobra_ref.__version__}"


def test_licence_is_bsd_3_clause_with_the_copyright_line():
    text = read("LICENSE")
    assert text.startswith("BSD 3-Clause License")
    assert "Copyright (c) 2026 the cobra_ref authors" in text
    assert text.count("\n1. ") + text.count("\n2. ") + text.count("\n3. ") == 3  # the three clauses
    assert 'license = "BSD-3-Clause"' in read("pyproject.toml")
