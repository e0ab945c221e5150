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

An input stage (``input_stage``, a torch module with an ``input_shape`` and optionally an ``input_dtype``) goes in
front of the actor, so that the graph takes what a device measures and holds the observation's preprocessing: with
``--input-stage ENV_ID`` the command asks the env for it, as its class's ``deploy_input(**env_kwargs)`` (options by
``--env-kwargs key:value``, values as Python literals); the Nomad envs give their sensors' ranges and odometry in cm.
"""

from __future__ import annotations

import argparse
import ast
import copy
import json
import sys
import warnings
from pathlib import Path
from typing import Any

import torch as th
from gymnasium import spaces
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.policies import ActorCriticPolicy
from stable_baselines3.common.preprocessing import is_image_space
from torch import nn


class StagedActor(nn.Module):
    """An input stage, then the actor: raw input -> observation -> action."""

    def __init__(self, stage: nn.Module, actor: nn.Module) -> None:
        super().__init__()
        self.stage = stage
        self.actor = actor

    def forward(self, raw: th.Tensor) -> th.Tensor:
        return self.actor(self.stage(raw))


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


def _staged(
    policy: ActorCriticPolicy, shape: tuple[int, ...], input_stage: nn.Module | None
) -> tuple[nn.Module, tuple[int, ...], th.dtype]:
    """The module to export, the shape of one input and its dtype: the actor, behind ``input_stage`` if given.

    :raises TypeError: if ``input_stage`` is not a torch module with an ``input_shape``
    """
    actor = _actor(policy)
    if input_stage is None:
        return actor, shape, th.float32
    input_shape = getattr(input_stage, "input_shape", None)
    if not isinstance(input_stage, nn.Module) or not isinstance(input_shape, tuple):
        raise TypeError(f"input_stage must be a torch module with an input_shape tuple, got {input_stage!r}")
    dtype: th.dtype = getattr(input_stage, "input_dtype", th.float32)
    return StagedActor(copy.deepcopy(input_stage).to("cpu").eval(), actor), input_shape, dtype


def _meta(model: BaseAlgorithm, shape: tuple[int, ...], dtype: th.dtype, n_actions: int, stage: str) -> str:
    """What the file holds beside the actor, as JSON: the algorithm, the input's and the output's layout."""
    return json.dumps(
        {
            "algorithm": type(model).__name__,
            "observation_shape": list(model.policy.observation_space.shape or ()),
            "input_stage": stage,
            "n_actions": n_actions,
            "input": f"{str(dtype).removeprefix('torch.')} (n, {', '.join(map(str, shape))})",
            "output": "int64 (n,) argmax action (= model.predict(obs, deterministic=True))",
        }
    )


def export_policy(model: BaseAlgorithm, path: str | Path, input_stage: nn.Module | None = None) -> Path:
    """Write ``model``'s deterministic actor (behind ``input_stage``, if given) as TorchScript (CPU); the path."""
    policy, shape, n_actions = _checked(model)
    module, shape, dtype = _staged(policy, shape, input_stage)
    scripted = th.jit.script(module)
    path = Path(path)
    stage = type(input_stage).__name__ if input_stage is not None else ""
    th.jit.save(scripted, str(path), _extra_files={"meta.json": _meta(model, shape, dtype, n_actions, stage)})
    return path


def export_onnx(model: BaseAlgorithm, path: str | Path, opset: int = 17, input_stage: nn.Module | None = None) -> Path:
    """Write ``model``'s deterministic actor (behind ``input_stage``, if given) as ONNX (input ``obs``, output
    ``action``, batch axis free).

    Uses torch's TorchScript-based exporter (``dynamo=False``): the newer exporter needs the
    ``onnxscript`` package, which the ``onnx`` extra does not install. The metadata of
    :func:`export_policy` is stored in the graph's ``metadata_props`` under ``meta.json``.
    """
    import onnx

    policy, shape, n_actions = _checked(model)
    module, shape, dtype = _staged(policy, shape, input_stage)
    path = Path(path)
    example = th.zeros((1, *shape), dtype=dtype)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", category=DeprecationWarning)
        th.onnx.export(
            module,
            (example,),
            str(path),
            dynamo=False,
            input_names=["obs"],
            output_names=["action"],
            dynamic_axes={"obs": {0: "n"}, "action": {0: "n"}},
            opset_version=opset,
        )
    graph = onnx.load(str(path))
    stage = type(input_stage).__name__ if input_stage is not None else ""
    graph.metadata_props.add(key="meta.json", value=_meta(model, shape, dtype, n_actions, stage))
    onnx.save(graph, str(path))
    return path


