"""TwoDimA2C: the actor-critic of two-dimensional evaluation reinforcement learning (2D-RL) on SB3's A2C."""

from typing import Any, ClassVar, TypeVar

import torch as th
from gymnasium import spaces
from stable_baselines3 import A2C
from stable_baselines3.common.buffers import RolloutBuffer
from stable_baselines3.common.distributions import Distribution
from stable_baselines3.common.policies import ActorCriticPolicy, BasePolicy
from stable_baselines3.common.type_aliases import GymEnv, MaybeCallback, Schedule
from stable_baselines3.common.utils import explained_variance
from torch.nn import functional as F

from sb3_twodrl.a2c.policies import CnnPolicy, MlpPolicy, MultiInputPolicy
from sb3_twodrl.common.buffers import TwoDimRolloutBuffer
from sb3_twodrl.common.on_policy import TwoDimOnPolicyMixin
from sb3_twodrl.common.policies import TEMPERED_SCORES, TwoDimActorCriticPolicy
from sb3_twodrl.common.splitting import RewardSplit

SelfTwoDimA2C = TypeVar("SelfTwoDimA2C", bound="TwoDimA2C")

ACTOR_UPDATES = ("log_prob", *TEMPERED_SCORES, "preference")


class TwoDimA2C(TwoDimOnPolicyMixin, A2C):
    """
    Two-dimensional evaluation actor-critic (2D-RL, Okada et al., section 2).

    A reward critic ``V_R`` (discount ``gamma``) and a punishment critic ``V_P`` (discount
    ``punishment_gamma``) learn the two evaluations (eq. 3-8). The actor follows the utility
    ``A_R - punishment_weight * A_P`` (eq. 1, 10, with GAE per stream) and, with
    ``temperature="interest"``, acts with a softmax temperature set by the interest
    ``delta+ = |delta_R| + |delta_P|`` (eq. 2, 9) as the ``interest`` and ``preferences`` modes say
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
    :param temperature: ``"interest"`` (eq. 9, ``T`` set by the interest) or a fixed positive temperature
    :param interest: how the interest sets ``T``: ``"learned"`` (default: a head's estimate of
        ``E[delta+ | s]``, the state's "criticality", over the running mean of ``delta+``),
        ``"paper"`` (eq. 9 literally: ``T = delta+`` of the transition into the state) or
        ``"relative"`` (that ``delta+`` over its running mean)
    :param preferences: ``"raw"`` (eq. 9 literally) or ``"bounded"`` (preferences divided by
        ``max(1, their sd over the actions / preference_bound)``, so that ``min_temperature`` bounds how
        greedy actions get)
    :param preference_bound: the largest sd over the actions of ``"bounded"`` preferences
    :param interest_coef: loss weight of the ``"learned"`` mode's interest head (its target is ``delta+``)
    :param actor_update: what the utility corrects: ``"log_prob"`` (the policy gradient of the
        untempered softmax, ``A * grad log pi(a|s)``: off-policy at ``T != 1``), ``"tempered"``
        (the policy gradient of the tempered policy that drew the action, eq. 9: ``A * grad log
        pi_T(a|s)`` at the action's own ``T``, on-policy), ``"compensated"`` (the same, times each
        action's ``T``: on-policy, and per unit of preference the log-prob update's size at any ``T``,
        ``A * (1[a] - pi_T(.|s))`` for a softmax; the entropy bonus likewise; for a Gaussian the same
        as ``"tempered"``), ``"compensated_skip_uniform"`` (default: the same, but no update from an episode's
        uniform first move, ``1/T = 0``, where ``"compensated"`` gives ``A * (1[a] - 1/4)`` whatever
        the policy) or ``"preference"`` (eq. 10 literally, lifted
        to function approximation as the critics' updates are: ``A * grad p(s, a)``, the taken
        action's preference alone; ``Discrete`` actions only)
    :param min_temperature: floor of the interest temperature; keeps the policy from freezing
        into argmax once the critics settle and the interest collapses toward 0
    :param max_temperature: ceiling of the interest temperature
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
        interest: str = "learned",
        preferences: str = "raw",
        preference_bound: float = 1.0,
        interest_coef: float = 0.5,
        actor_update: str = "compensated_skip_uniform",
        _init_setup_model: bool = True,
    ):
        if actor_update not in ACTOR_UPDATES:
            raise ValueError(f"actor_update must be one of {ACTOR_UPDATES}, got {actor_update!r}")
        self.actor_update = actor_update
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
            interest=interest,
            preferences=preferences,
            preference_bound=preference_bound,
            interest_coef=interest_coef,
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
        if actor_update == "preference" and not isinstance(self.action_space, spaces.Discrete):
            raise ValueError(f"actor_update='preference' needs Discrete actions, got {self.action_space}")

    def _rollout_log_probs(self, latent_pi: th.Tensor, distribution: Distribution, actions: th.Tensor) -> th.Tensor:
        """A2C never reads ``old_log_prob``: the tempered distribution's, which costs no second distribution."""
        return distribution.log_prob(actions)

    def train(self) -> None:
        """One gradient step: actor on the utility (eq. 1, 10), each critic on its own TD(lambda) target."""
        self.policy.set_training_mode(True)
        self._update_learning_rate(self.policy.optimizer)

        for rollout_data in self.rollout_buffer.get(batch_size=None):
            actions = rollout_data.actions
            if isinstance(self.action_space, spaces.Discrete):
                actions = actions.long().flatten()

            values, punishment_values, predicted, score, entropy = self.policy.evaluate_actions_two_dim(
                rollout_data.observations, actions, self.actor_update, rollout_data.inverse_temperatures
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
            if predicted is not None:  # the head learns E[delta+ | s] (sb3_twodrl.common.interest, "learned")
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
