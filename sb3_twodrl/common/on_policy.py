"""What 2D-RL adds to an SB3 on-policy algorithm, written once for TwoDimA2C and TwoDimPPO.

:class:`TwoDimOnPolicyMixin` goes before SB3's algorithm class (``class TwoDimA2C(TwoDimOnPolicyMixin,
A2C)``): it validates and stores the 2D-RL arguments, sets up the two-stream buffer and the
policy, collects rollouts with both evaluation streams and the interest temperature (eq. 1-9),
and logs the 2D statistics. The algorithm itself keeps only its ``train``.
"""

from typing import TYPE_CHECKING, Any

import numpy as np
import torch as th
from gymnasium import spaces
from stable_baselines3.common.buffers import RolloutBuffer
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.on_policy_algorithm import OnPolicyAlgorithm
from stable_baselines3.common.policies import ActorCriticPolicy
from stable_baselines3.common.utils import obs_as_tensor
from stable_baselines3.common.vec_env import VecEnv

from sb3_twodrl.common.buffers import TwoDimBufferMixin, TwoDimDictRolloutBuffer, TwoDimRolloutBuffer
from sb3_twodrl.common.policies import (
    TEMPERATURE_ARGUMENTS,
    TwoDimPolicyMixin,
    check_temperature,
    two_dim_policy_class,
)
from sb3_twodrl.common.splitting import RewardSplit, make_reward_split, split_rewards
from sb3_twodrl.common.utils import fast_explained_variance, fast_mean, flat
from sb3_twodrl.common.validation import (
    check_non_negative,
    check_positive_int,
    check_unit_interval,
)

if TYPE_CHECKING:  # what the mixin extends, for the type checker; at run time it goes before that class
    _AlgorithmBase = OnPolicyAlgorithm
else:
    _AlgorithmBase = object


