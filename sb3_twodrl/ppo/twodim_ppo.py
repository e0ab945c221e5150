"""TwoDimPPO: two-dimensional evaluation reinforcement learning (2D-RL) on SB3's PPO."""

from typing import Any, ClassVar, TypeVar

import numpy as np
import torch as th
from gymnasium import spaces
from stable_baselines3 import PPO
from stable_baselines3.common.buffers import RolloutBuffer
from stable_baselines3.common.policies import ActorCriticPolicy, BasePolicy
from stable_baselines3.common.type_aliases import GymEnv, MaybeCallback, Schedule
from stable_baselines3.common.utils import explained_variance
from torch.nn import functional as F

from sb3_twodrl.common.buffers import TwoDimRolloutBuffer
from sb3_twodrl.common.on_policy import TwoDimOnPolicyMixin
from sb3_twodrl.common.policies import TwoDimActorCriticPolicy
from sb3_twodrl.common.splitting import RewardSplit
from sb3_twodrl.ppo.policies import CnnPolicy, MlpPolicy, MultiInputPolicy

SelfTwoDimPPO = TypeVar("SelfTwoDimPPO", bound="TwoDimPPO")


def _clipped(values: th.Tensor, old_values: th.Tensor, clip_range_vf: float | None) -> th.Tensor:
    """PPO's value clipping: the new prediction kept within ``clip_range_vf`` of the rollout's (None: no clipping)."""
    if clip_range_vf is None:
        return values
    return old_values + th.clamp(values - old_values, -clip_range_vf, clip_range_vf)


