"""Export a trained policy for the robot (TorchScript or ONNX): readings -> action, no SB3 needed.

The module maps a float32 batch of observations ``(n, 34)`` (16 sonar, 16 IR normalised as in
``docs/nomad.md``, then odometry x, y in [0, 1]; ``(n, 32)`` for ``observe_odometry=False``) to
int64 actions ``(n,)`` (0 N, 1 E, 2 S, 3 W): the argmax of the actor's preferences, which is
what ``model.predict(obs, deterministic=True)`` returns. On the robot::

    import torch
    policy = torch.jit.load("policy.pt")
    action = int(policy(torch.as_tensor(obs, dtype=torch.float32)[None])[0])

With ``--format onnx`` (extra ``onnx``: ``pip install "sb3-twodrl[onnx]"``) the same actor is an
ONNX graph, input ``obs`` float32 ``(n, obs_dim)``, output ``action`` int64 ``(n,)``; the robot needs
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


def _actor(model: BaseAlgorithm) -> DeterministicActor:
    policy = model.policy
    if not isinstance(policy.action_space, spaces.Discrete) or not isinstance(policy.observation_space, spaces.Box):
        raise ValueError("export_policy supports Box observations and Discrete actions only")
    if policy.normalize_images and len(policy.observation_space.shape) == 3:
        raise ValueError("export_policy does not export image preprocessing")
    actor = DeterministicActor(policy.pi_features_extractor, policy.mlp_extractor.policy_net, policy.action_net)
    return copy.deepcopy(actor).to("cpu").eval()


def _meta(model: BaseAlgorithm) -> dict[str, object]:
    policy = model.policy
    return {
        "algorithm": type(model).__name__,
        "observation_shape": list(policy.observation_space.shape),
        "actions": ["north", "east", "south", "west"][: int(policy.action_space.n)],
        "input": "float32 (n, obs_dim): 16 sonar (r-40)/560, 16 IR r/40, then odometry scaled by the map bounds",
        "output": "int64 (n,) argmax action (= model.predict(obs, deterministic=True))",
    }


def export_policy(model: BaseAlgorithm, path: str | Path) -> Path:
    """Write ``model``'s deterministic actor as TorchScript (CPU); returns the path."""
    scripted = th.jit.script(_actor(model))
    path = Path(path)
    th.jit.save(scripted, str(path), _extra_files={"meta.json": json.dumps(_meta(model))})
    return path


def export_onnx(model: BaseAlgorithm, path: str | Path, opset: int = 17) -> Path:
    """Write ``model``'s deterministic actor as ONNX (input ``obs``, output ``action``, batch axis free).

    Uses torch's TorchScript-based exporter (``dynamo=False``): the newer exporter needs the
    ``onnxscript`` package, which the ``onnx`` extra does not install. The metadata of
    :func:`export_policy` is stored in the graph's ``metadata_props`` under ``meta.json``.
    """
    import onnx

    actor = _actor(model)
    path = Path(path)
    example = th.zeros((1, *model.policy.observation_space.shape), dtype=th.float32)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", category=DeprecationWarning)
        th.onnx.export(
            actor,
            (example,),
            str(path),
            dynamo=False,
            input_names=["obs"],
            output_names=["action"],
            dynamic_axes={"obs": {0: "n"}, "action": {0: "n"}},
            opset_version=opset,
        )
    graph = onnx.load(str(path))
    graph.metadata_props.add(key="meta.json", value=json.dumps(_meta(model)))
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
