"""What each part of 2D-RL contributes on the paper's task: the ablation of issue 11.

    python scripts/ablation.py --out ablation                        # 10 seeds, 10 epochs of 20k steps
    python scripts/ablation.py --out ablation --seeds 0 1 --epochs 2  # a quick look

Arms (every setting that is not 2D-RL's is the same in all of them: batched ``NomadOffice-v0`` (``--map``: ``office``,
the default, or ``open``) with 16 robots, ``n_steps=5``, gamma 0.9, ``gae_lambda=1``, learning rate 7e-4, RMSprop, no
entropy bonus, SB3's ``MlpPolicy`` network):

1. ``a2c``: SB3's A2C.
2. ``a2c_fixed``: A2C at a fixed temperature (TwoDimA2C with its 2D parts off: no punishment
   stream, ``punishment_weight=0``; the equivalence test shows this is A2C), the temperature being
   the mean temperature of the ``paper`` arm in the same run of this script; raw preferences.
3. ``twod_fixed``: TwoDimA2C (two critics, the utility) at that fixed temperature: no interest, raw preferences.
4. ``paper``: TwoDimA2C with ``interest="paper", preferences="raw"``: eq. 9 as the paper writes it.
5. ``relative_bounded``: TwoDimA2C with ``interest="relative", preferences="bounded"`` (the no-freeze option).
6. ``relative_raw``: the relative interest with raw preferences (which of the two changes does what).

Protocol, fixed before any run: an epoch is ``--epoch-steps`` learning steps, then one test
episode on each of ``--test-robots`` robots of a separately seeded batched office with the
stochastic policy (``predict(deterministic=False)``). Per run: final test goal rate (last epoch),
learned (final goal rate >= 0.8), the goal rate of the greedy policy (``deterministic=True``,
after the last epoch), epochs to a 0.5 goal rate, shortcut share and reward per step of
the last epoch, collapse (a goal rate >= 0.8 followed by 3 or more epochs below 0.5), and the
share of learning steps on which the interest, not a clamp, set the temperature. Per arm: the
mean over seeds with a 95% t-interval (Wilson for counts). Runs one at a time; each finished run
is a line of ``runs.jsonl`` in ``--out`` and is not run again; the table goes to ``table.md``,
the figure to ``ablation.png``.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import torch as th
from scipy import stats
from stable_baselines3 import A2C
from stable_baselines3.common.callbacks import BaseCallback

from envs.nomad.batched import make_sb3_vec_env
from sb3_twodrl import TwoDimA2C
from sb3_twodrl.callbacks import EpisodeTracker, summarize_episodes

ARMS = ("a2c", "a2c_fixed", "twod_fixed", "paper", "relative_bounded", "relative_raw")
SHARED = dict(n_steps=5, gamma=0.9, gae_lambda=1.0, learning_rate=7e-4, ent_coef=0.0, device="cpu")
TWO_DIM = dict(punishment_gamma=0.1, reward_split="info")
METRICS = (
    "learned",
    "final_goal_rate",
    "greedy_goal_rate",
    "epochs_to_half",
    "shortcut_share",
    "reward_per_step",
    "interest_share",
)


def whole_reward(reward: float, info: dict[str, Any]) -> tuple[float, float]:
    """A2C's view of the office: the whole reward ``r_R - r_P`` in the reward stream, no punishment."""
    return reward, 0.0


def make_model(arm: str, seed: int, temperature: float | None, map_name: str = "office") -> A2C:
    env = make_sb3_vec_env(16, seed=seed, map=map_name)
    if arm == "a2c":
        return A2C("MlpPolicy", env, seed=seed, **SHARED)
    if arm == "a2c_fixed":
        degenerate = dict(punishment_weight=0.0, punishment_vf_coef=0.0, reward_split=whole_reward)
        return TwoDimA2C(
            "MlpPolicy", env, temperature=temperature, preferences="raw", seed=seed, **degenerate, **SHARED
        )
    if arm == "twod_fixed":
        return TwoDimA2C("MlpPolicy", env, temperature=temperature, preferences="raw", seed=seed, **TWO_DIM, **SHARED)
    modes = {
        "paper": dict(interest="paper", preferences="raw"),
        "relative_bounded": dict(interest="relative", preferences="bounded"),
        "relative_raw": dict(interest="relative", preferences="raw"),
    }[arm]
    return TwoDimA2C("MlpPolicy", env, seed=seed, **modes, **TWO_DIM, **SHARED)