class TwoDimPPO(TwoDimOnPolicyMixin, PPO):
    """
    Two-dimensional evaluation PPO (2D-RL, Okada et al., section 2, with PPO's clipped surrogate).

    The rollout is ``TwoDimA2C``'s: a reward critic ``V_R`` (discount ``gamma``) and a punishment
    critic ``V_P`` (discount ``punishment_gamma``) learn the two evaluations (eq. 3-8), actions are
    drawn at the interest temperature of eq. 9. PPO's clipped surrogate is taken on the utility
    advantage ``A_R - punishment_weight * A_P`` (eq. 1 with GAE per stream; normalised per minibatch
    if ``normalize_advantage``); the ratio is that of the tempered policy that drew each action, its
    gradient with the ``1/T`` taken out and 1 for an action drawn uniformly (``TwoDimA2C``'s score,
    eq. 10 as a policy gradient). Each critic
    regresses on its own TD(lambda) target and, with ``clip_range_vf``, is clipped around its own
    rollout values.

    Every argument of SB3's ``PPO`` keeps its meaning and default (``gamma`` discounts the reward
    stream); see ``PPO`` for them.

    :param punishment_gamma: discount of the punishment critic (eq. 4, 6, 8)
    :param punishment_gae_lambda: GAE lambda of the punishment stream; None: ``gae_lambda``
    :param punishment_vf_coef: loss weight of the punishment critic; None: ``vf_coef``
    :param punishment_weight: ``w`` in the utility ``A_R - w * A_P`` (eq. 1 is ``w = 1``)
    :param reward_split: how ``(reward, info)`` becomes ``(r_R, r_P)``: ``"auto"``, ``"info"``,
        ``"cost"``, ``"sign"``, ``"none"`` (``r_R = r``, ``r_P = 0``) or a callable
        (see ``sb3_twodrl.common.splitting``)
    :param temperature: ``"interest"`` (eq. 9, as ``TwoDimA2C``'s) or a fixed positive temperature
    :param min_temperature: floor of the interest temperature
    :param max_temperature: ceiling of the interest temperature
    :param interest_coef: loss weight of the interest head ``I(s)`` (its target is ``delta+``)
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
        learning_rate: float | Schedule = 3e-4,
        n_steps: int = 2048,
        batch_size: int = 64,
        n_epochs: int = 10,
        gamma: float = 0.99,
        gae_lambda: float = 0.95,
        clip_range: float | Schedule = 0.2,
        clip_range_vf: float | Schedule | None = None,
        normalize_advantage: bool = True,
        ent_coef: float = 0.0,
        vf_coef: float = 0.5,
        max_grad_norm: float = 0.5,
        use_sde: bool = False,
        sde_sample_freq: int = -1,
        rollout_buffer_class: type[RolloutBuffer] | None = None,
        rollout_buffer_kwargs: dict[str, Any] | None = None,
        target_kl: float | None = None,
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
            batch_size=batch_size,
            n_epochs=n_epochs,
            gamma=gamma,
            gae_lambda=gae_lambda,
            clip_range=clip_range,
            clip_range_vf=clip_range_vf,
            normalize_advantage=normalize_advantage,
            ent_coef=ent_coef,
            vf_coef=vf_coef,
            max_grad_norm=max_grad_norm,
            use_sde=use_sde,
            sde_sample_freq=sde_sample_freq,
            rollout_buffer_class=rollout_buffer_class,
            rollout_buffer_kwargs=rollout_buffer_kwargs,
            target_kl=target_kl,
            stats_window_size=stats_window_size,
            tensorboard_log=tensorboard_log,
            policy_kwargs=policy_kwargs,
            verbose=verbose,
            seed=seed,
            device=device,
            _init_setup_model=_init_setup_model,
        )

    def train(self) -> None:
        """PPO's epochs of minibatch updates: clipped surrogate on the utility, each critic on its own target."""
        self.policy.set_training_mode(True)
        self._update_learning_rate(self.policy.optimizer)
        assert callable(self.clip_range)  # a schedule since _setup_model, as clip_range_vf
        clip_range = self.clip_range(self._current_progress_remaining)
        clip_range_vf = None
        if self.clip_range_vf is not None:
            assert callable(self.clip_range_vf)
            clip_range_vf = self.clip_range_vf(self._current_progress_remaining)

        entropy_losses, pg_losses, value_losses, punishment_value_losses, clip_fractions = [], [], [], [], []
        interest_losses: list[float] = []
        continue_training = True
        for epoch in range(self.n_epochs):
            approx_kl_divs = []
            for rollout_data in self.rollout_buffer.get(self.batch_size):
                actions = rollout_data.actions
                if isinstance(self.action_space, spaces.Discrete):
                    actions = rollout_data.actions.long().flatten()

                values, punishment_values, predicted, log_prob, entropy = self._evaluate_actions(
                    rollout_data.observations, actions, rollout_data.inverse_temperatures
                )
                old_log_prob = rollout_data.old_log_prob
                advantages = rollout_data.advantages
                if self.normalize_advantage and len(advantages) > 1:  # SB3 GitHub issue #325
                    advantages = (advantages - advantages.mean()) / (advantages.std() + 1e-8)

                ratio = th.exp(log_prob - old_log_prob)
                policy_loss_1 = advantages * ratio
                policy_loss_2 = advantages * th.clamp(ratio, 1 - clip_range, 1 + clip_range)
                policy_loss = -th.min(policy_loss_1, policy_loss_2).mean()
                pg_losses.append(policy_loss.item())
                clip_fractions.append(th.mean((th.abs(ratio - 1) > clip_range).float()).item())

                values_pred = _clipped(values.flatten(), rollout_data.old_values, clip_range_vf)
                value_loss = F.mse_loss(rollout_data.returns, values_pred)
                value_losses.append(value_loss.item())
                punishment_pred = _clipped(
                    punishment_values.flatten(), rollout_data.old_punishment_values, clip_range_vf
                )
                punishment_value_loss = F.mse_loss(rollout_data.punishment_returns, punishment_pred)
                punishment_value_losses.append(punishment_value_loss.item())

                entropy_loss = -th.mean(-log_prob) if entropy is None else -th.mean(entropy)
                entropy_losses.append(entropy_loss.item())

                loss = (
                    policy_loss
                    + self.ent_coef * entropy_loss
                    + self.vf_coef * value_loss
                    + self.punishment_vf_coef * punishment_value_loss
                )
                if predicted is not None:  # the head learns E[delta+ | s] (sb3_twodrl.common.interest)
                    interest_loss = F.mse_loss(rollout_data.interests, predicted.flatten())
                    interest_losses.append(interest_loss.item())
                    loss = loss + self.interest_coef * interest_loss

                # Approximate reverse KL for early stopping (SB3 GitHub issue #417)
                with th.no_grad():
                    log_ratio = log_prob - old_log_prob
                    approx_kl_div = th.mean((th.exp(log_ratio) - 1) - log_ratio).cpu().numpy()
                    approx_kl_divs.append(approx_kl_div)
                if self.target_kl is not None and approx_kl_div > 1.5 * self.target_kl:
                    continue_training = False
                    if self.verbose >= 1:
                        print(f"Early stopping at step {epoch} due to reaching max kl: {approx_kl_div:.2f}")
                    break

                self.policy.optimizer.zero_grad()
                loss.backward()
                th.nn.utils.clip_grad_norm_(self.policy.parameters(), self.max_grad_norm)
                self.policy.optimizer.step()

            self._n_updates += 1
            if not continue_training:
                break

        # PPO's own keys as PPO computes them
        buffer = self.rollout_buffer
        self.logger.record("train/entropy_loss", np.mean(entropy_losses))
        self.logger.record("train/policy_gradient_loss", np.mean(pg_losses))
        self.logger.record("train/value_loss", np.mean(value_losses))
        self.logger.record("train/approx_kl", np.mean(approx_kl_divs))
        self.logger.record("train/clip_fraction", np.mean(clip_fractions))
        self.logger.record("train/loss", loss.item())
        self.logger.record(
            "train/explained_variance", explained_variance(buffer.values.flatten(), buffer.returns.flatten())
        )
        if hasattr(self.policy, "log_std"):
            self.logger.record("train/std", th.exp(self.policy.log_std).mean().item())
        self.logger.record("train/n_updates", self._n_updates, exclude="tensorboard")
        self.logger.record("train/clip_range", clip_range)
        if clip_range_vf is not None:
            self.logger.record("train/clip_range_vf", clip_range_vf)
        self._log_two_dim(
            float(np.mean(punishment_value_losses)), float(np.mean(interest_losses)) if interest_losses else None
        )

    def learn(
        self: SelfTwoDimPPO,
        total_timesteps: int,
        callback: MaybeCallback = None,
        log_interval: int = 1,
        tb_log_name: str = "TwoDimPPO",
        reset_num_timesteps: bool = True,
        progress_bar: bool = False,
    ) -> SelfTwoDimPPO:
        return super().learn(
            total_timesteps=total_timesteps,
            callback=callback,
            log_interval=log_interval,
            tb_log_name=tb_log_name,
            reset_num_timesteps=reset_num_timesteps,
            progress_bar=progress_bar,
        )
