"""The installed zoo commands: ``sb3-twodrl-train`` and ``sb3-twodrl-enjoy`` (rl-zoo3's ``train`` and ``enjoy``).

Both register ``twoda2c`` and ``twodppo`` (:func:`twodrl_zoo.zoo.register_zoo`) and import the installed env packages
that list themselves under the ``sb3_twodrl.gym_packages`` entry points (:func:`twodrl_zoo.zoo.import_gym_packages`),
so their env IDs work from any folder without ``--gym-packages``; every rl-zoo3 option is kept, and
``--num-threads`` defaults to 1 (rl-zoo3's default keeps torch's thread count: several times slower for these small
networks on a shared machine, docs/zoo.md); ``sb3-twodrl-train``'s ``--n-eval-envs`` defaults to
:data:`twodrl_zoo.manager.SIDE_BY_SIDE` (a goal check's episodes side by side on a batched env).
``sb3-twodrl-train`` reads the packaged ``<algo>.yml`` (:mod:`twodrl_zoo.hyperparams`) for a2c, ppo, twoda2c and
twodppo unless ``-conf/--conf-file`` names another file. A command whose extra is missing exits, before any work,
with the ``pip install`` line that adds it (:func:`require_extra`). ``sb3-twodrl-enjoy`` without ``pygame`` (the
``render`` extra: gymnasium's window) replays headless, as with ``--no-render``, and says so.
"""

from __future__ import annotations

import difflib
import importlib
import importlib.util
import runpy
import sys
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from twodrl_zoo.hyperparams import Resolved

__all__ = [
    "RENDER_MODULE",
    "ZOO_MODULES",
    "check_command_line",
    "enjoy",
    "export_line",
    "given_options",
    "has_screen",
    "replay_options",
    "report_goal_rate",
    "require_extra",
    "train",
    "verdict",
]

ZOO_MODULES = ("rl_zoo3", "optuna", "pandas", "requests")
"""What the ``zoo`` extra installs and the commands import (rl-zoo3's enjoy imports ``requests`` undeclared)."""
RENDER_MODULE = "pygame"
"""What rl-zoo3's enjoy needs to show the env in a window (gymnasium's human rendering); the ``render`` extra."""


def require_extra(extra: str, *modules: str) -> None:
    """Exit (status 1) naming ``pip install "sb3-twodrl[<extra>]"`` if one of ``modules`` cannot be imported."""
    missing = []
    for module in modules:
        try:
            importlib.import_module(module)
        except ImportError:
            missing.append(module)
    if missing:
        sys.exit(
            f"{', '.join(missing)} not installed: this command needs the '{extra}' extra, "
            f'pip install "sb3-twodrl[{extra}]"'
        )


def train(argv: list[str] | None = None) -> None:
    """``sb3-twodrl-train``: rl-zoo3's ``train`` with the 2D-RL algorithms, the packaged hyperparameters and this
    project's :class:`~twodrl_zoo.manager.ExperimentManager` (the task's settings, goal checks, batched envs); then
    the goal rate of the saved policy (:func:`report_goal_rate`)."""
    require_extra("zoo", *ZOO_MODULES)
    import rl_zoo3.train

    from twodrl_zoo.manager import SIDE_BY_SIDE, ExperimentManager
    from twodrl_zoo.zoo import has_option, prepare_zoo_argv, run_zoo_entry

    argv = prepare_zoo_argv(sys.argv[1:] if argv is None else argv, packaged_conf=True)
    options = check_command_line("sb3-twodrl-train", argv)
    if not has_option(argv, "--num-threads"):
        argv += ["--num-threads", "1"]
    if not has_option(argv, "--n-eval-envs"):
        argv += ["--n-eval-envs", str(SIDE_BY_SIDE)]
    zoo_manager = rl_zoo3.train.ExperimentManager
    rl_zoo3.train.ExperimentManager = ExperimentManager  # type: ignore[misc]
    try:
        run_zoo_entry("sb3-twodrl-train", argv, rl_zoo3.train.train)
    finally:
        rl_zoo3.train.ExperimentManager = zoo_manager  # type: ignore[misc]
    if not has_option(argv, "-optimize", "--optimize-hyperparameters"):
        report_goal_rate(argv, options)


