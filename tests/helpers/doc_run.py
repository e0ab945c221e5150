"""A guide's ``$`` commands run as written, in order, in one folder (the slow tests of the docs' paths)."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

EXPORT = re.compile(r"^sb3-twodrl-train: export: (.*)$", re.MULTILINE)


def run_doc_commands(commands: list[str], folder: Path, timeout: float = 1200) -> list[str]:
    """Each command's stdout, every command having succeeded; a doc's export line must be the one its training
    printed (the doc tells the reader to run that line)."""
    printed: list[str] = []
    outputs = []
    for command in commands:
        out = subprocess.run(["bash", "-c", command], cwd=folder, capture_output=True, text=True, timeout=timeout)
        assert out.returncode == 0, (command, out.stdout[-2000:], out.stderr[-3000:])
        if command.startswith("sb3-twodrl-export"):
            assert command == printed[-1]
        printed += EXPORT.findall(out.stdout)
        outputs.append(out.stdout)
    return outputs
