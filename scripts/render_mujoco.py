"""A top-down picture of ``NomadOfficeMuJoCo-v0``'s MuJoCo scene (docs/mujoco.md): the paper's office and a
generated one side by side, each the env's ``render()`` (``render_mode="rgb_array"``: MuJoCo's offscreen
rendering, headless through EGL) with the robot at the map's start. Needs the ``mujoco`` extra only.

    python scripts/render_mujoco.py --out docs/mujoco_offices.png
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import gymnasium as gym
import numpy as np

import twodrl_envs  # noqa: F401  (registers the IDs)


def start_frame(map_name: str | None) -> np.ndarray:
    """The env's MuJoCo frame of ``map_name`` with the robot at the start; an error where MuJoCo cannot render."""
    env = gym.make("NomadOfficeMuJoCo-v0", map=map_name, render_mode="rgb_array", disable_env_checker=True)
    env.reset(seed=0)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)  # the env's fallback to the lattice picture
        frame = env.render()
    env.close()
    return np.asarray(frame)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--maps", nargs="+", default=["office", "generated:M:7"], help="maps, side by side")
    parser.add_argument("--out", type=Path, default=Path("docs/mujoco_offices.png"))
    args = parser.parse_args()
    try:
        frames = [start_frame(name) for name in args.maps]
    except RuntimeWarning as warning:
        sys.exit(f"render_mujoco.py: {warning}")
    height = max(f.shape[0] for f in frames)
    gap = np.full((height, 20, 3), 255, dtype=np.uint8)
    padded = [np.pad(f, ((height - f.shape[0], 0), (0, 0), (0, 0)), constant_values=255) for f in frames]
    image = np.concatenate([x for f in padded for x in (f, gap)][:-1], axis=1)
    import matplotlib.pyplot as plt

    plt.imsave(args.out, image)
    print(f"wrote {args.out} ({image.shape[1]} x {image.shape[0]} px)")


if __name__ == "__main__":
    main()