def check_command_line(prog: str, argv: list[str]) -> dict[str, dict[str, Any]]:
    """The command line's ``key:value`` options, parsed, after checking what would otherwise fail deep in rl-zoo3
    with a traceback: the env ID, the ``key:value`` literals and the env's options (a map, a database). Exits with
    one line naming what is wrong."""
    import gymnasium as gym

    from twodrl_zoo.zoo import dict_options, option_value

    try:
        _, given = dict_options(argv)
    except (NameError, SyntaxError, ValueError) as error:
        sys.exit(
            f"{prog}: a key:value option is not a Python literal ({error}); quote strings twice, "
            """e.g. --env-kwargs map:'"my_office.json"'"""
        )
    budget = option_value(argv, "-n", "--n-timesteps")
    if budget is not None and not (budget.lstrip("+").isdigit() and int(budget) > 0):
        sys.exit(f"{prog}: -n/--n-timesteps must be a positive number of steps, got {budget!r}")
    env_id = option_value(argv, "--env")
    if env_id is not None and env_id not in gym.registry:
        close = difflib.get_close_matches(env_id, list(gym.registry), n=1)
        sys.exit(f"{prog}: env {env_id!r} is not registered" + (f"; did you mean {close[0]!r}?" if close else ""))
    if env_id is not None:
        resolved = given_options(given)
        for option, options in (("--env-kwargs", resolved.env_kwargs), ("--eval-env-kwargs", resolved.eval_env_kwargs)):
            if option == "--eval-env-kwargs" and not given[option]:
                continue  # the env of --env-kwargs, made just above
            try:
                gym.make(env_id, **options).close()
            except (ValueError, TypeError, FileNotFoundError) as error:
                sys.exit(f"{prog}: {env_id} with {option} {given[option]}: {error}")
    return given


def given_options(given: dict[str, dict[str, Any]]) -> Resolved:
    """The command line's env options (``given``, :func:`check_command_line`) in the one precedence
    (:func:`twodrl_zoo.hyperparams.resolve`): ``--env-kwargs`` for training, ``--eval-env-kwargs`` over them for
    tests."""
    from twodrl_zoo.hyperparams import resolve

    return resolve({}, None, env_kwargs=given["--env-kwargs"], eval_env_kwargs=given["--eval-env-kwargs"])


def report_goal_rate(argv: list[str], given: dict[str, dict[str, Any]], episodes: int = 20) -> float | None:
    """Run ``episodes`` deterministic test episodes of the model ``train`` just saved (the run folder its manager
    saved, :data:`twodrl_zoo.manager.SAVED`; :func:`twodrl_zoo.evaluation.run_episodes`); print the goal rate, the
    verdict and the export line.

    The test env is the run's evaluation env (``goal_checks.json``: the command's options with the task's test
    options, e.g. a map's start). The line says which policy it is: the goal check it was kept at (steps, goal rate)
    and how long training took. The goal rate is the share of episodes whose last ``info["is_success"]`` is true;
    an env that never sets it gets no line (None). One verdict follows (:func:`verdict`), never two that disagree.
    """
    import json
    import math
    import os

    from rl_zoo3.utils import ALGOS, create_test_env, get_saved_hyperparams

    from twodrl_zoo.evaluation import goal_rate, run_episodes
    from twodrl_zoo.manager import CHECKS_FILE, SAVED
    from twodrl_zoo.zoo import option_value

    algo, env_id = option_value(argv, "--algo") or "ppo", option_value(argv, "--env") or "CartPole-v1"
    if not SAVED:
        return None
    log_path = SAVED[-1]
    model_path = os.path.join(log_path, f"{env_id}.zip")
    if not os.path.isfile(model_path):
        return None
    with open(os.path.join(log_path, CHECKS_FILE)) as f:
        record = json.load(f)
    hyperparams, stats_path = get_saved_hyperparams(os.path.join(log_path, env_id), norm_reward=False, test_mode=True)
    env = create_test_env(
        env_id,
        n_envs=1,
        stats_path=stats_path,
        seed=int(option_value(argv, "--seed") or 0),
        log_dir=None,
        should_render=False,
        hyperparams=hyperparams,
        env_kwargs=record["test_env_kwargs"] or given_options(given).eval_env_kwargs,
    )
    model = ALGOS[algo].load(model_path, device="cpu")
    rate = goal_rate(run_episodes(model, env, per_env=episodes))
    env.close()
    if math.isnan(rate):
        return None
    reached = round(rate * episodes)
    kept = record["kept"]
    which = (
        f"the policy of the check at {kept['timesteps']:,} steps (goal rate {kept['goal_rate']:.2f}), "
        if kept
        else "the final policy, "
    )
    stop = "stopped once learned" if record["learned_at"] is not None else "budget spent"
    print(
        f"sb3-twodrl-train: goal rate {rate:.2f} ({reached} of {episodes} deterministic test episodes) of {which}"
        f"trained {record['num_timesteps']:,} of {record['n_timesteps']:,} steps ({stop}) in {record['train_s']:.0f} s"
    )
    print(f"sb3-twodrl-train: {verdict(rate, record)}")
    print(f"sb3-twodrl-train: export: {export_line(algo, env_id, model_path, given['--env-kwargs'])}")
    return rate


