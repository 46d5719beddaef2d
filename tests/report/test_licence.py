"""The licence and the citation file: present, and saying what the package says."""

from __future__ import annotations

import tomllib
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[2]


def test_the_licence_is_the_apache_licence_2_0():
    text = (ROOT / "LICENSE").read_text(encoding="utf-8")
    assert "Apache License" in text and "Version 2.0, January 2004" in text
    assert "END OF TERMS AND CONDITIONS" in text
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert project["license"] == {"text": "Apache-2.0"}
    assert "License :: OSI Approved :: Apache Software License" in project["classifiers"]
    assert not any("Proprietary" in c for c in project["classifiers"])


def test_the_citation_file_names_the_package_version_and_the_paper():
    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text(encoding="utf-8"))
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert cff["cff-version"] == "1.2.0"
    assert str(cff["version"]) == project["version"]
    assert cff["license"] == "Apache-2.0"
    assert cff["authors"] == [{"name": "rockfall-design developers"}]
    spang = next(r for r in cff["references"] if "rockfall protection" in r["title"])
    assert [a["family-names"] for a in spang["authors"]] == ["Spang", "Rautenstrauch"]
    assert spang["year"] == 1988
    assert "Lausanne" in spang["conference"]["city"]


def test_the_readme_ends_with_how_to_cite():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    last = readme.rsplit("\n## ", 1)[1]
    assert last.startswith("Citing")
    assert "Spang" in last and "Rautenstrauch" in last and "1988" in last
    assert "CITATION.cff" in last and "LICENSE" in last
