"""What a distribution of evotol declares and carries (issue 40): one licence with its text, the
vendored robot descriptions' own licences, one version source, and an sdist that holds what the
tests read (MANIFEST.in). The wheel and sdist themselves are built and tried in ``.ci/run``."""
from __future__ import annotations

import re
import tomllib
from pathlib import Path

import evotol

ROOT = Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))


def test_licence_declared_with_its_text():
    project = PYPROJECT["project"]
    assert project["license"] == "BSD-3-Clause"
    text = (ROOT / "LICENSE").read_text(encoding="utf-8")
    # the three clauses of BSD-3-Clause, the third being the no-endorsement clause
    assert text.startswith("BSD 3-Clause License") and "Neither the name of the copyright holder" in text
    assert "LICENSE" in project["license-files"]
    assert int(PYPROJECT["build-system"]["requires"][0].split(">=")[1]) >= 77   # PEP 639 support


def test_every_vendored_urdf_folder_has_its_licence_text():
    urdf = ROOT / "robots" / "urdf"
    folders = sorted({p.parent.parent for p in urdf.glob("*/urdf/*.urdf")})
    assert [f.name for f in folders] == ["panda_description", "ur_description"]
    for folder in folders:
        text = (folder / "LICENSE").read_text(encoding="utf-8")
        assert len(text) > 1000, folder          # a full licence text, not a one-line mention
    assert "BSD 3-Clause" in (urdf / "ur_description" / "LICENSE").read_text(encoding="utf-8")
    assert "Apache License" in (urdf / "panda_description" / "LICENSE").read_text(encoding="utf-8")


def test_one_version_source():
    assert "version" not in PYPROJECT["project"] and "version" in PYPROJECT["project"]["dynamic"]
    assert PYPROJECT["tool"]["setuptools"]["dynamic"]["version"] == {"attr": "evotol.__version__"}
    assert re.fullmatch(r"\d+\.\d+\.\d+\S*", evotol.__version__)


def test_typed_marker_shipped():
    assert (ROOT / "evotol" / "py.typed").is_file()
    assert "py.typed" in PYPROJECT["tool"]["setuptools"]["package-data"]["evotol"]


def test_sdist_manifest_holds_what_the_tests_read():
    """Every top-level folder a test names as ``ROOT / "folder"`` is grafted into the sdist."""
    manifest = (ROOT / "MANIFEST.in").read_text(encoding="utf-8")
    grafted = set(re.findall(r"^graft (\S+)", manifest, re.M))
    named = set()
    for test in (ROOT / "tests").glob("*.py"):
        if test.name == Path(__file__).name:
            continue
        named |= set(re.findall(r'ROOT\s*/\s*"([A-Za-z_.]+)"', test.read_text(encoding="utf-8")))
    # the packages, and the files every sdist holds (setuptools adds pyproject.toml; MANIFEST.in includes the rest)
    packages = {"evotol", "robots", "cost_models", "pyproject.toml", "LICENSE", "README.md"}
    missing = [name for name in sorted(named - packages)
               if not any(g == name or g.startswith(name + "/") for g in grafted)]
    assert not missing, f"tests read {missing}, which MANIFEST.in does not graft"
    assert "tests" in grafted
