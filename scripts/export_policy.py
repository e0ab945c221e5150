"""Export a trained policy as a TorchScript module for the robot: readings -> action, no SB3 needed.

The module maps a float32 batch of observations ``(n, 34)`` (16 sonar, 16 IR normalised as in
``docs/nomad.md``, then odometry x, y in [0, 1]; ``(n, 32)`` for ``observe_odometry=False``) to
int64 actions ``(n,)`` (0 N, 1 E, 2 S, 3 W): the argmax of the actor's preferences, which is
what ``model.predict(obs, deterministic=True)`` returns. On the robot::

    import torch
    policy = torch.jit.load("policy.pt")
    action = int(policy(torch.as_tensor(obs, dtype=torch.float32)[None])[0])

    PYTHONPATH=. python scripts/export_policy.py model.zip policy.pt [--algo a2c]
"""

from __future__ import annotations

import argparse
import copy
import json
from pathlib import Path

import torch as th
from gymnasium import spaces
from stable_baselines3.common.base_class import BaseAlgorithm
from torch import nn


class DeterministicActor(nn.Module):
    """Features extractor, actor MLP and action head of an SB3 actor-critic policy; argmax action."""

    def __init__(self, features: nn.Module, policy_net: nn.Module, action_net: nn.Module) -> None:
        super().__init__()
        self.features = features
        self.policy_net = policy_net
        self.action_net = action_net

    def forward(self, obs: th.Tensor) -> th.Tensor:
        logits = self.action_net(self.policy_net(self.features(obs.float())))
        return th.argmax(logits, dim=-1)


def export_policy(model: BaseAlgorithm, path: str | Path) -> Path:
    """Write ``model``'s deterministic actor as TorchScript (CPU); returns the path."""
    policy = model.policy
    if not isinstance(policy.action_space, spaces.Discrete) or not isinstance(policy.observation_space, spaces.Box):
        raise ValueError("export_policy supports Box observations and Discrete actions only")
    if policy.normalize_images and len(policy.observation_space.shape) == 3:
        raise ValueError("export_policy does not export image preprocessing")
    actor = DeterministicActor(policy.pi_features_extractor, policy.mlp_extractor.policy_net, policy.action_net)
    actor = actor.to("cpu").eval()
    scripted = th.jit.script(copy.deepcopy(actor))
    meta = {
        "algorithm": type(model).__name__,
        "observation_shape": list(policy.observation_space.shape),
        "actions": ["north", "east", "south", "west"][: int(policy.action_space.n)],
        "input": "float32 (n, obs_dim): 16 sonar (r-40)/560, 16 IR r/40, then odometry scaled by the map bounds",
        "output": "int64 (n,) argmax action (= model.predict(obs, deterministic=True))",
    }
    path = Path(path)
    th.jit.save(scripted, str(path), _extra_files={"meta.json": json.dumps(meta)})
    return path


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("model", type=Path, help="saved SB3 model (.zip)")
    parser.add_argument("out", type=Path, help="TorchScript file to write (.pt)")
    parser.add_argument("--algo", choices=("twodim", "a2c"), default="twodim", help="TwoDimA2C (default) or A2C")
    args = parser.parse_args(argv)
    if args.algo == "twodim":
        from sb3_twodrl import TwoDimA2C as Algo
    else:
        from stable_baselines3 import A2C as Algo
    model = Algo.load(args.model, device="cpu")
    print(f"wrote {export_policy(model, args.out)}")


if __name__ == "__main__":
    main()
