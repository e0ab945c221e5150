"""The gap between NomadOffice-v0 (ideal) and NomadOfficeReal-v0 (stand-in robot), before any learning.

Prints, per sensor bearing, the share of reachable lattice cells where the realistic reading,
median over ``--draws`` noise draws, differs from the ideal reading by more than 50 cm (sonar) or
10 cm (infrared), and the dead-reckoning error after 20 and 50 random moves; ``--figure`` draws
both models' sonar readings at three poses (the start, and cells one and two thirds of the
longest shortest path away from it).

    python scripts/sensor_gap.py --draws 7 --seed 0 --figure docs/realistic_readings.png
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from twodrl_envs.analysis.gap import k_convergence, odometry_errors, systematic_difference
from twodrl_envs.memorable.recording import shortest_paths
from twodrl_envs.nomad.core import office_core
from twodrl_envs.nomad.realistic import RealisticModel
from twodrl_envs.nomad.sensors import BEARINGS, N_SONAR, exact_ranges


def default_poses(core) -> list[tuple[float, float]]:
    """The start and the first reachable cells one third and two thirds of the farthest path length away."""
    lengths = np.array([len(p) if core.lattice.reachable[c] else -1 for c, p in enumerate(shortest_paths(core))])
    picks = [core.start_cell] + [int(np.flatnonzero(lengths == lengths.max() * k // 3)[0]) for k in (1, 2)]
    return [tuple(float(v) for v in core.lattice.cells[c]) for c in picks]


def figure(path: Path, map_path: Path | None, model: RealisticModel, seed: int) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    core = office_core(map_path)
    scene = model.scene(core.office)
    axes_xy = np.stack([np.sin(BEARINGS), np.cos(BEARINGS)], axis=1)
    rng = np.random.default_rng(seed)
    poses = default_poses(core)
    fig, axes = plt.subplots(1, len(poses), figsize=(5 * len(poses), 4.2))
    for ax, pose in zip(axes, poses, strict=True):
        xy = np.array([pose])
        ideal = np.clip(exact_ranges(core.office, xy)[0, :N_SONAR], 40, 600)
        for wall in core.office.walls:
            ax.plot(wall[[0, 2]], wall[[1, 3]], "k-", lw=2)
        ax.add_patch(plt.Circle(pose, 30, fill=False, color="0.4"))
        for k in range(5):
            real = scene.ranges(xy, rng.integers(0, 2**63, 1, dtype=np.uint64), np.zeros(1, int))[0, :N_SONAR]
            lost = real >= 600
            pts = xy[0] + np.where(lost, 45.0, 30 + real)[:, None] * axes_xy
            ax.plot(*pts[~lost].T, "rx", ms=5, label="realistic (5 draws)" if k == 0 else None)
            ax.plot(*pts[lost].T, "v", color="tab:orange", ms=4, label="realistic: no echo (600)" if k == 0 else None)
        pts = xy[0] + (30 + ideal)[:, None] * axes_xy
        ax.plot(pts[:, 0], pts[:, 1], "o", mfc="none", mec="tab:blue", ms=7, label="ideal")
        for s in range(N_SONAR):
            end = xy[0] + 60 * axes_xy[s]
            ax.plot([xy[0, 0], end[0]], [xy[0, 1], end[1]], "-", color="0.8", lw=0.5)
        x0, y0, x1, y1 = core.office.bounds
        ax.set_xlim(x0 - 40, x1 + 40)
        ax.set_ylim(y0 - 40, y1 + 40)
        ax.set_aspect("equal")
        ax.set_title(f"robot at {pose} cm; red marks beyond a wall: multipath ranges")
        ax.title.set_fontsize(8)
    axes[0].legend(loc="upper right", fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--draws", type=int, default=7, help="noise draws per cell, median taken (default 7)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--robots", type=int, default=2000, help="robots for the odometry error (default 2000)")
    parser.add_argument("--map", type=Path, default=None, help="office map JSON (default: the shipped office)")
    parser.add_argument("--figure", type=Path, default=None, help="write the readings figure here (.png)")
    parser.add_argument(
        "--k-sweep",
        type=int,
        default=0,
        help="also compare K = 1, 2, 4, 8, 16 recorded readings per "
        "cell with this many (e.g. 64): how many a database needs",
    )
    args = parser.parse_args(argv)
    model = RealisticModel()
    core = office_core(args.map)
    diff = systematic_difference(core, model, args.draws, args.seed)
    sonar, ir = (diff[:, :N_SONAR] > 50).mean(axis=0), (diff[:, N_SONAR:] > 10).mean(axis=0)
    print(f"{len(diff)} reachable cells, median of {args.draws} draws per reading, seed {args.seed}")
    print("sensor  bearing (deg ccw from north)  sonar |diff| > 50 cm   IR |diff| > 10 cm")
    for s in range(N_SONAR):
        print(f"{s:6d}  {22.5 * s:28.1f}  {100 * sonar[s]:19.1f}%  {100 * ir[s]:16.1f}%")
    print(f"{'all':>6s}  {'':28s}  {100 * sonar.mean():19.1f}%  {100 * ir.mean():16.1f}%")
    for straight in (False, True):
        errors = odometry_errors(model, 50, args.robots, args.seed, straight=straight)
        for n in (20, 50):
            e = errors[n - 1]
            print(
                f"odometry error after {n} {'straight' if straight else 'random'} moves ({args.robots} robots): "
                f"median {np.median(e):.1f} cm, mean {e.mean():.1f} cm, 95th percentile {np.percentile(e, 95):.1f} cm"
            )
    if args.k_sweep:
        shares = k_convergence(core, model, (1, 2, 4, 8, 16), args.k_sweep, args.seed)
        for k, share in shares.items():
            print(
                f"K = {k:2d}: median of K readings differs > 50 cm from the median of {args.k_sweep}: "
                f"{100 * share:.1f}% of (cell, sonar)"
            )
    if args.figure is not None:
        figure(args.figure, args.map, model, args.seed)


if __name__ == "__main__":
    main()
