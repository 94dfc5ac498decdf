"""CITATION.cff is valid Citation File Format 1.2.0 (the rules of its schema that the file can break:
keys, required fields, types, URLs) and says what docs/credits.md says: SkelScope under MIT by its
developers, the paper as the preferred citation, the toolbox whose scans ship in resources/scans."""

from __future__ import annotations

import re
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[2]
PAPER = "Skeletonization Quality Evaluation: Geometric Metrics for Point Cloud Analysis in Robotics"
PAPER_AUTHORS = [("Qingmeng", "Wen"), ("Yu-Kun", "Lai"), ("Ze", "Ji"), ("Seyed Amir", "Tafrishi")]
TOOLBOX = "https://github.com/weiqimeng1/PointCloud_Skeletonization_Metrics"

# CFF 1.2.0's schema (https://citation-file-format.github.io/1.2.0/schema), the parts used here
TOP_KEYS = {"abstract", "authors", "cff-version", "commit", "contact", "date-released", "doi", "identifiers",
            "keywords", "license", "license-url", "message", "preferred-citation", "references", "repository",
            "repository-artifact", "repository-code", "title", "type", "url", "version"}
TOP_REQUIRED = {"authors", "cff-version", "message", "title"}
PERSON_KEYS = {"address", "affiliation", "alias", "city", "country", "email", "family-names", "fax",
               "given-names", "name-particle", "name-suffix", "orcid", "post-code", "region", "tel", "website"}
ENTITY_KEYS = {"address", "alias", "city", "country", "date-end", "date-start", "email", "fax", "location",
               "name", "orcid", "post-code", "region", "tel", "website"}
REFERENCE_REQUIRED = {"authors", "title", "type"}
REFERENCE_TYPES = {"art", "article", "audiovisual", "bill", "blog", "book", "catalogue", "conference-paper",
                   "conference", "data", "database", "dictionary", "edited-work", "encyclopedia",
                   "film-broadcast", "generic", "government-document", "grant", "hearing", "historical-work",
                   "legal-case", "legal-rule", "magazine-article", "manual", "map", "multimedia", "music",
                   "newspaper-article", "pamphlet", "patent", "personal-communication", "proceedings", "report",
                   "serial", "slides", "software-code", "software-container", "software-executable",
                   "software-virtual-machine", "software", "sound-recording", "standard", "statute", "thesis",
                   "unpublished", "video", "website"}
URL = re.compile(r"^(https|http|ftp|sftp)://.+")


def _cff() -> dict:
    return yaml.safe_load((ROOT / "CITATION.cff").read_text(encoding="utf-8"))


def _check_authors(authors, where: str) -> None:
    assert isinstance(authors, list) and authors, where
    for a in authors:
        assert isinstance(a, dict) and a, where
        if "name" in a:  # an entity
            assert set(a) <= ENTITY_KEYS, (where, a)
        else:  # a person
            assert set(a) <= PERSON_KEYS, (where, a)
        assert all(isinstance(v, str) and v for v in a.values()), (where, a)


def _check_reference(ref: dict, where: str) -> None:
    assert REFERENCE_REQUIRED <= set(ref), where
    assert ref["type"] in REFERENCE_TYPES, where
    assert isinstance(ref["title"], str) and ref["title"], where
    _check_authors(ref["authors"], where)
    for key in ("url", "repository-code", "repository"):
        if key in ref:
            assert URL.match(ref[key]), (where, key)


def test_citation_cff_is_valid_cff_1_2_0():
    cff = _cff()
    assert set(cff) <= TOP_KEYS, set(cff) - TOP_KEYS
    assert TOP_REQUIRED <= set(cff)
    assert cff["cff-version"] == "1.2.0"  # a string, as the schema wants (not a float)
    assert isinstance(cff["message"], str) and cff["message"]
    assert cff["type"] in ("software", "dataset")
    _check_authors(cff["authors"], "authors")
    assert len(set(map(str, cff["authors"]))) == len(cff["authors"])
    assert isinstance(cff["keywords"], list) and len(set(cff["keywords"])) == len(cff["keywords"])
    _check_reference(cff["preferred-citation"], "preferred-citation")
    assert isinstance(cff["references"], list) and cff["references"]
    for i, ref in enumerate(cff["references"]):
        _check_reference(ref, f"references[{i}]")


def test_citation_cff_names_skelscope_the_paper_and_the_toolbox():
    cff = _cff()
    assert cff["title"] == "SkelScope" and cff["type"] == "software"
    assert cff["authors"] == [{"name": "The SkelScope developers"}]
    assert cff["license"] == "MIT"
    assert 'license = "MIT"' in (ROOT / "pyproject.toml").read_text(encoding="utf-8")
    paper = cff["preferred-citation"]
    assert paper["title"] == PAPER
    assert [(a["given-names"], a["family-names"]) for a in paper["authors"]] == PAPER_AUTHORS
    toolbox = [r for r in cff["references"] if r.get("repository-code") == TOOLBOX]
    assert len(toolbox) == 1 and toolbox[0]["license"] == "MIT"
    assert toolbox[0]["authors"] == [{"alias": "weiqimeng1"}]
    assert any(r["title"] == PAPER for r in cff["references"])
    credits = " ".join((ROOT / "docs" / "credits.md").read_text(encoding="utf-8").split())  # lines unwrapped
    assert PAPER in credits and "CITATION.cff" in credits and TOOLBOX in credits


def test_the_version_is_one_in_citation_package_and_changelog():
    """A release names one version and one date: CITATION.cff's, the package's and the newest release
    heading of CHANGELOG.md (Keep a Changelog: ``## [X.Y.Z] - YYYY-MM-DD`` below ``## [Unreleased]``)."""
    from skelcore.version import __version__

    cff = _cff()
    assert isinstance(cff["version"], str) and isinstance(cff["date-released"], str)
    assert re.fullmatch(r"\d{4}-\d{2}-\d{2}", cff["date-released"])
    assert cff["version"] == __version__
    headings = re.findall(r"^## \[([^\]]+)\](?: - (\S+))?$",
                          (ROOT / "CHANGELOG.md").read_text(encoding="utf-8"), flags=re.M)
    assert headings[0] == ("Unreleased", "")
    assert headings[1] == (__version__, cff["date-released"])
