"""The scripts import the installed packages (``pip install -e .``): none changes ``sys.path``."""

import ast
from pathlib import Path

SCRIPTS = Path(__file__).resolve().parents[2] / "scripts"


def changes_sys_path(path: Path) -> bool:
    """Whether the script at ``path`` names ``sys.path`` (an insert, an append, an assignment)."""
    tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
    return any(
        isinstance(node, ast.Attribute)
        and node.attr == "path"
        and isinstance(node.value, ast.Name)
        and node.value.id == "sys"
        for node in ast.walk(tree)
    )


def test_no_script_changes_sys_path() -> None:
    scripts = sorted(SCRIPTS.glob("*.py"))
    assert any(path.name == "bench_env.py" for path in scripts)
    assert not [path.name for path in scripts if changes_sys_path(path)]


def test_a_sys_path_change_is_found(tmp_path: Path) -> None:
    script = tmp_path / "s.py"
    script.write_text("import sys\nsys.path.insert(0, 'envs')\n")
    assert changes_sys_path(script)
    script.write_text("import sys\nprint(sys.argv)\n")
    assert not changes_sys_path(script)
