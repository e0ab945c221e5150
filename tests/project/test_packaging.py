"""The wheel ships every package of the checkout: ``pyproject.toml`` lists them (the env package under its own name)."""

from pathlib import Path

import pytest

tomllib = pytest.importorskip("tomllib")  # Python >= 3.11
ROOT = Path(__file__).resolve().parents[2]


def test_every_package_folder_is_listed_under_its_import_name() -> None:
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    assert config["package-dir"] == {"twodrl_envs": "envs/twodrl_envs"}  # the folder has the import name
    found = set()
    for top in (ROOT / "sb3_twodrl", ROOT / "twodrl_zoo", ROOT / "twodrl_bench", ROOT / "envs" / "twodrl_envs"):
        for init in top.rglob("__init__.py"):
            found.add(".".join(init.parent.relative_to(top.parent).parts))
    assert set(config["packages"]) == found
    assert not (ROOT / "envs" / "__init__.py").exists()  # envs/ is a folder of the layout, not a package
