"""The library stands alone: ``import sb3_twodrl`` and its algorithms load nothing of the app, the bench or the envs."""

import json
import subprocess
import sys
from pathlib import Path

LIBRARY = Path(__file__).resolve().parents[2] / "sb3_twodrl"
PROGRAM = """
import json, sys
import sb3_twodrl
from sb3_twodrl import TwoDimA2C, TwoDimPPO
TwoDimA2C("MlpPolicy", "CartPole-v1", n_steps=8, seed=0).learn(64)
TwoDimPPO("MlpPolicy", "CartPole-v1", n_steps=8, batch_size=8, n_epochs=1, seed=0).learn(64)
print(json.dumps([sb3_twodrl.__file__, sorted(sys.modules)]))
"""


def test_the_algorithms_load_no_module_of_the_app_the_bench_nor_the_envs() -> None:
    root = LIBRARY.parent
    result = subprocess.run(
        [sys.executable, "-c", PROGRAM], cwd=root, capture_output=True, text=True, check=True, timeout=300
    )
    library, modules = json.loads(result.stdout.splitlines()[-1])
    assert Path(library).parent == LIBRARY  # this checkout's library
    assert "sb3_twodrl.a2c.twodim_a2c" in modules and "sb3_twodrl.ppo.twodim_ppo" in modules
    outside = [name for name in modules if name.split(".")[0] in ("twodrl_bench", "twodrl_envs", "twodrl_zoo", "envs")]
    assert not outside, outside


def test_no_library_file_names_the_bench() -> None:
    files = [path for path in LIBRARY.rglob("*") if path.is_file() and "__pycache__" not in path.parts]
    assert any(path.name == "on_policy.py" for path in files)
    naming = [
        str(path.relative_to(LIBRARY))
        for path in files
        if any(word in path.read_text(errors="replace") for word in ("twodrl_bench", "twodrl_zoo", "experiments"))
    ]
    assert not naming, naming