def deploy_input(env_id: str, env_kwargs: dict[str, Any] | None = None) -> nn.Module:
    """The input stage the env ``env_id`` offers for ``env_kwargs``: its class's ``deploy_input(**options)``.

    :raises ValueError: if the env's class offers none
    """
    from gymnasium.error import Error

    from twodrl_zoo.hyperparams import env_class
    from twodrl_zoo.zoo import import_gym_packages

    import_gym_packages()  # the env packages that register IDs (entry-point group)
    try:
        creator, registered = env_class(env_id)
    except Error as err:
        raise ValueError(f"--input-stage {env_id}: {err}") from err
    offer = getattr(creator, "deploy_input", None)
    if offer is None:
        raise ValueError(f"--input-stage {env_id}: its class {creator!r} offers no deploy_input")
    stage: nn.Module = offer(**{**registered, **(env_kwargs or {})})
    return stage


def _literal_options(pairs: list[str]) -> dict[str, Any]:
    """``key:value`` strings as a dict, each value a Python literal (``map:'"office.json"'``)."""
    options = {}
    for pair in pairs:
        key, sep, value = pair.partition(":")
        if not sep or not key:
            raise ValueError(f"--env-kwargs takes key:value pairs, got {pair!r}")
        try:
            options[key] = ast.literal_eval(value)
        except (ValueError, SyntaxError) as err:
            raise ValueError(f"--env-kwargs {key}: {value!r} is not a Python literal (quote strings: '\"x\"')") from err
    return options


HELP = """Export a trained policy's deterministic actor, TorchScript or ONNX: observations in, actions out.

The graph maps a float32 batch of observations (n, *obs_shape) to int64 actions (n,), the actions
model.predict(obs, deterministic=True) gives. With --format onnx (pip install "sb3-twodrl[onnx]") it needs only
onnxruntime: input "obs", output "action". With --input-stage ENV_ID (the env's options by --env-kwargs, values
as Python literals) the env's input stage goes before the actor: the Nomad envs' graph then takes the robot's
16 sonar and 16 IR ranges and its odometry in cm, float64 (n, 34).

    sb3-twodrl-export logs/twoda2c/NomadOffice-v0_1/NomadOffice-v0.zip policy.pt
    sb3-twodrl-export model.zip policy.onnx --format onnx --input-stage NomadOffice-v0 --env-kwargs map:'"my.json"'
"""


def unlearned_warning(model_path: str | Path) -> str | None:
    """What to warn of when exporting the model at ``model_path``: None, unless the train command's record beside it
    (``goal_checks.json``, :mod:`twodrl_zoo.manager`) shows that no goal check passed."""
    from sb3_twodrl.callbacks import SUCCESS_THRESHOLD
    from twodrl_zoo.manager import CHECKS_FILE

    record_path = Path(model_path).parent / CHECKS_FILE
    if not record_path.is_file():
        return None
    record = json.loads(record_path.read_text())
    checks = record.get("checks") or []
    threshold = record.get("threshold", SUCCESS_THRESHOLD)
    if not checks or record.get("passed", any(c["goal_rate"] >= threshold for c in checks)):
        return None
    best = max(c["goal_rate"] for c in checks)
    return (
        f"no goal check of this run passed ({record_path}: best goal rate {best:.2f} < {threshold} in "
        f"{record['num_timesteps']:,} steps): this policy has not learned its task and will likely not reach the goal"
    )


def main(argv: list[str] | None = None) -> None:
    """``sb3-twodrl-export``: load a saved model and write its deterministic actor (:data:`HELP`)."""
    from sb3_twodrl import ALGOS
    from twodrl_zoo.cli import require_extra

    parser = argparse.ArgumentParser(
        prog="sb3-twodrl-export", description=HELP, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("model", type=Path, help="saved SB3 model (.zip)")
    parser.add_argument("out", type=Path, help="file to write (.pt for TorchScript, .onnx for ONNX)")
    parser.add_argument("--format", choices=("torchscript", "onnx"), default="torchscript", help="default torchscript")
    parser.add_argument("--algo", choices=sorted(ALGOS), default="twoda2c", help="the model's algorithm (twoda2c)")
    parser.add_argument("--input-stage", metavar="ENV_ID", help="put the env's deploy input stage before the actor")
    parser.add_argument("--env-kwargs", nargs="+", default=[], metavar="KEY:VALUE", help="the env's options")
    args = parser.parse_args(argv)
    if args.format == "onnx":
        require_extra("onnx", "onnx")
    stage = None
    if args.input_stage is not None:
        try:
            stage = deploy_input(args.input_stage, _literal_options(args.env_kwargs))
        except ValueError as err:
            parser.error(str(err))
    model = ALGOS[args.algo].load(args.model, device="cpu")
    warning = unlearned_warning(args.model)
    if warning is not None:
        print(f"sb3-twodrl-export: WARNING: {warning}", file=sys.stderr)
    if args.format == "onnx":
        print(f"wrote {export_onnx(model, args.out, input_stage=stage)}")
    else:
        print(f"wrote {export_policy(model, args.out, input_stage=stage)}")


if __name__ == "__main__":
    main()
