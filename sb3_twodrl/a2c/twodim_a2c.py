"""TwoDimA2C: the actor-critic of two-dimensional evaluation reinforcement learning (2D-RL) on SB3's A2C."""

from typing import Any, ClassVar, TypeVar

import torch as th
from gymnasium import spaces
from stable_baselines3 import A2C
from stable_baselines3.common.buffers import RolloutBuffer
from stable_baselines3.common.policies import ActorCriticPolicy, BasePolicy
from stable_baselines3.common.type_aliases import GymEnv, MaybeCallback, Schedule
from stable_baselines3.common.utils import explained_variance
from torch.nn import functional as F

from sb3_twodrl.a2c.policies import CnnPolicy, MlpPolicy, MultiInputPolicy
from sb3_twodrl.common.buffers import TwoDimRolloutBuffer
from sb3_twodrl.common.on_policy import TwoDimOnPolicyMixin
from sb3_twodrl.common.policies import TwoDimActorCriticPolicy
from sb3_twodrl.common.splitting import RewardSplit

SelfTwoDimA2C = TypeVar("SelfTwoDimA2C", bound="TwoDimA2C")


class TwoDimA2C(TwoDimOnPolicyMixin, A2C):
    """
    Two-dimensional evaluation actor-critic (2D-RL, Okada et al., section 2).

    A reward critic ``V_R`` (discount ``gamma``) and a punishment critic ``V_P`` (discount
    ``punishment_gamma``) learn the two evaluations (eq. 3-8). The actor follows the utility
    ``A_R - punishment_weight * A_P`` (eq. 1, 10, with GAE per stream) and, with
    ``temperature="interest"``, acts with a softmax temperature set by the interest
    ``delta+ = |delta_R| + |delta_P|`` (eq. 2, 9) on a dimensionless scale
    (:mod:`sb3_twodrl.common.interest`), clamped to ``[min_temperature, max_temperature]``.

    Every argument of SB3's ``A2C`` keeps its meaning and default (``gamma`` discounts the reward
    stream); see ``A2C`` for them.

    :param punishment_gamma: discount of the punishment critic (eq. 4, 6, 8)
    :param punishment_gae_lambda: GAE lambda of the punishment stream; None: ``gae_lambda``
    :param punishment_vf_coef: loss weight of the punishment critic; None: ``vf_coef``
    :param punishment_weight: ``w`` in the utility ``A_R - w * A_P`` (eq. 1 is ``w = 1``)
    :param reward_split: how ``(reward, info)`` becomes ``(r_R, r_P)``: ``"auto"``, ``"info"``,
        ``"cost"``, ``"sign"``, ``"none"`` (``r_R = r``, ``r_P = 0``) or a callable
        (see ``sb3_twodrl.common.splitting``)
    :param temperature: ``"interest"`` (eq. 9: ``T = I(s) / mean(delta+)``, ``I(s)`` a head's
        estimate of ``E[delta+ | s]``, the state's "criticality"; :mod:`sb3_twodrl.common.interest`)
        or a fixed positive temperature
    :param min_temperature: floor of the interest temperature; keeps the policy from freezing
        into argmax once the critics settle and the interest collapses toward 0
    :param max_temperature: ceiling of the interest temperature
    :param interest_coef: loss weight of the interest head ``I(s)`` (its target is ``delta+``)

    The actor's score is that of the tempered policy that drew each action, with the ``1/T`` taken
    out of its gradient, and 0 for an action drawn uniformly (eq. 10 as a policy gradient;
    :meth:`~sb3_twodrl.common.policies.TwoDimPolicyMixin.evaluate_actions_two_dim`). The
    temperature settings are the policy's constructor arguments, passed through (not in ``policy_kwargs``).
    """

    policy_aliases: ClassVar[dict[str, type[BasePolicy]]] = {
        "MlpPolicy": MlpPolicy,
        "CnnPolicy": CnnPolicy,
        "MultiInputPolicy": MultiInputPolicy,
    }
    policy: TwoDimActorCriticPolicy
    rollout_buffer: TwoDimRolloutBuffer

    def __init__(
        self,
        policy: str | type[ActorCriticPolicy],
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
        min_temperature: float = 0.5,
        max_temperature: float = 10.0,
        interest_coef: float = 0.5,
        _init_setup_model: bool = True,
    ):
        policy = self._init_two_dim(
            policy,
            n_steps=n_steps,
            gamma=gamma,
            gae_lambda=gae_lambda,
            ent_coef=ent_coef,
            vf_coef=vf_coef,
            punishment_gamma=punishment_gamma,
            punishment_gae_lambda=punishment_gae_lambda,
            punishment_vf_coef=punishment_vf_coef,
            punishment_weight=punishment_weight,
            reward_split=reward_split,
            temperature=temperature,
            min_temperature=min_temperature,
            max_temperature=max_temperature,
            interest_coef=interest_coef,
            policy_kwargs=policy_kwargs,
        )
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

    def train(self) -> None:
        """One gradient step: actor on the utility (eq. 1, 10), each critic on its own TD(lambda) target."""
        self.policy.set_training_mode(True)
        self._update_learning_rate(self.policy.optimizer)

        for rollout_data in self.rollout_buffer.get(batch_size=None):
            actions = rollout_data.actions
            if isinstance(self.action_space, spaces.Discrete):
                actions = actions.long().flatten()

            values, punishment_values, predicted, score, entropy = self._evaluate_actions(
                rollout_data.observations, actions, rollout_data.inverse_temperatures
            )
            advantages = rollout_data.advantages
            if self.normalize_advantage:
                advantages = (advantages - advantages.mean()) / (advantages.std() + 1e-8)

            policy_loss = -(advantages * score).mean()
            value_loss = F.mse_loss(rollout_data.returns, values.flatten())
            punishment_value_loss = F.mse_loss(rollout_data.punishment_returns, punishment_values.flatten())
            entropy_loss = -th.mean(-score) if entropy is None else -th.mean(entropy)

            loss = (
                policy_loss
                + self.ent_coef * entropy_loss
                + self.vf_coef * value_loss
                + self.punishment_vf_coef * punishment_value_loss
            )
            interest_loss = None
            if predicted is not None:  # the head learns E[delta+ | s] (sb3_twodrl.common.interest)
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
        interest_loss: th.Tensor | None = None,
    ) -> None:
        self.logger.record("train/n_updates", self._n_updates, exclude="tensorboard")
        # A2C's own key as A2C computes it
        self.logger.record(
            "train/explained_variance",
            explained_variance(self.rollout_buffer.values.flatten(), self.rollout_buffer.returns.flatten()),
        )
        self.logger.record("train/entropy_loss", entropy_loss.item())
        self.logger.record("train/policy_loss", policy_loss.item())
        self.logger.record("train/value_loss", value_loss.item())
        if hasattr(self.policy, "log_std"):
            self.logger.record("train/std", th.exp(self.policy.log_std).mean().item())
        self._log_two_dim(punishment_value_loss.item(), None if interest_loss is None else interest_loss.item())

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
