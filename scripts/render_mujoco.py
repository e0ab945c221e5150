"""A top-down picture of ``NomadOfficeMuJoCo-v0``'s MuJoCo scene (docs/mujoco.md): the paper's office and a
generated one, rendered offscreen by MuJoCo (needs an OpenGL context without a display: ``MUJOCO_GL=egl``).

    MUJOCO_GL=egl python scripts/render_mujoco.py --out docs/mujoco_offices.png
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "envs"))  # this checkout's envs

import numpy as np

from twodrl_envs.nomad.core import office_core
from twodrl_envs.nomad.physics import MuJoCoRobot

PIXELS_PER_M = 160


def top_down(map_name: str | None) -> np.ndarray:
    """An orthographic top-down frame of the map's MuJoCo scene, the robot at the start."""
    import mujoco

    robot = MuJoCoRobot(office_core(map_name))
    model, data = robot.mjmodel, robot.data
    robot.reset_motion(np.array(robot.core.office.start))
    x0, y0, x1, y1 = (v / 100.0 for v in robot.core.office.bounds)
    width, height = round((x1 - x0 + 0.2) * PIXELS_PER_M), round((y1 - y0 + 0.2) * PIXELS_PER_M)
    model.vis.global_.offwidth, model.vis.global_.offheight = max(width, 640), max(height, 480)
    skins = [i for i in range(model.ngeom) if model.geom(i).name.startswith("skin")]
    model.geom_rgba[skins] = (0.25, 0.25, 0.3, 1.0)  # the walls' contact capsules, seen from above
    camera = mujoco.MjvCamera()
    camera.lookat[:] = ((x0 + x1) / 2, (y0 + y1) / 2, 0.0)
    model.vis.global_.fovy = 4.0  # from far above: the walls' sides barely show
    fovy = np.deg2rad(model.vis.global_.fovy)
    camera.distance = (y1 - y0 + 0.2) / 2 / np.tan(fovy / 2) + 1.0
    camera.elevation, camera.azimuth = -90.0, 90.0
    options = mujoco.MjvOption()
    options.geomgroup[:] = 1
    with mujoco.Renderer(model, height, width) as renderer:
        renderer.update_scene(data, camera, options)
        return renderer.render()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--maps", nargs="+", default=["office", "generated:M:7"], help="maps, side by side")
    parser.add_argument("--out", type=Path, default=Path("docs/mujoco_offices.png"))
    args = parser.parse_args()
    os.environ.setdefault("MUJOCO_GL", "egl")
    frames = [top_down(name) for name in args.maps]
    height = max(f.shape[0] for f in frames)
    gap = np.full((height, 20, 3), 255, dtype=np.uint8)
    padded = [np.pad(f, ((height - f.shape[0], 0), (0, 0), (0, 0)), constant_values=255) for f in frames]
    image = np.concatenate([x for f in padded for x in (f, gap)][:-1], axis=1)
    import matplotlib.pyplot as plt

    plt.imsave(args.out, image)
    print(f"wrote {args.out} ({image.shape[1]} x {image.shape[0]} px)")


if __name__ == "__main__":
    main()