def export_line(algo: str, env_id: str, model_path: str, env_kwargs: dict[str, Any]) -> str:
    """The ``sb3-twodrl-export`` command (ONNX) for the model at ``model_path``, as a shell takes it: with the env's
    input stage (readings as the robot measures them) where its class offers one."""
    import json

    from twodrl_zoo.hyperparams import env_class

    line = f"sb3-twodrl-export {model_path} policy.onnx --format onnx --algo {algo}"
    if hasattr(env_class(env_id)[0], "deploy_input"):
        line += f" --input-stage {env_id}"
        if env_kwargs:
            quoted = (f"{k}:'{json.dumps(v)}'" if isinstance(v, str) else f"{k}:{v!r}" for k, v in env_kwargs.items())
            line += " --env-kwargs " + " ".join(quoted)
    return line


def verdict(rate: float, record: dict[str, Any]) -> str:
    """What the final test's goal ``rate`` and the run's goal checks (``goal_checks.json``'s ``record``) say, in one
    sentence: learned (on recorded readings: which a robot's may not match, so the robot's goal rate may differ);
    the checks passed but the test did not (readings that vary from visit to visit); or no check passed (nothing
    learned is kept), with what to try."""
    from sb3_twodrl.callbacks import SUCCESS_THRESHOLD

    threshold = record.get("threshold", SUCCESS_THRESHOLD)
    checks, passed = record["checks"], record.get("passed")
    if not checks:
        return f"learned (the final test reaches {threshold})" if rate >= threshold else f"below {threshold}"
    best = max(c["goal_rate"] for c in checks)
    if passed is None:
        passed = best >= threshold
    if passed and rate >= threshold and record.get("readings_vary"):
        return (
            f"learned on the recorded readings: the goal checks and the final test reach {threshold}; a robot's own "
            "readings differ from them, so its goal rate may be lower: drive it from the start before relying on it "
            "(docs/own_office.md, step 5)"
        )
    if passed and rate >= threshold:
        return f"learned: the goal checks and the final test reach {threshold}"
    if passed:
        return (
            f"the goal checks reached {threshold} ({record.get('check_episodes', '?')} episodes each) but the final "
            f"test reads {rate:.2f}: the readings vary from visit to visit, so the policy may also reach the goal less "
            "often on the robot; train again (another --seed) or record more readings per cell"
        )
    return (
        f"NOT learned: no goal check reached {threshold} in {record['num_timesteps']:,} steps (the best: {best:.2f}); "
        "the saved policy is the best check's, not a learned one, and sb3-twodrl-export will say so. Check that the "
        "map is learnable on exact readings (the same command with --env NomadOffice-v0), then train the database "
        "longer (-n twice the budget) or with the progress signal (--env-kwargs progress:0.05); docs/own_office.md "
        "says what each setting does"
    )


