"""The paper's experiment (section 3.4, figures 3-5) from the command line: ``sb3-twodrl-reproduce``.

Runs every (algo, seed) of a protocol preset through :func:`~twodrl_bench.grid.run_grid`
and writes under ``--out`` (default ``runs/reproduce/<env>``): ``results.csv`` (one row per algo,
seed, epoch), ``pairs/`` (one CSV per finished run), ``checkpoints/`` (running pairs),
``models/<algo>_seed<seed>.zip`` (final models, ``<Algo>.load``), ``tb/<algo>_seed<seed>_0``
(TensorBoard: SB3's keys, ``rollout/*`` metrics, ``test/*`` per epoch), ``config.json``,
``fig3_goal_rate.png``, ``fig4_reward_per_step.png``, ``fig5_route_share.png`` and ``summary.md``.
Running the same command again resumes: finished runs are skipped, interrupted ones continue from
their last checkpoint.

Hyperparameters: the env's entry of the packaged ``<algo>.yml`` (:mod:`sb3_twodrl.hyperparams`), or of the one
in ``--hyperparams-dir``; an env without one is an error.
Ray workers (``--backend ray --ray-address ...``) must be able to import ``sb3_twodrl`` and the env
package; with ``--out`` on a shared file system their checkpoints, models and logs land there too.
"""

from __future__ import annotations

import argparse
import importlib
import os
from pathlib import Path

from sb3_twodrl.hyperparams import hyperparams_path
from twodrl_bench.algos import ALGOS
from twodrl_bench.grid import BACKENDS, check_config, collect_results, pending, run_grid
from twodrl_bench.protocol import PRESETS, RunSpec, load_hyperparams, parse_env_kwargs
from twodrl_bench.vec_env import VEC_ENV_MODES


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--env", default="NomadOfficeMemorable-v0", help="Gymnasium ID (default: %(default)s)")
    p.add_argument("--preset", choices=sorted(PRESETS), default="quick", help="protocol size (default: %(default)s)")
    p.add_argument("--epochs", type=int, help="epochs (overrides the preset)")
    p.add_argument("--learn-episodes", "-K", type=int, help="learning trials per epoch, K (overrides the preset)")
    p.add_argument("--test-episodes", "-M", type=int, help="test trials per epoch, M (overrides the preset)")
    p.add_argument("--seeds", "-S", type=int, help="number of seeds, 0..S-1 (overrides the preset)")
    p.add_argument("--seed-list", type=int, nargs="+", help="explicit seeds (overrides --seeds)")
    p.add_argument("--algos", nargs="+", default=["twoda2c", "a2c"], choices=sorted(ALGOS))
    p.add_argument("--n-envs", type=int, help="parallel learning envs (default: the hyperparams file's n_envs)")
    p.add_argument("--hyperparams-dir", help="folder of <algo>.yml (default: the packaged files)")
    p.add_argument("--env-kwargs", nargs="*", metavar="KEY:VALUE", help="env arguments, e.g. observe_odometry:False")
    p.add_argument("--vec-env", choices=VEC_ENV_MODES, default="auto", help="batched env or DummyVecEnv")
    p.add_argument("--checkpoint-every", type=int, default=10, help="epochs between checkpoints (0: none)")
    p.add_argument("--no-models", action="store_true", help="do not save the final models")
    p.add_argument("--no-tensorboard", action="store_true", help="no TensorBoard logs")
    p.add_argument("--out", help="output folder (default: runs/reproduce/<env>)")
    p.add_argument("--backend", choices=BACKENDS, default="process")
    p.add_argument("--workers", type=int, default=os.cpu_count() or 1, help="parallel runs (default: CPU count)")
    p.add_argument("--ray-address", help="Ray cluster address (e.g. 'auto' or 'ray://host:10001'); default: local")
    p.add_argument("--gym-packages", nargs="*", default=["envs"], help="modules that register the env")
    p.add_argument("--no-plots", action="store_true", help="skip the figures")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    return p.parse_args(argv)


def specs_from_args(args: argparse.Namespace) -> tuple[list[RunSpec], Path, dict]:
    """The run specs, the output folder and the config that :func:`check_config` guards."""
    preset = PRESETS[args.preset]
    epochs = args.epochs or preset["epochs"]
    k = args.learn_episodes or preset["learn_episodes"]
    m = args.test_episodes or preset["test_episodes"]
    seeds = args.seed_list if args.seed_list else list(range(args.seeds or preset["seeds"]))
    out = Path(args.out or Path("runs") / "reproduce" / args.env)
    env_kwargs = parse_env_kwargs(args.env_kwargs)
    hyperparams = {a: load_hyperparams(hyperparams_path(a, args.hyperparams_dir), args.env) for a in args.algos}
    if args.n_envs:
        for hp in hyperparams.values():
            hp["n_envs"] = args.n_envs
    config = {
        "env_id": args.env,
        "epochs": epochs,
        "learn_episodes": k,
        "test_episodes": m,
        "vec_env": args.vec_env,
        "env_kwargs": env_kwargs,
        "hyperparams": {a: {key: repr(v) for key, v in hp.items()} for a, hp in hyperparams.items()},
    }
    specs = [
        RunSpec(
            env_id=args.env,
            algo=a,
            seed=s,
            epochs=epochs,
            learn_episodes=k,
            test_episodes=m,
            hyperparams=hyperparams[a],
            out_dir=str(out),
            gym_packages=list(args.gym_packages),
            vec_env=args.vec_env,
            checkpoint_every=args.checkpoint_every,
            save_model=not args.no_models,
            tensorboard=not args.no_tensorboard,
            env_kwargs=env_kwargs,
        )
        for a in args.algos
        for s in seeds
    ]
    return specs, out, config


def reproduce(argv: list[str] | None = None) -> Path:
    """Run (or resume) the grid of ``argv``; the output folder."""
    args = parse_args(argv)
    for package in args.gym_packages:
        importlib.import_module(package)
    specs, out, config = specs_from_args(args)
    check_config(out, config)
    todo = pending(specs)
    if len(todo) < len(specs):
        print(f"resuming: {len(specs) - len(todo)} of {len(specs)} (algo, seed) runs already finished in {out}")
    bar = None
    if not args.no_progress:
        from tqdm.auto import tqdm

        total, done = len(specs) * config["epochs"], (len(specs) - len(todo)) * config["epochs"]
        bar = tqdm(total=total, initial=done, unit="epoch", desc=f"{args.env} grid")
    try:
        run_grid(todo, args.backend, args.workers, args.ray_address, on_epoch=None if bar is None else bar.update)
    finally:
        if bar is not None:
            bar.close()
    df = collect_results(out)
    df.to_csv(out / "results.csv", index=False)
    if not args.no_plots:
        from twodrl_bench.plots import make_figures, summary_table, window_table

        k, m = config["learn_episodes"], config["test_episodes"]
        make_figures(df, out, title=f"{args.env}: K={k}, M={m}, {df['seed'].nunique()} seeds")
        summary = summary_table(df, env_id=args.env, k=k, m=m) + "\nBy the paper's epoch windows:\n\n"
        (out / "summary.md").write_text(summary + window_table(df))
    print(f"results: {out / 'results.csv'} ({len(df)} rows)")
    return out


def main(argv: list[str] | None = None) -> None:
    reproduce(argv)