class TwoDimOnPolicyMixin(_AlgorithmBase):
    """
    2D-RL on an SB3 on-policy algorithm: two critics, the utility advantage and the interest temperature.

    The algorithm's ``__init__`` calls :meth:`_init_two_dim` before SB3's ``__init__``. See
    ``TwoDimA2C`` for the arguments.

    Extension points (``docs/design.md``, "Extension points"), beside SB3's own (``collect_rollouts``,
    ``_setup_model``, ...) and the policy's (:class:`~sb3_twodrl.common.policies.TwoDimPolicyMixin`):

    - :meth:`_policy_two_dim_kwargs`: the policy's constructor arguments that the algorithm takes as
      its own (a subclass adding policy arguments adds them here, and they are saved with the algorithm).
    - :meth:`_evaluate_actions`: the critics and the actor's score of a minibatch, which the utility
      multiplies (eq. 10) or, in PPO, whose difference from the rollout's is the log-ratio.
    - :meth:`_rollout_log_prob`: the score stored with each action during the rollout (PPO's ``old_log_prob``).

    An ``ActorCriticPolicy`` subclass passed as ``policy`` that is not a 2D-RL policy yet becomes one by
    :func:`~sb3_twodrl.common.policies.two_dim_policy_class`; a ``TwoDimPolicyMixin`` subclass is used as it is.
    """

    policy: TwoDimPolicyMixin
    rollout_buffer: TwoDimBufferMixin

    def _init_two_dim(
        self,
        policy: str | type[ActorCriticPolicy],
        *,
        n_steps: int,
        gamma: float,
        gae_lambda: float,
        ent_coef: float,
        vf_coef: float,
        punishment_gamma: float,
        punishment_gae_lambda: float | None,
        punishment_vf_coef: float | None,
        punishment_weight: float,
        reward_split: str | RewardSplit,
        temperature: str | float,
        min_temperature: float,
        max_temperature: float,
        interest_coef: float,
        policy_kwargs: dict[str, Any] | None,
    ) -> str | type[ActorCriticPolicy]:
        """Validate and store the 2D-RL arguments; returns the policy, a class made 2D (eq. 3-9) if needed."""
        check_positive_int("n_steps", n_steps)
        for name, value in (("gamma", gamma), ("gae_lambda", gae_lambda), ("punishment_gamma", punishment_gamma)):
            check_unit_interval(name, value)
        if punishment_gae_lambda is not None:
            check_unit_interval("punishment_gae_lambda", punishment_gae_lambda)
        for name, value in (("ent_coef", ent_coef), ("vf_coef", vf_coef), ("punishment_weight", punishment_weight)):
            check_non_negative(name, value)
        if punishment_vf_coef is not None:
            check_non_negative("punishment_vf_coef", punishment_vf_coef)
        make_reward_split(reward_split)  # validates
        check_temperature(temperature, min_temperature, max_temperature)
        check_non_negative("interest_coef", interest_coef)
        self.punishment_gamma = punishment_gamma
        self.punishment_gae_lambda = gae_lambda if punishment_gae_lambda is None else punishment_gae_lambda
        self.punishment_vf_coef = vf_coef if punishment_vf_coef is None else punishment_vf_coef
        self.punishment_weight = punishment_weight
        self.reward_split = reward_split
        self.temperature = temperature
        self.min_temperature = min_temperature
        self.max_temperature = max_temperature
        self.interest_coef = interest_coef
        passed = sorted(set(policy_kwargs or {}) & set(self._policy_two_dim_kwargs()))
        if passed:
            raise ValueError(
                f"policy_kwargs must not hold {passed}: they are {type(self).__name__}'s own arguments, "
                "which it passes to the policy"
            )
        self._carried_interest: tuple[Any, np.ndarray] | None = None
        return policy if isinstance(policy, str) else two_dim_policy_class(policy)

    def _policy_two_dim_kwargs(self) -> dict[str, Any]:
        """The policy's constructor arguments that are the algorithm's own (eq. 9's temperature settings):
        passed to the policy beside ``policy_kwargs``, which must not hold them."""
        return {name: getattr(self, name) for name in TEMPERATURE_ARGUMENTS}

    def _setup_model(self) -> None:
        if not issubclass(self.policy_class, TwoDimPolicyMixin):  # only a file of another algorithm gets here
            raise ValueError(
                f"{type(self).__name__} cannot use the policy class {self.policy_class.__name__}, which has no "
                "punishment critic: if you are loading a file, it holds a model saved by another algorithm "
                "(e.g. stock A2C or PPO); load it with that algorithm's load"
            )
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
        # The policy gets the algorithm's own arguments beside the user's policy_kwargs, which stay as given
        # (SB3's ``load(..., policy_kwargs=...)`` compares them with the file's)
        policy_kwargs = self.policy_kwargs
        self.policy_kwargs = {**policy_kwargs, **self._policy_two_dim_kwargs()}
        try:
            super()._setup_model()
        finally:
            self.policy_kwargs = policy_kwargs

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

    def _rollout_log_prob(
        self, latent_pi: th.Tensor, actions: th.Tensor, log_prob: th.Tensor, inverse_temperature: np.ndarray
    ) -> th.Tensor:
        """The score stored with each action (PPO's ``old_log_prob``), as :meth:`_evaluate_actions` scores it
        with the rollout's parameters, so that PPO's ratio is 1 at the first epoch: the ``log_prob`` under
        the tempered distribution that drew it (eq. 9), 0 for an action drawn uniformly (``1/T = 0``)."""
        if inverse_temperature.all():  # no uniform draw (the algorithms' own temperatures are never 0)
            return log_prob
        return log_prob * th.as_tensor(inverse_temperature > 0, device=log_prob.device)

    def _evaluate_actions(
        self, observations: Any, actions: th.Tensor, inverse_temperatures: th.Tensor
    ) -> tuple[th.Tensor, th.Tensor, th.Tensor | None, th.Tensor, th.Tensor | None]:
        """``V_R``, ``V_P``, ``I(s)`` (None without the head), the actor's score of ``actions`` and the entropy
        (None: the algorithm uses ``-score``) of a minibatch: the policy's
        :meth:`~sb3_twodrl.common.policies.TwoDimPolicyMixin.evaluate_actions_two_dim`."""
        return self.policy.evaluate_actions_two_dim(observations, actions, inverse_temperatures)

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
        action (after the last step, to bootstrap the returns). gSDE's noise is resampled as SB3 does.
        """
        assert self._last_obs is not None, "No previous observation was provided"
        assert isinstance(rollout_buffer, TwoDimBufferMixin), "a 2D-RL rollout needs a TwoDimBufferMixin buffer"
        self.policy.set_training_mode(False)
        n_steps = 0
        rollout_buffer.reset()
        if self.use_sde:
            self.policy.reset_noise(env.num_envs)
        callback.on_rollout_start()
        reward_split = make_reward_split(self.reward_split)
        with th.no_grad():
            obs_tensor = obs_as_tensor(self._last_obs, self.device)
            latent_pi, values, punishment_values, predicted = self.policy.evaluate_state(obs_tensor)
        critics = flat(values), flat(punishment_values)
        # with an interest head, the state's own interest; without, the transition's into it
        inverse_temperature = self.policy.inverse_temperature(
            flat(predicted) if predicted is not None else self._interest_at_rollout_start()
        )

        while n_steps < n_rollout_steps:
            if self.use_sde and self.sde_sample_freq > 0 and n_steps % self.sde_sample_freq == 0:
                self.policy.reset_noise(env.num_envs)
            with th.no_grad():
                sampled, log_probs = self.policy.sample_tempered(latent_pi, inverse_temperature)
                log_probs = self._rollout_log_prob(latent_pi, sampled, log_probs, inverse_temperature)
            actions = sampled.cpu().numpy().reshape((-1, *(self.action_space.shape or ())))

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

            assert not isinstance(new_obs, tuple), "SB3's policies take array or dict observations"
            with th.no_grad():
                obs_tensor = obs_as_tensor(new_obs, self.device)
                if n_steps < n_rollout_steps:
                    latent_pi, next_values, next_punishment_values, predicted = self.policy.evaluate_state(obs_tensor)
                else:  # only the critics are needed after the last step, to bootstrap the returns
                    next_values, next_punishment_values = self.policy.predict_critics(obs_tensor)
            next_critics = flat(next_values), flat(next_punishment_values)
            rewards, punishments = split_rewards(reward_split, rewards, infos, self.num_timesteps)
            interest = self._interest(rewards, punishments, critics, next_critics, dones)
            self.policy.update_interest_scale(interest, dones)
            # Bootstrap both critics on time-limit truncation, as SB3 does (GitHub issue #633)
            for idx in np.flatnonzero(dones):
                if infos[idx].get("terminal_observation") is not None and infos[idx].get("TimeLimit.truncated", False):
                    terminal_obs = self.policy.obs_to_tensor(infos[idx]["terminal_observation"])[0]
                    with th.no_grad():
                        terminal_value, terminal_punishment_value = self.policy.predict_critics(terminal_obs)
                    rewards[idx] += self.gamma * terminal_value[0]
                    punishments[idx] += self.punishment_gamma * terminal_punishment_value[0]

            rollout_buffer.add(
                self._last_obs,
                actions,
                rewards,
                self._last_episode_starts,
                values,
                log_probs,
                punishment=punishments,
                punishment_value=critics[1],
                inverse_temperature=inverse_temperature,
            )
            self._last_obs = new_obs
            self._last_episode_starts = dones
            values, punishment_values, critics = next_values, next_punishment_values, next_critics
            if n_steps < n_rollout_steps:
                inverse_temperature = self.policy.inverse_temperature(
                    flat(predicted) if predicted is not None else interest
                )

        rollout_buffer.compute_returns_and_advantage(
            last_values=values, dones=dones, last_punishment_values=punishment_values
        )
        self._carried_interest = (new_obs, interest)

        callback.update_locals(locals())
        callback.on_rollout_end()
        return True

    def interest_share(self, inverse_temperatures: np.ndarray) -> float:
        """Share of actions whose temperature the interest set: strictly between the clamps, not uniform.

        0 at a fixed ``temperature``.
        """
        if self.temperature != "interest":
            return 0.0
        low, high = np.float32(1.0 / self.max_temperature), np.float32(1.0 / self.min_temperature)
        inside = (inverse_temperatures > low) & (inverse_temperatures < high)
        return int(np.count_nonzero(inside)) / inverse_temperatures.size

    def _log_two_dim(self, punishment_value_loss: float, interest_loss: float | None = None) -> None:
        """Log the 2D statistics of the last rollout beside the algorithm's own keys."""
        buffer = self.rollout_buffer
        if interest_loss is not None:
            self.logger.record("train/interest_loss", interest_loss)
        self.logger.record(
            "train/punishment_explained_variance",
            fast_explained_variance(buffer.punishment_values, buffer.punishment_returns),
        )
        self.logger.record("train/punishment_value_loss", punishment_value_loss)
        self.logger.record("train/interest", fast_mean(buffer.interests))
        self.logger.record("train/utility", fast_mean(buffer.utilities))
        tempered = buffer.inverse_temperatures[buffer.inverse_temperatures > 0]
        if tempered.size:
            self.logger.record("train/temperature", fast_mean(1.0 / tempered))
        self.logger.record("train/interest_share", self.interest_share(buffer.inverse_temperatures))
        self.logger.record("rollout/punishment_mean", fast_mean(buffer.punishments))
