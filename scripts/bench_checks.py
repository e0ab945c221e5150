"""What goal checks side by side buy: ``sb3-twodrl-train`` with its default ``--n-eval-envs`` (a check's episodes
side by side, :data:`twodrl_zoo.manager.SIDE_BY_SIDE`) against rl-zoo3's one eval env, alternated (A B A B) on the
same maps and seeds, one training at a time in this process's children.

    python scripts/bench_checks.py --maps generated:M:5 generated:S:3 office --seeds 1

Prints each run's steps, checks and training seconds (the run's own ``goal_checks.json``), whether the two runs'
checks are the same (they are on exact readings), and the median ratio of training seconds, side by side over B/A.
"""

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from twodrl_zoo.manager import CHECKS_FILE

ARMS = {"side by side": [], "one env": ["--n-eval-envs", "1"]}


def train(map_: str, seed: int, args: argparse.Namespace, more: list[str], folder: Path) -> dict:
    """One run of the train command; its ``goal_checks.json``."""
    argv = ["--algo", args.algo, "--env", args.env, "--seed", str(seed), "-f", str(folder), *more]
    options = ([] if map_ == "office" else [f"map:{map_!r}"]) + args.env_kwargs
    if options:
        argv += ["--env-kwargs", *options]
    code = f"from twodrl_zoo.cli import train; train({argv!r})"
    subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True)
    (path,) = folder.glob(f"{args.algo}/*/{CHECKS_FILE}")
    return json.loads(path.read_text())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--maps", nargs="+", default=["generated:M:5"], help="maps ('office': the paper's)")
    parser.add_argument("--seeds", nargs="+", type=int, default=[1])
    parser.add_argument("--algo", default="twoda2c")
    parser.add_argument("--env", default="NomadOffice-v0")
    parser.add_argument(
        "--env-kwargs", nargs="*", default=[], help="more key:value env options, e.g. database:'DB.npz'"
    )
    args = parser.parse_args()
    ratios = []
    print("| map | seed | arm | steps | checks | train s |")
    print("| --- | --- | --- | --- | --- | --- |")
    with tempfile.TemporaryDirectory() as tmp:
        for map_ in args.maps:
            for seed in args.seeds:
                runs = {}
                for arm, more in ARMS.items():
                    folder = Path(tmp) / f"{map_}_{seed}_{len(runs)}".replace(":", "_")
                    runs[arm] = train(map_, seed, args, more, folder)
                    record = runs[arm]
                    steps, checks = record["num_timesteps"], len(record["checks"])
                    print(f"| {map_} | {seed} | {arm} | {steps:,} | {checks} | {record['train_s']} |", flush=True)
                fast, slow = runs["side by side"], runs["one env"]
                ratios.append(fast["train_s"] / slow["train_s"])
                print(f"| {map_} | {seed} | same checks: {fast['checks'] == slow['checks']} | | | {ratios[-1]:.2f} |")
    print(f"median training seconds, side by side / one env: {statistics.median(ratios):.2f} ({len(ratios)} pairs)")


if __name__ == "__main__":
    main()