def enjoy(argv: list[str] | None = None) -> None:
    """``sb3-twodrl-enjoy``: rl-zoo3's ``enjoy`` (``-f`` defaults to ``logs``, train's folder).

    It replays as the train command tests: with the test options of the run's task (:func:`replay_options`: a map's
    start and its time limit, not the training options), under what ``--env-kwargs`` gives.
    ``--record -o videos`` records a video instead (rl-zoo3's ``record_video``, needs ``moviepy``; the env must
    support ``render_mode="rgb_array"``). Without ``pygame`` it replays headless (``--no-render``) and says how to
    get the window; without a screen (:func:`has_screen`) it replays headless too and says so.
    """
    require_extra("zoo", *ZOO_MODULES)
    from twodrl_zoo.zoo import has_option, prepare_zoo_argv, run_zoo_entry

    argv = prepare_zoo_argv(sys.argv[1:] if argv is None else argv)
    if not has_option(argv, "-f", "--folder"):
        argv += ["-f", "logs"]
    check_command_line("sb3-twodrl-enjoy", argv)
    argv = replay_options(argv)
    if "--record" in argv:
        try:
            importlib.import_module("moviepy")
        except ImportError:
            sys.exit("moviepy not installed: --record needs it, pip install moviepy")
        argv.remove("--record")
        argv = _import_gym_packages(argv)  # record_video has no --gym-packages option
        run_zoo_entry("sb3-twodrl-enjoy", argv, lambda: runpy.run_module("rl_zoo3.record_video", run_name="__main__"))
        return
    from rl_zoo3.enjoy import enjoy as zoo_enjoy

    if "--no-render" not in argv and importlib.util.find_spec(RENDER_MODULE) is None:
        print(
            f"{RENDER_MODULE} not installed: replaying without a window (--no-render); for one, "
            'pip install "sb3-twodrl[render]"',
            file=sys.stderr,
        )
        argv.append("--no-render")
    elif "--no-render" not in argv and not has_screen():
        print(
            "no screen (DISPLAY and WAYLAND_DISPLAY unset): replaying without a window (--no-render); "
            "--record -o videos writes a video instead",
            file=sys.stderr,
        )
        argv.append("--no-render")
    if not has_option(argv, "--num-threads"):
        argv += ["--num-threads", "1"]
    run_zoo_entry("sb3-twodrl-enjoy", argv, zoo_enjoy)


def has_screen() -> bool:
    """Whether a window can open: not on Linux without ``DISPLAY`` or ``WAYLAND_DISPLAY`` (a server, CI, ssh)."""
    import os

    return not sys.platform.startswith("linux") or bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def replay_options(argv: list[str]) -> list[str]:
    """``argv`` of an enjoy command with ``--env-kwargs`` holding the test options of the run's task, as
    :func:`twodrl_zoo.hyperparams.resolve` orders them: the training options saved in the run's ``args.yml`` < the
    task's test options < the ``--env-kwargs`` of ``argv`` (the user's test options). Unchanged where the run or its
    ``args.yml`` is not found (rl-zoo3 then says so)."""
    import os

    import yaml
    from rl_zoo3.utils import get_latest_run_id

    from twodrl_zoo.hyperparams import derived_settings, resolve
    from twodrl_zoo.zoo import dict_options, option_value

    algo, env_id = option_value(argv, "--algo"), option_value(argv, "--env")
    folder = option_value(argv, "-f", "--folder") or "logs"
    if algo is None or env_id is None:
        return argv
    exp_id = int(option_value(argv, "--exp-id") or 0) or get_latest_run_id(os.path.join(folder, algo), env_id)
    args_file = os.path.join(folder, algo, f"{env_id}_{exp_id}", env_id, "args.yml")
    if not os.path.isfile(args_file):
        return argv
    with open(args_file) as f:
        trained = (yaml.load(f, Loader=yaml.UnsafeLoader) or {}).get("env_kwargs") or {}
    rest, given = dict_options(argv)
    derived = derived_settings(env_id, trained)
    options = resolve({"env_kwargs": trained}, derived, eval_env_kwargs=given["--env-kwargs"]).eval_env_kwargs
    if not options:
        return argv
    for option in ("--eval-env-kwargs", "--hyperparams"):
        if given[option]:
            rest += [option, *(f"{key}:{value!r}" for key, value in given[option].items())]
    return [*rest, "--env-kwargs", *(f"{key}:{value!r}" for key, value in options.items())]


def _import_gym_packages(argv: list[str]) -> list[str]:
    """Import the modules after ``--gym-packages`` and drop the option (for rl-zoo3's ``record_video``)."""
    if "--gym-packages" not in argv:
        return argv
    i = argv.index("--gym-packages")
    j = i + 1
    while j < len(argv) and not argv[j].startswith("-"):
        importlib.import_module(argv[j])
        j += 1
    return argv[:i] + argv[j:]