def run_test_episodes(
    model: A2C, robots: int, seed: int, deterministic: bool = False, map_name: str = "office"
) -> dict[str, float]:
    """One test episode per robot of a batched office seeded with ``seed``; the stochastic policy unless told."""
    env = make_sb3_vec_env(robots, seed=seed, map=map_name)
    with th.random.fork_rng(devices=[]):
        th.manual_seed(seed)
        obs, tracker, records = env.reset(), EpisodeTracker(robots), [None] * robots
        while any(record is None for record in records):
            actions, _ = model.predict(obs, deterministic=deterministic)
            obs, rewards, dones, infos = env.step(actions)
            for idx, record in zip(np.flatnonzero(dones), tracker.step(infos, dones, rewards), strict=True):
                if records[idx] is None:
                    records[idx] = record
    return summarize_episodes(records)


class Epochs(BaseCallback):
    """Test episodes after every ``epoch_steps`` learning steps; the interest's share and mean temperature."""

    def __init__(self, epoch_steps: int, robots: int, seed: int, map_name: str = "office"):
        super().__init__()
        self.epoch_steps, self.robots, self.seed, self.map_name = epoch_steps, robots, seed, map_name
        self.epochs: list[dict[str, float]] = []
        self.inside = self.steps = 0
        self.temperature_sum, self.tempered = 0.0, 0

    def _on_step(self) -> bool:
        if self.num_timesteps >= (len(self.epochs) + 1) * self.epoch_steps:
            seed = 10**6 + 1_000 * self.seed + len(self.epochs)
            self.epochs.append(run_test_episodes(self.model, self.robots, seed, map_name=self.map_name))
        return True

    def _on_rollout_end(self) -> None:
        if not isinstance(self.model, TwoDimA2C):
            return
        inverse = self.model.rollout_buffer.inverse_temperatures
        self.inside += round(self.model.interest_share(inverse) * inverse.size)
        self.steps += inverse.size
        self.temperature_sum += float(np.sum(1.0 / inverse[inverse > 0]))
        self.tempered += int(np.count_nonzero(inverse > 0))


def run(
    arm: str,
    seed: int,
    epochs: int,
    epoch_steps: int,
    robots: int,
    temperature: float | None,
    map_name: str = "office",
) -> dict[str, Any]:
    th.set_num_threads(1)
    model = make_model(arm, seed, temperature, map_name)
    callback = Epochs(epoch_steps, robots, seed, map_name)
    model.learn(epochs * epoch_steps, callback=callback)
    goal_rates = [epoch["goal_rate"] for epoch in callback.epochs]
    last = callback.epochs[-1]
    greedy = run_test_episodes(model, robots, 10**6 + 1_000 * seed + epochs, deterministic=True, map_name=map_name)
    half = next((i + 1 for i, rate in enumerate(goal_rates) if rate >= 0.5), math.nan)
    peak = next((i for i, rate in enumerate(goal_rates) if rate >= 0.8), None)
    below = [rate < 0.5 for rate in goal_rates[peak:]] if peak is not None else []
    longest = max((len(s) for s in "".join("x" if b else " " for b in below).split()), default=0)
    return dict(
        arm=arm,
        seed=seed,
        goal_rates=goal_rates,
        final_goal_rate=last["goal_rate"],
        learned=float(last["goal_rate"] >= 0.8),
        greedy_goal_rate=greedy["goal_rate"],
        epochs_to_half=half,
        shortcut_share=last.get("shortcut_share", math.nan),
        reward_per_step=last["reward_per_step"],
        interest_share=callback.inside / callback.steps if callback.steps else math.nan,
        mean_temperature=callback.temperature_sum / callback.tempered if callback.tempered else math.nan,
        collapsed=float(longest >= 3),
        fixed_temperature=temperature,
    )


def interval(values: list[float], count: bool = False) -> tuple[float, float, float, int]:
    """Mean and 95% interval over seeds (Wilson for a share of seeds, t otherwise), NaNs left out."""
    x = np.array([v for v in values if not math.isnan(v)], dtype=float)
    if not x.size:
        return math.nan, math.nan, math.nan, 0
    mean = float(x.mean())
    if count:
        n, z = x.size, 1.959964
        centre = (mean + z * z / (2 * n)) / (1 + z * z / n)
        half = z * math.sqrt(mean * (1 - mean) / n + z * z / (4 * n * n)) / (1 + z * z / n)
        return mean, centre - half, centre + half, n
    if x.size < 2:
        return mean, math.nan, math.nan, 1
    half = float(stats.t.ppf(0.975, x.size - 1) * x.std(ddof=1) / math.sqrt(x.size))
    return mean, mean - half, mean + half, int(x.size)


