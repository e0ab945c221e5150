#!/usr/bin/env python
"""The baseline's settings search as ``docs/reproduce.md`` ran it: ``sb3-twodrl-search`` over n_envs x
learning rate x n_steps x ent_coef, ranked by the mean test goal rate. Any other grid, e.g. PPO's:

    sb3-twodrl-search --algo ppo --grid learning_rate:3e-4,1e-3,3e-3 n_epochs:4,10 \
        --set n_steps:16 batch_size:256 n_envs:64 --epochs 20 --score-epochs 11 20
"""

import argparse

from twodrl_bench.search import main


def translate() -> list[str]:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--env", default="NomadOfficeMemorable-v0")
    p.add_argument("--algo", default="a2c")
    p.add_argument("--n-envs", nargs="+", default=["16", "64", "256"])
    p.add_argument("--learning-rates", nargs="+", default=["7e-4", "3e-3"])
    p.add_argument("--n-steps", nargs="+", default=["5"])
    p.add_argument("--ent-coefs", nargs="+", help="default: the YAML's")
    p.add_argument("--epochs", default="8")
    p.add_argument("--learn-episodes", "-K", default="1000")
    p.add_argument("--test-episodes", "-M", default="100")
    p.add_argument("--seeds", nargs="+", default=["0", "1"])
    p.add_argument("--workers", default="2")
    p.add_argument("--out", default="runs/search_baseline")
    a = p.parse_args()
    grid = [f"n_envs:{','.join(a.n_envs)},", f"learning_rate:{','.join(a.learning_rates)},"]
    grid += [f"n_steps:{','.join(a.n_steps)},"] + ([f"ent_coef:{','.join(a.ent_coefs)},"] if a.ent_coefs else [])
    run = [
        "--epochs",
        a.epochs,
        "-K",
        a.learn_episodes,
        "-M",
        a.test_episodes,
        "--seeds",
        *a.seeds,
        "--workers",
        a.workers,
        "--out",
        a.out,
    ]
    return ["--env", a.env, "--algo", a.algo, "--grid", *grid, "--rank-by", "goal_rate", *run]


if __name__ == "__main__":
    main(translate())
