"""Scales of the interest and of the preferences during learning (measured in docs/interest.md).

    python scripts/interest_scales.py --env NomadOffice-v0 --seed 0 --steps 300000 --interest paper --preferences raw
    python scripts/interest_scales.py --env CartPole-v1 --seed 0 --steps 100000 --interest paper --preferences raw

Every ``--window`` rollouts it prints, over the transitions collected in that window: the mean,
median, 90th and 99th percentile and maximum of ``delta+`` (eq. 2), its coefficient of variation
across states, the mean spread (max - min) and standard deviation over the actions of the raw
preferences ``p(s, .)`` on the last rollout's states, the entropy of their untempered softmax, and
the share of actions whose temperature the interest (not a clamp) set. NomadOffice-v0 runs on the
batched office with 16 robots and the zoo file's 2D settings; CartPole-v1 with 8 envs and A2C's defaults.
"""

from __future__ import annotations

import argparse

import numpy as np
import torch as th
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.env_util import make_vec_env

import twodrl_envs  # noqa: F401  (registers the IDs)
from twodrl_bench.algorithms import make_model
from twodrl_bench.algorithms.variants import INTEREST_MODES, PREFERENCE_MODES
from twodrl_zoo.vec_env import make_train_env


class Scales(BaseCallback):
    """Prints the scales of ``delta+`` and of the preferences every ``window`` rollouts."""

    def __init__(self, window: int):
        super().__init__()
        self.window, self.rollouts = window, 0
        self.interests: list[np.ndarray] = []
        self.shares: list[float] = []

    def _on_step(self) -> bool:
        return True

    def _on_rollout_end(self) -> None:
        buffer = self.model.rollout_buffer
        self.interests.append(buffer.interests.ravel().copy())
        self.shares.append(self.model.interest_share(buffer.inverse_temperatures))
        self.rollouts += 1
        if self.rollouts % self.window:
            return
        interest = np.concatenate(self.interests)
        obs = th.as_tensor(buffer.observations.reshape(-1, *self.model.observation_space.shape))
        with th.no_grad():
            logits = self.model.policy.action_net(self.model.policy._actor_latent(obs)).numpy()
        probs = np.exp(logits - logits.max(1, keepdims=True))
        probs /= probs.sum(1, keepdims=True)
        entropy = float(-(probs * np.log(probs + 1e-12)).sum(1).mean())
        q50, q90, q99 = np.quantile(interest, [0.5, 0.9, 0.99])
        row = (
            self.num_timesteps,
            interest.mean(),
            q50,
            q90,
            q99,
            interest.max(),
            interest.std() / max(interest.mean(), 1e-12),
            (logits.max(1) - logits.min(1)).mean(),
            logits.std(1).mean(),
            entropy,
            np.mean(self.shares),
        )
        print(" | ".join(f"{value:.3g}" for value in row), flush=True)
        self.interests, self.shares = [], []


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--env", choices=["NomadOffice-v0", "CartPole-v1"], default="NomadOffice-v0")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--steps", type=int, default=300_000)
    parser.add_argument("--window", type=int, default=250, help="rollouts per printed row")
    parser.add_argument("--interest", choices=INTEREST_MODES, default="relative")
    parser.add_argument("--preferences", choices=PREFERENCE_MODES, default="bounded")
    args = parser.parse_args()
    th.set_num_threads(1)
    modes = dict(interest=args.interest, preferences=args.preferences)
    if args.env == "NomadOffice-v0":
        env = make_train_env("NomadOffice-v0", 16, args.seed)
        settings = dict(gamma=0.9, punishment_gamma=0.1, reward_split="info", **modes)
    else:
        env, settings = make_vec_env(args.env, n_envs=8, seed=args.seed), modes
    model = make_model("twoda2c_variant", env, settings, seed=args.seed)  # the interest modes are variants
    print("steps | d+ mean | median | p90 | p99 | max | cv | pref. spread | pref. sd | H(T=1) | interest share")
    model.learn(args.steps, callback=Scales(args.window))


if __name__ == "__main__":
    main()
