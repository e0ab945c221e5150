"""The collapse probe (``results/collapse_probe/``): does training bring an actor that has collapsed onto
driving into the wall back to the goal?

``tests.helpers.toy_envs.LatticeCorridor(6, 3)`` (60-step limit, 4 envs, gamma 0.9), the actor's bias set to
``lead`` for west (the wall at the start) before training, 20k steps; then 20 stochastic test episodes
(goal, crash) and the greedy policy's outcome, one Markdown row per (setting, lead, ``ent_coef``, seed).
It lives beside the corridor it trains on (``tests/helpers/toy_envs.py``, which ``tests/bench/test_interest.py``
also runs the probe's cases on); run from the repository root: ``python -m tests.helpers.collapse_probe
[SETTING ...]`` (default: every setting).
"""

import itertools
import sys
import time

import torch as th
from gymnasium.wrappers import TimeLimit
from stable_baselines3.common.env_util import make_vec_env

from tests.helpers.toy_envs import LatticeCorridor
from twodrl_bench.algorithms.variants import VariantTwoDimA2C as TwoDimA2C  # the interest modes are variants

SETTINGS = {
    "paper (eq. 9), raw": {"interest": "paper"},
    "relative, raw": {"interest": "relative"},
    "relative, bounded": {"interest": "relative", "preferences": "bounded"},
    "learned, raw": {"interest": "learned"},
}


def outcomes(model: TwoDimA2C, deterministic: bool, episodes: int) -> list[str]:
    env = TimeLimit(LatticeCorridor(6, 3), 60)
    ends = []
    for episode in range(episodes):
        obs, _ = env.reset(seed=episode)
        while True:
            action, _ = model.predict(obs, deterministic=deterministic)
            obs, _, terminated, truncated, info = env.step(int(action))
            if terminated or truncated:
                ends.append("goal" if info["is_success"] else "crash" if terminated else "limit")
                break
    return ends


def main() -> None:
    th.set_num_threads(1)
    print("| setting | lead | ent_coef | seed | stochastic goals / 20 | crashes / 20 | greedy | s |")
    print("|---|---|---|---|---|---|---|---|")
    chosen = {name: SETTINGS[name] for name in sys.argv[1:] or SETTINGS}
    for (name, kwargs), lead, ent_coef, seed in itertools.product(chosen.items(), (5.0, 30.0), (0.0, 0.05), range(3)):
        start = time.time()
        env = make_vec_env(lambda: TimeLimit(LatticeCorridor(6, 3), 60), n_envs=4, seed=seed)
        model = TwoDimA2C("MlpPolicy", env, gamma=0.9, ent_coef=ent_coef, seed=seed, **kwargs)
        with th.no_grad():
            model.policy.action_net.bias.copy_(th.tensor([0.0, 0.0, 0.0, lead]))
        model.learn(20_000)
        ends = outcomes(model, deterministic=False, episodes=20)
        greedy = outcomes(model, deterministic=True, episodes=1)[0]
        row = (name, lead, ent_coef, seed, ends.count("goal"), ends.count("crash"), greedy, round(time.time() - start))
        print("| " + " | ".join(map(str, row)) + " |", flush=True)


if __name__ == "__main__":
    main()
