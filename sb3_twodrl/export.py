"""Export a trained policy's deterministic actor (TorchScript or ONNX): observations -> actions, no SB3 needed.

The module maps a float32 batch of observations ``(n, *obs_shape)`` (``obs_shape`` the policy's ``Box``
observation space's shape, stored in the file's metadata) to int64 actions ``(n,)``: the argmax of the
actor's preferences, which is what ``model.predict(obs, deterministic=True)`` returns. Where it runs::

    import torch
    policy = torch.jit.load("policy.pt")
    action = int(policy(torch.as_tensor(obs, dtype=torch.float32)[None])[0])

With ``--format onnx`` (extra ``onnx``: ``pip install "sb3-twodrl[onnx]"``) the same actor is an
ONNX graph, input ``obs`` float32 ``(n, *obs_shape)``, output ``action`` int64 ``(n,)``; it needs
only onnxruntime::

    import onnxruntime
    session = onnxruntime.InferenceSession("policy.onnx")
    action = int(session.run(["action"], {"obs": obs[None].astype("float32")})[0][0])

The command (``--algo``: the saved model's algorithm, default twoda2c)::

    sb3-twodrl-export model.zip policy.pt [--algo a2c]
    sb3-twodrl-export model.zip policy.onnx --format onnx
"""

from __future__ import annotations

import argparse
import copy
import json
import warnings
from pathlib import Path

import torch as th
from gymnasium import spaces
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.policies import ActorCriticPolicy
from stable_baselines3.common.preprocessing import is_image_space
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


def _checked(model: BaseAlgorithm) -> tuple[ActorCriticPolicy, tuple[int, ...], int]:
    """``model``'s policy, the shape of one observation and the number of actions.

    :raises ValueError: unless the policy is an ``ActorCriticPolicy`` with a ``Box`` observation space that
        is not an image (whose scaling the export leaves out) and a ``Discrete`` action space
    """
    policy = model.policy
    if not isinstance(policy, ActorCriticPolicy):
        raise ValueError(f"model.policy must be an ActorCriticPolicy, got {type(policy).__name__}")
    observation_space, action_space = policy.observation_space, policy.action_space
    if not isinstance(action_space, spaces.Discrete) or not isinstance(observation_space, spaces.Box):
        raise ValueError(
            "export supports Box observations and Discrete actions only, "
            f"got observation_space={observation_space!r}, action_space={action_space!r}"
        )
    if policy.normalize_images and is_image_space(observation_space):
        raise ValueError(f"export does not export image preprocessing, got image observations {observation_space!r}")
    return policy, observation_space.shape, int(action_space.n)


def _actor(policy: ActorCriticPolicy) -> DeterministicActor:
    """A CPU copy of ``policy``'s deterministic actor."""
    actor = DeterministicActor(policy.pi_features_extractor, policy.mlp_extractor.policy_net, policy.action_net)
    return copy.deepcopy(actor).to("cpu").eval()


def _meta(model: BaseAlgorithm, shape: tuple[int, ...], n_actions: int) -> str:
    """What the file holds beside the actor, as JSON: the algorithm, the input's and the output's layout."""
    return json.dumps(
        {
            "algorithm": type(model).__name__,
            "observation_shape": list(shape),
            "n_actions": n_actions,
            "input": f"float32 (n, {', '.join(map(str, shape))})",
            "output": "int64 (n,) argmax action (= model.predict(obs, deterministic=True))",
        }
    )


def export_policy(model: BaseAlgorithm, path: str | Path) -> Path:
    """Write ``model``'s deterministic actor as TorchScript (CPU); returns the path."""
    policy, shape, n_actions = _checked(model)
    scripted = th.jit.script(_actor(policy))
    path = Path(path)
    th.jit.save(scripted, str(path), _extra_files={"meta.json": _meta(model, shape, n_actions)})
    return path


def export_onnx(model: BaseAlgorithm, path: str | Path, opset: int = 17) -> Path:
    """Write ``model``'s deterministic actor as ONNX (input ``obs``, output ``action``, batch axis free).

    Uses torch's TorchScript-based exporter (``dynamo=False``): the newer exporter needs the
    ``onnxscript`` package, which the ``onnx`` extra does not install. The metadata of
    :func:`export_policy` is stored in the graph's ``metadata_props`` under ``meta.json``.
    """
    import onnx

    policy, shape, n_actions = _checked(model)
    path = Path(path)
    example = th.zeros((1, *shape), dtype=th.float32)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", category=DeprecationWarning)
        th.onnx.export(
            _actor(policy),
            (example,),
            str(path),
            dynamo=False,
            input_names=["obs"],
            output_names=["action"],
            dynamic_axes={"obs": {0: "n"}, "action": {0: "n"}},
            opset_version=opset,
        )
    graph = onnx.load(str(path))
    graph.metadata_props.add(key="meta.json", value=_meta(model, shape, n_actions))
    onnx.save(graph, str(path))
    return path


def main(argv: list[str] | None = None) -> None:
    """``sb3-twodrl-export``: load a saved model and write its deterministic actor."""
    from sb3_twodrl import ALGOS
    from sb3_twodrl.cli import require_extra

    parser = argparse.ArgumentParser(
        prog="sb3-twodrl-export", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("model", type=Path, help="saved SB3 model (.zip)")
    parser.add_argument("out", type=Path, help="file to write (.pt for TorchScript, .onnx for ONNX)")
    parser.add_argument("--format", choices=("torchscript", "onnx"), default="torchscript", help="default torchscript")
    parser.add_argument("--algo", choices=sorted(ALGOS), default="twoda2c", help="the model's algorithm (twoda2c)")
    args = parser.parse_args(argv)
    if args.format == "onnx":
        require_extra("onnx", "onnx")
    model = ALGOS[args.algo].load(args.model, device="cpu")
    export = export_onnx if args.format == "onnx" else export_policy
    print(f"wrote {export(model, args.out)}")


if __name__ == "__main__":
    main()
