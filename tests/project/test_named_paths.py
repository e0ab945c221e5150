"""Every repository path and module that the docs and the docstrings name exists (issue 67).

A path is a word that starts at one of the repository's folders (``docs/``, ``scripts/``, ``results/``, a package's
folder, ...); where it holds a placeholder (``<algo>``, ``*``, ``{a,b}``) the folder before it must exist. A module is
a dotted name that starts at one of the packages (``twodrl_bench.settings.settings_file``, or ``.protocol.ROUTES``
in a Sphinx role, from the module's package): its modules must exist and the next name must be defined at the top of
the last one. A path after a revision (``01db862:scripts/reproduce.py``) is that commit's, one after ``--out`` is what
a command writes, and ``CHANGELOG.md`` and the studies' records under ``results/`` are left as written: they tell
what was.
"""

from __future__ import annotations

import ast
import re
from collections.abc import Iterator
from functools import cache
from importlib.metadata import distribution
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = {
    "sb3_twodrl": ROOT / "sb3_twodrl",
    "twodrl_zoo": ROOT / "twodrl_zoo",
    "twodrl_bench": ROOT / "twodrl_bench",
    "twodrl_envs": ROOT / "envs" / "twodrl_envs",
    "tests": ROOT / "tests",
}
FOLDERS = ("docs", "results", "envs", "scripts", "tests", ".ci", *PACKAGES)
PATH = re.compile(rf"(?<![\w./:-])((?:{'|'.join(re.escape(f) for f in FOLDERS)})/[\w./<>*{{}},-]*)")
MODULE = re.compile(rf"(?<![\w./-])((?:{'|'.join(PACKAGES)})(?:\.\w+)+)")
RELATIVE = re.compile(r":\w+:`~?(\.\w+(?:\.\w+)*)`")
PLACEHOLDER = re.compile(r"[<>*{}]")
OUTPUT = re.compile(r"--out[ =]\S+")
"""A command's output folder (``--out results/<study>/part``): what the command writes, not what is there."""
PENDING: dict[str, list[str]] = {}
"""Stale names in docstrings of files that another session is changing (issue 67); each goes once it is mended."""
BUILT = ("docs/_build", "docs/results/")
"""Paths that the docs build makes, not the repository holds: the site, the records' pages."""


def docs() -> Iterator[tuple[Path, str]]:
    """The README and the docs pages, each with its text (not what the docs build makes: the site, the records'
    pages)."""
    pages = [*sorted((ROOT / "docs").rglob("*.md")), *sorted((ROOT / "docs").rglob("*.rst"))]
    for path in [ROOT / "README.md", *pages]:
        if not path.relative_to(ROOT).as_posix().startswith(BUILT):
            yield path, path.read_text(encoding="utf-8")


def sources() -> list[Path]:
    """The Python files of the packages, the scripts, the tests and the docs' configuration."""
    folders = [*PACKAGES.values(), ROOT / "scripts", ROOT / "docs"]
    return sorted({path for folder in folders for path in folder.rglob("*.py") if "_build" not in path.parts})


def docstrings(path: Path) -> Iterator[str]:
    """The docstrings of the module at ``path``: its own, its classes' and functions', and the strings under its
    assignments (attribute docstrings)."""
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant) and isinstance(node.value.value, str):
            yield node.value.value


def module_name(path: Path) -> str:
    """The dotted name of the module at ``path`` (a package's ``__init__.py``: the package)."""
    for name, folder in PACKAGES.items():
        if folder in path.parents:
            parts = [name, *path.relative_to(folder).with_suffix("").parts]
            return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
    return ""


@cache
def defined_names(path: Path) -> set[str]:
    """The names defined at the top of the module at ``path``: functions, classes, assignments, imports."""
    names: set[str] = set()
    for node in ast.parse(path.read_text(encoding="utf-8")).body:
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            names.add(node.name)
        elif isinstance(node, ast.Assign | ast.AnnAssign):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            names |= {n.id for t in targets for n in ast.walk(t) if isinstance(n, ast.Name)}
        elif isinstance(node, ast.Import | ast.ImportFrom):
            names |= {(alias.asname or alias.name).split(".")[0] for alias in node.names}
    return names


def module_exists(dotted: str) -> bool:
    """Whether ``dotted`` names a module of the packages, or a name defined at the top of one."""
    first, *rest = dotted.split(".")
    folder = PACKAGES[first]
    while rest and (folder / rest[0] / "__init__.py").is_file():
        folder = folder / rest.pop(0)
    module = folder / "__init__.py"
    if rest and (folder / f"{rest[0]}.py").is_file():
        module = folder / f"{rest.pop(0)}.py"
    return not rest or rest[0] in defined_names(module)


@cache
def entry_point_groups() -> frozenset[str]:
    """The entry-point groups of the installed package (``sb3_twodrl.gym_packages``): dotted names, no module."""
    return frozenset(entry.group for entry in distribution("sb3-twodrl").entry_points)


def missing_paths(text: str) -> list[str]:
    """The repository paths ``text`` names that do not exist."""
    out = []
    for word in PATH.findall(OUTPUT.sub("", text)):
        path = PLACEHOLDER.split(word.rstrip(".,:;"))[0]
        path = path if path == word.rstrip(".,:;") else path.rpartition("/")[0]
        if not path.startswith(BUILT) and not (ROOT / path).exists():
            out.append(word)
    return out


def missing_modules(text: str, package: str = "") -> list[str]:
    """The modules (and their names) ``text`` names that do not exist; ``.name`` in a Sphinx role from
    ``package``."""
    groups = entry_point_groups()
    named = [word.rstrip(".") for word in MODULE.findall(text) if word.rstrip(".") not in groups]
    relative = [f"{package}{word}" for word in RELATIVE.findall(text)] if package else []
    return [name for name in named + relative if not module_exists(name)]


def test_a_missing_path_or_module_is_found() -> None:
    text = "`docs/nowhere.md`, `scripts/bench_env.py`, `01db862:scripts/gone.py`, `--out results/new/part`"
    assert missing_paths(text) == ["docs/nowhere.md"]
    assert missing_paths("`twodrl_zoo/hyperparams/<algo>.yml`, `twodrl_zoo/nowhere/<algo>.yml`") == [
        "twodrl_zoo/nowhere/<algo>.yml"
    ]
    assert missing_modules("``twodrl_bench.protocol.ROUTES``, ``twodrl_bench.protocol.NOWHERE``") == [
        "twodrl_bench.protocol.NOWHERE"
    ]
    assert missing_modules(":mod:`.spec`, :data:`~.protocol.NOWHERE`", "twodrl_bench") == [
        "twodrl_bench.protocol.NOWHERE"
    ]


def test_every_path_and_module_the_docs_name_exists() -> None:
    missing = {
        str(path.relative_to(ROOT)): found
        for path, text in docs()
        if (found := missing_paths(text) + missing_modules(text))
    }
    assert not missing, missing


def test_every_path_and_module_a_docstring_names_exists() -> None:
    missing = {}
    for path in sources():
        package = module_name(path).rpartition(".")[0] if path.name != "__init__.py" else module_name(path)
        found = [word for text in docstrings(path) for word in missing_paths(text) + missing_modules(text, package)]
        if found:
            missing[str(path.relative_to(ROOT))] = found
    assert len(sources()) > 100
    assert missing == PENDING