def table(runs: list[dict[str, Any]]) -> str:
    lines = ["| arm | seeds | " + " | ".join(METRICS) + " | collapsed | mean T |", "|---" * (len(METRICS) + 4) + "|"]
    for arm in ARMS:
        mine = [r for r in runs if r["arm"] == arm]
        if not mine:
            continue
        cells = []
        for key in METRICS:
            mean, low, high, n = interval([r[key] for r in mine], count=key == "learned")
            digits = 1 if key == "epochs_to_half" else 2 if key != "reward_per_step" else 3
            cells.append("-" if n == 0 else f"{mean:.{digits}f} [{low:.{digits}f}, {high:.{digits}f}] (n={n})")
        collapsed = sum(r["collapsed"] for r in mine)
        temperature = interval([r["mean_temperature"] for r in mine])[0]
        lines.append(f"| {arm} | {len(mine)} | " + " | ".join(cells) + f" | {collapsed:.0f} | {temperature:.2f} |")
    return "\n".join(lines)


def figure(runs: list[dict[str, Any]], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    arms = [arm for arm in ARMS if any(r["arm"] == arm for r in runs)]
    fig, axes = plt.subplots(1, len(METRICS) + 1, figsize=(4 * (len(METRICS) + 1), 3.6))
    for ax, key in zip(axes, METRICS, strict=False):
        for i, arm in enumerate(arms):
            mean, low, high, n = interval([r[key] for r in runs if r["arm"] == arm], count=key == "learned")
            if n:
                error = [[mean - low], [high - mean]] if not math.isnan(low) else None
                ax.bar(i, mean, yerr=error, capsize=4, color=f"C{i}")
        ax.set_xticks(range(len(arms)), arms, rotation=40, ha="right")
        ax.set_title(key)
    ax = axes[-1]
    for i, arm in enumerate(arms):
        curves = np.array([r["goal_rates"] for r in runs if r["arm"] == arm])
        ax.plot(np.arange(1, curves.shape[1] + 1), curves.mean(0), color=f"C{i}", label=arm)
    ax.set_xlabel("epoch")
    ax.set_title("test goal rate (mean over seeds)")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, default=Path("ablation"))
    parser.add_argument("--arms", nargs="+", choices=ARMS, default=list(ARMS))
    parser.add_argument("--seeds", type=int, nargs="+", default=list(range(10)))
    parser.add_argument("--epochs", type=int, default=10)
    parser.add_argument("--epoch-steps", type=int, default=20_000)
    parser.add_argument("--test-robots", type=int, default=32)
    parser.add_argument("--map", default="office", help="office (the default office) or open (the issue-4 office)")
    parser.add_argument("--fixed-temperature", type=float, default=None, help="default: the paper arm's mean T")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    log = args.out / "runs.jsonl"
    runs = [json.loads(line) for line in log.read_text().splitlines()] if log.exists() else []
    order = sorted(args.arms, key=lambda arm: arm != "paper")  # the fixed arms need the paper arm's temperature
    for arm in order:
        temperature = None
        if arm in ("a2c_fixed", "twod_fixed"):
            measured = [r["mean_temperature"] for r in runs if r["arm"] == "paper"]
            temperature = args.fixed_temperature or (float(np.mean(measured)) if measured else None)
            if temperature is None:
                raise ValueError(f"arm {arm} needs --fixed-temperature or runs of the paper arm")
        for seed in args.seeds:
            if any(r["arm"] == arm and r["seed"] == seed for r in runs):
                continue
            result = run(arm, seed, args.epochs, args.epoch_steps, args.test_robots, temperature, args.map)
            runs.append(result)
            with log.open("a") as f:
                f.write(json.dumps(result) + "\n")
            print(f"{arm} seed {seed}: goal rates {result['goal_rates']}", flush=True)
    text = table(runs)
    (args.out / "table.md").write_text(text + "\n")
    print(text)
    figure(runs, args.out / "ablation.png")


if __name__ == "__main__":
    main()
