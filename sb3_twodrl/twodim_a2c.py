"""TwoDimA2C: the actor-critic of two-dimensional evaluation reinforcement learning (2D-RL)."""

from typing import Any, ClassVar, TypeVar

import numpy as np
import torch as th
from gymnasium import spaces
from stable_baselines3 import A2C
from stable_baselines3.common.buffers import RolloutBuffer
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.policies import BasePolicy
from stable_baselines3.common.type_aliases import GymEnv, MaybeCallback, Schedule
from stable_baselines3.common.utils import explained_variance, obs_as_tensor
from stable_baselines3.common.vec_env import VecEnv
from torch.nn import functional as F

from sb3_twodrl.buffers import TwoDimBufferMixin, TwoDimDictRolloutBuffer, TwoDimRolloutBuffer
from sb3_twodrl.policies import (
    TwoDimActorCriticCnnPolicy,
    TwoDimActorCriticPolicy,
    TwoDimMultiInputPolicy,
)
from sb3_twodrl.splitting import RewardSplit, make_reward_split, split_rewards

SelfTwoDimA2C = TypeVar("SelfTwoDimA2C", bound="TwoDimA2C")


def _flat(values: th.Tensor) -> np.ndarray:
    return values.cpu().numpy().ravel()


def _mean(values: np.ndarray) -> float:
    """``values.mean()`` by way of ``sum``: inside the training loop ``ndarray.mean`` costs several times more."""
    return float(values.sum()) / values.size


def _variance(values: np.ndarray) -> float:
    """``values.var()`` by way of :func:`_mean`, for the same reason."""
    deviations = values - _mean(values)
    return _mean(deviations * deviations)


def _explained_variance(predictions: np.ndarray, targets: np.ndarray) -> float:
    """SB3's ``explained_variance`` (NaN where the targets do not vary) by way of :func:`_variance`."""
    target_variance = _variance(targets)
    return np.nan if target_variance == 0 else 1.0 - _variance(targets - predictions) / target_variance


def _check_unit_interval(name: str, value: float) -> None:
    if not 0.0 <= value <= 1.0:
        raise ValueError(f"{name} must be in [0, 1], got {value!r}")


def _check_non_negative(name: str, value: float) -> None:
    if not value >= 0.0:
        raise ValueError(f"{name} must be >= 0, got {value!r}")


