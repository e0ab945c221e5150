"""The version is written once (``sb3_twodrl.__version__``), read by ``pyproject.toml``; the changelog has it."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

import sb3_twodrl

tomllib = pytest.importorskip("tomllib")  # Python 3.11+

ROOT = Path(__file__).resolve().parents[2]


def test_pyproject_reads_the_version_from_the_package() -> None:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert "version" not in project["project"] and "version" in project["project"]["dynamic"]
    assert project["tool"]["setuptools"]["dynamic"]["version"] == {"attr": "sb3_twodrl.__version__"}
    assert re.fullmatch(r"\d+\.\d+\.\d+", sb3_twodrl.__version__)


def test_the_changelog_has_an_unreleased_section_then_the_current_version() -> None:
    headings = re.findall(r"^## (.+)$", (ROOT / "CHANGELOG.md").read_text(), flags=re.MULTILINE)
    assert headings[:2] == ["Unreleased", sb3_twodrl.__version__]
