"""Training and test VecEnvs by env ID: a batched env where the registry offers one, else SB3's ``DummyVecEnv``.

An env package offers a batched implementation through Gymnasium's registry: ``register(...,
vector_entry_point="pkg.module:Class")``, where ``Class(num_envs=N, **spec.kwargs,
max_episode_steps=spec.max_episode_steps)`` is a ``gymnasium.vector.VectorEnv`` with same-step
autoreset whose sub-env ``i`` reset with seed ``s + i`` behaves like ``gym.make(env_id)`` reset with
seed ``s + i`` (``twodrl_envs`` registers its ``NomadOffice-v0`` and ``NomadOfficeMemorable-v0`` batches
so). :class:`VectorEnvAdapter` turns it into an SB3 ``VecEnv``; nothing here imports the env
package, which registers its IDs when its name (``gym_packages``) is imported.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.envs.registration import load_env_creator
from gymnasium.vector import AutoresetMode
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.vec_env import DummyVecEnv, VecEnv
from stable_baselines3.common.vec_env.base_vec_env import VecEnvStepReturn

VEC_ENV_MODES = ("auto", "batched", "dummy")
_FINAL_KEYS = ("final_obs", "final_info")


class VectorEnvAdapter(VecEnv):
    """SB3 ``VecEnv`` view of a same-step-autoreset ``gymnasium.vector.VectorEnv`` with array infos.

    Each info key ``k`` (with its mask ``_k``) becomes ``infos[i][k]`` as a Python value (by
    ``tolist``) where the mask is set; at an episode end ``infos[i]`` gets SB3's
    ``terminal_observation`` (from ``final_obs``) and ``TimeLimit.truncated``.
    """

    def __init__(self, venv: gym.vector.VectorEnv) -> None:
        mode = venv.metadata.get("autoreset_mode")
        if mode != AutoresetMode.SAME_STEP:
            raise ValueError(f"venv must reset sub-envs in the same step (AutoresetMode.SAME_STEP), got {mode!r}")
        self.venv = venv
        super().__init__(venv.num_envs, venv.single_observation_space, venv.single_action_space)
        self._actions: np.ndarray = np.zeros(venv.num_envs, dtype=np.int64)

    def reset(self) -> np.ndarray:
        seed = None if self._seeds[0] is None else list(self._seeds)
        obs, _ = self.venv.reset(seed=seed)  # type: ignore[arg-type]  # a seed per sub-env, as gymnasium takes
        self._reset_seeds()
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = np.asarray(actions).reshape((self.num_envs, *(self.action_space.shape or ())))

    def step_wait(self) -> VecEnvStepReturn:
        obs, rewards, terminated, truncated, info = self.venv.step(self._actions)
        dones = terminated | truncated
        infos = self._split_infos(info)
        for i in np.flatnonzero(dones):
            infos[i]["terminal_observation"] = info["final_obs"][i]
            infos[i]["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
        return obs, rewards.astype(np.float32), dones, infos

    def _split_infos(self, info: dict[str, Any]) -> list[dict[str, Any]]:
        """The per-env dicts of a step's info arrays: one ``tolist`` per key, not one per env and key."""
        columns = {k: values.tolist() for k, values in info.items() if not k.startswith("_") and k not in _FINAL_KEYS}
        masks = {key: info[f"_{key}"] for key in columns if f"_{key}" in info}
        everywhere = [key for key in columns if key not in masks or masks[key].all()]
        rows = zip(*(columns[key] for key in everywhere), strict=True) if everywhere else [()] * self.num_envs
        infos = [dict(zip(everywhere, values, strict=True)) for values in rows]
        for key in [key for key in columns if key not in everywhere]:
            for i in np.flatnonzero(masks[key]):
                infos[i][key] = columns[key][i]
        return infos

    def close(self) -> None:
        self.venv.close()

    def get_attr(self, attr_name: str, indices: Any = None) -> list[Any]:
        return [getattr(self.venv, attr_name)] * len(list(self._get_indices(indices)))

    def set_attr(self, attr_name: str, value: Any, indices: Any = None) -> None:
        setattr(self.venv, attr_name, value)

    def env_method(self, method_name: str, *method_args: Any, indices: Any = None, **method_kwargs: Any) -> list[Any]:
        raise NotImplementedError(f"{type(self.venv).__name__} is one batched env: it has no per-env methods")

    def env_is_wrapped(self, wrapper_class: type, indices: Any = None) -> list[bool]:
        return [False] * len(list(self._get_indices(indices)))


def has_batched_env(env_id: str) -> bool:
    """Whether the registry gives ``env_id`` a same-step-autoreset vector entry point."""
    entry_point = gym.spec(env_id).vector_entry_point
    if entry_point is None:
        return False
    creator = entry_point if callable(entry_point) else load_env_creator(entry_point)
    return getattr(creator, "metadata", {}).get("autoreset_mode") == AutoresetMode.SAME_STEP


def _batched(env_id: str, n_envs: int, mode: str) -> bool:
    if mode not in VEC_ENV_MODES:
        raise ValueError(f"vec_env must be one of {VEC_ENV_MODES}, got {mode!r}")
    if mode == "dummy":
        return False
    available = has_batched_env(env_id)
    if mode == "batched" and not available:
        raise ValueError(f"vec_env='batched': {env_id!r} has no same-step-autoreset vector_entry_point in the registry")
    return available


def _vector(env_id: str, n_envs: int, env_kwargs: dict[str, Any] | None) -> VecEnv:
    venv = gym.make_vec(env_id, num_envs=n_envs, vectorization_mode="vector_entry_point", **(env_kwargs or {}))
    return VectorEnvAdapter(venv)


def make_train_env(
    env_id: str, n_envs: int, seed: int, mode: str = "auto", env_kwargs: dict[str, Any] | None = None
) -> VecEnv:
    """``n_envs`` learning envs seeded ``seed + i``: batched (``mode`` ``"auto"``/``"batched"``) or SB3's.

    ``env_kwargs`` go to the env's constructor on top of the registered ones (rl-zoo3's ``env_kwargs``).
    """
    if _batched(env_id, n_envs, mode):
        venv = _vector(env_id, n_envs, env_kwargs)
        venv.seed(seed)
        return venv
    return make_vec_env(env_id, n_envs=n_envs, seed=seed, env_kwargs=env_kwargs)


def make_test_env(env_id: str, n_envs: int, mode: str = "auto", env_kwargs: dict[str, Any] | None = None) -> VecEnv:
    """``n_envs`` test envs (no monitor), one test trial each per call of :func:`run_test_trials`."""
    if _batched(env_id, n_envs, mode):
        return _vector(env_id, n_envs, env_kwargs)
    kwargs = env_kwargs or {}
    return DummyVecEnv([lambda: gym.make(env_id, **kwargs)] * n_envs)
