"""The bench meets the env package by value only (its rule, ``twodrl_bench/__init__.py``): envs by ID, their packages
by ``gym_packages``, the route labels whose shares are its columns by their names."""

import ast
from pathlib import Path

from twodrl_bench.protocol import METRICS, ROUTES
from twodrl_envs.nomad.geometry import ROUTE_REGIONS

BENCH = Path(__file__).resolve().parents[2] / "twodrl_bench"


def imported_packages(path: Path) -> set[str]:
    """The top-level packages that the module at ``path`` imports (absolute imports)."""
    out = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            out |= {alias.name.split(".")[0] for alias in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            out.add(node.module.split(".")[0])
    return out


def test_no_bench_module_imports_the_env_package() -> None:
    modules = sorted(BENCH.rglob("*.py"))
    assert any(path.name == "protocol.py" for path in modules)
    importing = [str(path.relative_to(BENCH)) for path in modules if "twodrl_envs" in imported_packages(path)]
    assert not importing, importing


def test_the_route_columns_are_the_office_s_route_labels() -> None:
    assert ROUTES == ROUTE_REGIONS
    assert [f"{route}_share" for route in ROUTE_REGIONS] == [m for m in METRICS if m.endswith("_share")]
