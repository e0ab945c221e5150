"""The wheel ships every package of the checkout: ``pyproject.toml`` lists them (the env package under its own name)."""

from pathlib import Path

import pytest

tomllib = pytest.importorskip("tomllib")  # Python >= 3.11
ROOT = Path(__file__).resolve().parents[1]


def test_every_package_folder_is_listed_under_its_import_name() -> None:
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    folders = {value: key for key, value in config["package-dir"].items()}
    found = set()
    for top in ("sb3_twodrl", "twodrl_bench", "envs"):
        for init in (ROOT / top).rglob("__init__.py"):
            parts = init.parent.relative_to(ROOT).parts
            found.add(".".join((folders.get(parts[0], parts[0]), *parts[1:])))
    assert set(config["packages"]) == found
    assert "envs" not in {name.split(".")[0] for name in config["packages"]}