class TwoDimA2C(A2C):
    """
    Two-dimensional evaluation actor-critic (2D-RL, Okada et al., section 2).

    A reward critic ``V_R`` (discount ``gamma``) and a punishment critic ``V_P`` (discount
    ``punishment_gamma``) learn the two evaluations (eq. 3-8). The actor follows the utility
    ``A_R - punishment_weight * A_P`` (eq. 1, 10, with GAE per stream) and, with
    ``temperature="interest"``, acts with a softmax temperature set by the interest
    ``delta+ = |delta_R| + |delta_P|`` (eq. 2, 9) as the ``interest`` and ``preferences`` modes say
    (:mod:`sb3_twodrl.interest`), clamped to ``[min_temperature, max_temperature]``.

    Every argument of SB3's ``A2C`` keeps its meaning and default (``gamma`` discounts the reward
    stream); see ``A2C`` for them.

    :param punishment_gamma: discount of the punishment critic (eq. 4, 6, 8)
    :param punishment_gae_lambda: GAE lambda of the punishment stream; None: ``gae_lambda``
    :param punishment_vf_coef: loss weight of the punishment critic; None: ``vf_coef``
    :param punishment_weight: ``w`` in the utility ``A_R - w * A_P`` (eq. 1 is ``w = 1``)
    :param reward_split: how ``(reward, info)`` becomes ``(r_R, r_P)``: ``"auto"``, ``"info"``,
        ``"cost"``, ``"sign"`` or a callable (see ``sb3_twodrl.splitting``)
    :param temperature: ``"interest"`` (eq. 9, ``T`` set by the interest) or a fixed positive temperature
    :param interest: how the interest sets ``T``: ``"paper"`` (eq. 9 literally: ``T = delta+`` of the
        transition into the state), ``"relative"`` (``delta+`` over its running mean) or ``"learned"``
        (a head's ``E[delta+ | s]`` over the running mean of ``delta+``)
    :param preferences: ``"raw"`` (eq. 9 literally) or ``"bounded"`` (preferences divided by
        ``max(1, their sd over the actions)``, so that ``min_temperature`` bounds how greedy actions get)
    :param interest_coef: loss weight of the ``"learned"`` mode's interest head (its target is ``delta+``)
    :param min_temperature: floor of the interest temperature; keeps the policy from freezing
        into argmax once the critics settle and the interest collapses toward 0
    :param max_temperature: ceiling of the interest temperature
    """

    policy_aliases: ClassVar[dict[str, type[BasePolicy]]] = {
        "MlpPolicy": TwoDimActorCriticPolicy,
        "CnnPolicy": TwoDimActorCriticCnnPolicy,
        "MultiInputPolicy": TwoDimMultiInputPolicy,
    }
    policy: TwoDimActorCriticPolicy
    rollout_buffer: TwoDimRolloutBuffer

    def __init__(
        self,
        policy: str | type[TwoDimActorCriticPolicy],
        env: GymEnv | str,
        learning_rate: float | Schedule = 7e-4,
        n_steps: int = 5,
        gamma: float = 0.99,
        gae_lambda: float = 1.0,
        ent_coef: float = 0.0,
        vf_coef: float = 0.5,
        max_grad_norm: float = 0.5,
        rms_prop_eps: float = 1e-5,
        use_rms_prop: bool = True,
        use_sde: bool = False,
        sde_sample_freq: int = -1,
        rollout_buffer_class: type[RolloutBuffer] | None = None,
        rollout_buffer_kwargs: dict[str, Any] | None = None,
        normalize_advantage: bool = False,
        stats_window_size: int = 100,
        tensorboard_log: str | None = None,
        policy_kwargs: dict[str, Any] | None = None,
        verbose: int = 0,
        seed: int | None = None,
        device: th.device | str = "auto",
        punishment_gamma: float = 0.1,
        punishment_gae_lambda: float | None = None,
        punishment_vf_coef: float | None = None,
        punishment_weight: float = 1.0,
        reward_split: str | RewardSplit = "auto",
        temperature: str | float = "interest",
        interest: str = "paper",
        preferences: str = "raw",
        interest_coef: float = 0.5,
        min_temperature: float = 0.5,
        max_temperature: float = 10.0,
        _init_setup_model: bool = True,
    ):
        self.punishment_gamma = punishment_gamma
        self.punishment_gae_lambda = gae_lambda if punishment_gae_lambda is None else punishment_gae_lambda
        self.punishment_vf_coef = vf_coef if punishment_vf_coef is None else punishment_vf_coef
        self.punishment_weight = punishment_weight
        make_reward_split(reward_split)  # validates
        self.reward_split = reward_split
        for name in ("gamma", "gae_lambda"):
            _check_unit_interval(name, locals()[name])
        for name in ("punishment_gamma", "punishment_gae_lambda"):
            _check_unit_interval(name, getattr(self, name))
        for name in ("ent_coef", "vf_coef"):
            _check_non_negative(name, locals()[name])
        for name in ("punishment_vf_coef", "punishment_weight"):
            _check_non_negative(name, getattr(self, name))
        _check_non_negative("interest_coef", interest_coef)
        self.interest_coef = interest_coef
        policy_kwargs = dict(policy_kwargs or {})
        policy_kwargs.update(
            temperature=temperature,
            interest=interest,
            preferences=preferences,
            min_temperature=min_temperature,
            max_temperature=max_temperature,
        )
        self._carried_interest: tuple[Any, np.ndarray] | None = None
        super().__init__(
            policy,
            env,
            learning_rate=learning_rate,
            n_steps=n_steps,
            gamma=gamma,
            gae_lambda=gae_lambda,
            ent_coef=ent_coef,
            vf_coef=vf_coef,
            max_grad_norm=max_grad_norm,
            rms_prop_eps=rms_prop_eps,
            use_rms_prop=use_rms_prop,
            use_sde=use_sde,
            sde_sample_freq=sde_sample_freq,
            rollout_buffer_class=rollout_buffer_class,
            rollout_buffer_kwargs=rollout_buffer_kwargs,
            normalize_advantage=normalize_advantage,
            stats_window_size=stats_window_size,
            tensorboard_log=tensorboard_log,
            policy_kwargs=policy_kwargs,
            verbose=verbose,
            seed=seed,
            device=device,
            _init_setup_model=_init_setup_model,
        )

    def _setup_model(self) -> None:
        if self.rollout_buffer_class is None:
            is_dict = isinstance(self.observation_space, spaces.Dict)
            self.rollout_buffer_class = TwoDimDictRolloutBuffer if is_dict else TwoDimRolloutBuffer
        if not issubclass(self.rollout_buffer_class, TwoDimBufferMixin):
            raise ValueError(f"rollout_buffer_class must subclass TwoDimBufferMixin, got {self.rollout_buffer_class!r}")
        self.rollout_buffer_kwargs.update(
            punishment_gamma=self.punishment_gamma,
            punishment_gae_lambda=self.punishment_gae_lambda,
            punishment_weight=self.punishment_weight,
        )
        super()._setup_model()

    def _excluded_save_params(self) -> list[str]:
        return [*super()._excluded_save_params(), "_carried_interest"]

    def _interest(
        self,
        rewards: np.ndarray,
        punishments: np.ndarray,
        critics: tuple[np.ndarray, np.ndarray],
        next_critics: tuple[np.ndarray, np.ndarray],
        dones: np.ndarray,
    ) -> np.ndarray:
        """Interest ``|delta_R| + |delta_P|`` (eq. 2, 7, 8) of one vectorised transition, before bootstrapping.

        An env whose episode ended has interest 0: its next state starts a new episode.
        """
        delta_r = rewards + self.gamma * next_critics[0] - critics[0]
        delta_p = punishments + self.punishment_gamma * next_critics[1] - critics[1]
        interest = np.abs(delta_r) + np.abs(delta_p)
        interest[dones] = 0.0
        return interest

    def _interest_at_rollout_start(self) -> np.ndarray:
        """Interest carried over from the previous rollout's last transition, if it led into ``_last_obs``.

        That transition was valued by the critics of the previous rollout at both ends; after a reset
        or a new env there is no such transition (interest 0).
        """
        carried = self._carried_interest
        if carried is None or carried[0] is not self._last_obs:
            return np.zeros(self.n_envs, dtype=np.float32)
        return carried[1]

    def collect_rollouts(
        self,
        env: VecEnv,
        callback: BaseCallback,
        rollout_buffer: RolloutBuffer,
        n_rollout_steps: int,
    ) -> bool:
        """SB3's rollout loop with both evaluation streams and the interest temperature of eq. 9.

        Each step evaluates the state it led to at once: that evaluation gives the transition's
        interest, which sets the temperature of the next action, and it is reused to take that
        action (after the last step, to bootstrap the returns).
        """
        assert self._last_obs is not None, "No previous observation was provided"
        self.policy.set_training_mode(False)
        n_steps = 0
        rollout_buffer.reset()
        callback.on_rollout_start()
        reward_split = make_reward_split(self.reward_split)
        with th.no_grad():
            obs_tensor = obs_as_tensor(self._last_obs, self.device)  # type: ignore[arg-type]
            latent_pi, values, punishment_values, predicted = self.policy.evaluate_state(obs_tensor)
        critics = _flat(values), _flat(punishment_values)
        learned = predicted is not None
        inverse_temperature = self.policy.inverse_temperature(
            _flat(predicted) if learned else self._interest_at_rollout_start()
        )

        while n_steps < n_rollout_steps:
            with th.no_grad():
                distribution = self.policy.tempered_distribution(latent_pi, inverse_temperature)
                actions = distribution.get_actions()
                log_probs = distribution.log_prob(actions)
            actions = actions.cpu().numpy().reshape((-1, *self.action_space.shape))  # type: ignore[misc]

            clipped_actions = actions
            if isinstance(self.action_space, spaces.Box):
                if self.policy.squash_output:
                    clipped_actions = self.policy.unscale_action(clipped_actions)
                else:
                    clipped_actions = np.clip(actions, self.action_space.low, self.action_space.high)

            new_obs, rewards, dones, infos = env.step(clipped_actions)
            self.num_timesteps += env.num_envs

            callback.update_locals(locals())
            if not callback.on_step():
                return False

            self._update_info_buffer(infos, dones)
            n_steps += 1

            if isinstance(self.action_space, spaces.Discrete):
                actions = actions.reshape(-1, 1)

            with th.no_grad():
                obs_tensor = obs_as_tensor(new_obs, self.device)  # type: ignore[arg-type]
                if n_steps < n_rollout_steps:
                    latent_pi, *next_values, predicted = self.policy.evaluate_state(obs_tensor)
                else:  # only the critics are needed after the last step, to bootstrap the returns
                    next_values = self.policy.predict_critics(obs_tensor)
            next_critics = _flat(next_values[0]), _flat(next_values[1])
            rewards, punishments = split_rewards(reward_split, rewards, infos, self.num_timesteps)
            interest = self._interest(rewards, punishments, critics, next_critics, dones)
            self.policy.update_interest_scale(interest, dones)
            # Bootstrap both critics on time-limit truncation, as SB3 does (GitHub issue #633)
            for idx, done in enumerate(dones):
                if (
                    done
                    and infos[idx].get("terminal_observation") is not None
                    and infos[idx].get("TimeLimit.truncated", False)
                ):
                    terminal_obs = self.policy.obs_to_tensor(infos[idx]["terminal_observation"])[0]
                    with th.no_grad():
                        terminal_value, terminal_punishment_value = self.policy.predict_critics(terminal_obs)
                    rewards[idx] += self.gamma * terminal_value[0]
                    punishments[idx] += self.punishment_gamma * terminal_punishment_value[0]

            rollout_buffer.add(
                self._last_obs,  # type: ignore[arg-type]
                actions,
                rewards,
                self._last_episode_starts,  # type: ignore[arg-type]
                values,
                log_probs,
                punishment=punishments,
                punishment_value=critics[1],
                inverse_temperature=inverse_temperature,
            )
            self._last_obs = new_obs  # type: ignore[assignment]
            self._last_episode_starts = dones
            (values, punishment_values), critics = next_values, next_critics
            if n_steps < n_rollout_steps:
                inverse_temperature = self.policy.inverse_temperature(_flat(predicted) if learned else interest)

        rollout_buffer.compute_returns_and_advantage(
            last_values=values, dones=dones, last_punishment_values=punishment_values
        )
        self._carried_interest = (new_obs, interest)
        self.policy.update_running_interest(_mean(rollout_buffer.interests))

        callback.update_locals(locals())
        callback.on_rollout_end()
        return True

    def interest_share(self, inverse_temperatures: np.ndarray) -> float:
        """Share of actions whose temperature the interest set: strictly between the clamps, not uniform.

        0 at a fixed ``temperature``.
        """
        if self.policy.temperature != "interest":
            return 0.0
        low, high = np.float32(1.0 / self.policy.max_temperature), np.float32(1.0 / self.policy.min_temperature)
        inside = (inverse_temperatures > low) & (inverse_temperatures < high)
        return int(np.count_nonzero(inside)) / inverse_temperatures.size

    def train(self) -> None:
        """One gradient step: actor on the utility (eq. 1, 10), each critic on its own TD(lambda) target."""
        self.policy.set_training_mode(True)
        self._update_learning_rate(self.policy.optimizer)

        for rollout_data in self.rollout_buffer.get(batch_size=None):
            actions = rollout_data.actions
            if isinstance(self.action_space, spaces.Discrete):
                actions = actions.long().flatten()

            values, punishment_values, predicted, log_prob, entropy = self.policy.evaluate_actions_two_dim(
                rollout_data.observations, actions
            )
            advantages = rollout_data.advantages
            if self.normalize_advantage:
                advantages = (advantages - advantages.mean()) / (advantages.std() + 1e-8)

            policy_loss = -(advantages * log_prob).mean()
            value_loss = F.mse_loss(rollout_data.returns, values.flatten())
            punishment_value_loss = F.mse_loss(rollout_data.punishment_returns, punishment_values.flatten())
            entropy_loss = -th.mean(-log_prob) if entropy is None else -th.mean(entropy)

            loss = (
                policy_loss
                + self.ent_coef * entropy_loss
                + self.vf_coef * value_loss
                + self.punishment_vf_coef * punishment_value_loss
            )
            interest_loss = None
            if predicted is not None:  # the head learns E[delta+ | s] (sb3_twodrl.interest, "learned")
                interest_loss = F.mse_loss(rollout_data.interests, predicted.flatten())
                loss = loss + self.interest_coef * interest_loss
            self.policy.optimizer.zero_grad()
            loss.backward()
            th.nn.utils.clip_grad_norm_(self.policy.parameters(), self.max_grad_norm)
            self.policy.optimizer.step()

        self._n_updates += 1
        self._log_train(policy_loss, value_loss, punishment_value_loss, entropy_loss, interest_loss)

    def _log_train(
        self,
        policy_loss: th.Tensor,
        value_loss: th.Tensor,
        punishment_value_loss: th.Tensor,
        entropy_loss: th.Tensor,
        interest_loss: th.Tensor | None,
    ) -> None:
        buffer = self.rollout_buffer
        self.logger.record("train/n_updates", self._n_updates, exclude="tensorboard")
        # A2C's own key as A2C computes it; the punishment critic's the same, but cheaper
        self.logger.record(
            "train/explained_variance", explained_variance(buffer.values.flatten(), buffer.returns.flatten())
        )
        self.logger.record(
            "train/punishment_explained_variance",
            _explained_variance(buffer.punishment_values, buffer.punishment_returns),
        )
        self.logger.record("train/entropy_loss", entropy_loss.item())
        self.logger.record("train/policy_loss", policy_loss.item())
        self.logger.record("train/value_loss", value_loss.item())
        self.logger.record("train/punishment_value_loss", punishment_value_loss.item())
        self.logger.record("train/interest", _mean(buffer.interests))
        self.logger.record("train/utility", _mean(buffer.utilities))
        if interest_loss is not None:
            self.logger.record("train/interest_loss", interest_loss.item())
        tempered = buffer.inverse_temperatures[buffer.inverse_temperatures > 0]
        if tempered.size:
            self.logger.record("train/temperature", _mean(1.0 / tempered))
        self.logger.record("train/interest_share", self.interest_share(buffer.inverse_temperatures))
        self.logger.record("rollout/punishment_mean", _mean(buffer.punishments))
        if hasattr(self.policy, "log_std"):
            self.logger.record("train/std", th.exp(self.policy.log_std).mean().item())

    def learn(
        self: SelfTwoDimA2C,
        total_timesteps: int,
        callback: MaybeCallback = None,
        log_interval: int = 100,
        tb_log_name: str = "TwoDimA2C",
        reset_num_timesteps: bool = True,
        progress_bar: bool = False,
    ) -> SelfTwoDimA2C:
        return super().learn(
            total_timesteps=total_timesteps,
            callback=callback,
            log_interval=log_interval,
            tb_log_name=tb_log_name,
            reset_num_timesteps=reset_num_timesteps,
            progress_bar=progress_bar,
        )
