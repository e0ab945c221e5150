"""The documented extension points (``docs/design.md``, "Extension points"): each overridden by a small
subclass written here, and each override changes what the algorithm does."""

from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch as th
from stable_baselines3.common.type_aliases import Schedule

from sb3_twodrl import TwoDimA2C, TwoDimActorCriticPolicy, TwoDimPPO
from sb3_twodrl.common.fast import build_optimizer


def actor_parameters(model: Any) -> list[th.Tensor]:
    actor = (*model.policy.mlp_extractor.policy_net.parameters(), *model.policy.action_net.parameters())
    return [p.detach().clone() for p in actor]


def moved(before: list[th.Tensor], after: list[th.Tensor]) -> float:
    return max(float((a - b).abs().max()) for a, b in zip(before, after, strict=True))


def learn(model: Any, steps: int) -> tuple[float, Any]:
    """How far ``steps`` of learning move the actor's parameters, and the model."""
    before = actor_parameters(model)
    model.learn(steps)
    return moved(before, actor_parameters(model)), model


class FirstActionPolicy(TwoDimActorCriticPolicy):
    """Preferences that put every action but the first far below it."""

    def action_preferences(self, latent_pi: th.Tensor) -> th.Tensor:
        preferences = super().action_preferences(latent_pi)
        return preferences + th.tensor([0.0, -50.0])


def test_action_preferences_are_what_the_temperature_divides() -> None:
    model = TwoDimA2C(FirstActionPolicy, "CartPole-v1", n_steps=16, seed=0).learn(64)
    assert not model.rollout_buffer.actions.any()  # every action drawn is the first
    plain = TwoDimA2C("MlpPolicy", "CartPole-v1", n_steps=16, seed=0).learn(64)
    assert plain.rollout_buffer.actions.any()


class UniformPolicy(TwoDimActorCriticPolicy):
    """``1 / T = 0`` whatever the interest: every action is drawn uniformly."""

    def inverse_temperature(self, interest: np.ndarray) -> np.ndarray:
        return np.zeros(np.shape(interest), dtype=np.float32)


@pytest.mark.parametrize("algo", [TwoDimA2C, TwoDimPPO])
def test_an_inverse_temperature_of_zero_draws_uniformly_and_leaves_the_actor_alone(algo: type) -> None:
    kwargs = dict(n_steps=16, batch_size=16, n_epochs=2) if algo is TwoDimPPO else dict(n_steps=16)
    distance, model = learn(algo(UniformPolicy, "CartPole-v1", seed=0, **kwargs), 64)
    buffer = model.rollout_buffer
    assert not buffer.inverse_temperatures.any()
    assert not buffer.log_probs.any()  # the stored score of a uniform draw (_rollout_log_prob)
    assert distance == 0.0  # such an action scores 0 (_evaluate_actions), and ent_coef is 0
    assert learn(algo("MlpPolicy", "CartPole-v1", seed=0, **kwargs), 64)[0] > 1e-4


class UnscaledPolicy(TwoDimActorCriticPolicy):
    """Keeps no running scale of the interest."""

    def update_interest_scale(self, interest: np.ndarray, dones: np.ndarray) -> None:
        self.calls = getattr(self, "calls", 0) + 1


def test_update_interest_scale_is_called_each_step() -> None:
    model = TwoDimA2C(UnscaledPolicy, "CartPole-v1", n_steps=8, seed=0).learn(64)
    assert model.policy.calls == 64 and model.policy.running_interest.item() == 0.0
    assert TwoDimA2C("MlpPolicy", "CartPole-v1", n_steps=8, seed=0).learn(64).policy.running_interest.item() > 0


class RecordingPolicy(TwoDimActorCriticPolicy):
    """Records the interest that each temperature is set from."""

    def inverse_temperature(self, interest: np.ndarray) -> np.ndarray:
        self.seen = [*getattr(self, "seen", []), np.array(interest, dtype=np.float32)]
        return super().inverse_temperature(interest)


class TransitionInterestPolicy(RecordingPolicy):
    """No interest head: the temperature follows each transition's ``delta+`` (eq. 9 as written)."""

    def _build(self, lr_schedule: Schedule) -> None:
        super()._build(lr_schedule)
        self.interest_net = None
        self.optimizer = build_optimizer(self, lr_schedule)


@pytest.mark.parametrize("policy", [RecordingPolicy, TransitionInterestPolicy])
def test_without_the_interest_head_the_rollout_passes_each_transitions_interest(policy: type) -> None:
    model = TwoDimA2C(policy, "CartPole-v1", n_steps=6, seed=0).learn(6)  # one rollout, no episode ends
    seen, interests = model.policy.seen, model.rollout_buffer.interests[:, 0]
    assert len(seen) == 6
    if policy is RecordingPolicy:  # the head's I(s), not the transitions'
        assert "interest_net.weight" in model.policy.state_dict()
        assert not np.allclose(np.concatenate(seen[1:]), interests[:5])
    else:  # none before the first transition, then the transition into each state
        assert not any(name.startswith("interest_net") for name in model.policy.state_dict())
        assert seen[0][0] == 0.0
        np.testing.assert_allclose(np.concatenate(seen[1:]), interests[:5], rtol=1e-5)


class ScaledPolicy(TwoDimActorCriticPolicy):
    """A policy argument of its own: the preferences times ``preference_scale``."""

    def __init__(self, *args: Any, preference_scale: float = 1.0, **kwargs: Any):
        self.preference_scale = preference_scale
        super().__init__(*args, **kwargs)

    def _get_constructor_parameters(self) -> dict[str, Any]:
        return {**super()._get_constructor_parameters(), "preference_scale": self.preference_scale}

    def action_preferences(self, latent_pi: th.Tensor) -> th.Tensor:
        return super().action_preferences(latent_pi) * self.preference_scale


class ScaledA2C(TwoDimA2C):
    """Takes the policy's ``preference_scale`` as its own argument."""

    def __init__(self, *args: Any, preference_scale: float = 1.0, **kwargs: Any):
        self.preference_scale = preference_scale
        super().__init__(*args, **kwargs)

    def _policy_two_dim_kwargs(self) -> dict[str, Any]:
        return {**super()._policy_two_dim_kwargs(), "preference_scale": self.preference_scale}


def test_policy_two_dim_kwargs_pass_the_algorithms_own_policy_arguments(tmp_path: Path) -> None:
    model = ScaledA2C(ScaledPolicy, "CartPole-v1", preference_scale=0.0, n_steps=8, seed=0).learn(16)
    assert model.policy.preference_scale == 0.0 and "preference_scale" not in model.policy_kwargs
    # preferences times 0: the softmax is uniform, so each action is drawn at log-probability log(1/2)
    np.testing.assert_allclose(model.rollout_buffer.log_probs, np.log(0.5), rtol=1e-6)
    model.save(tmp_path / "m")
    assert ScaledA2C.load(tmp_path / "m").policy.preference_scale == 0.0
    with pytest.raises(ValueError, match=r"policy_kwargs must not hold \['preference_scale'\]"):
        ScaledA2C(ScaledPolicy, "CartPole-v1", policy_kwargs=dict(preference_scale=2.0))


class CriticOnlyA2C(TwoDimA2C):
    """The actor's score is 0: only the critics learn."""

    def _evaluate_actions(self, observations: Any, actions: th.Tensor, inverse_temperatures: th.Tensor) -> Any:
        values, punishment_values, predicted, score, entropy = super()._evaluate_actions(
            observations, actions, inverse_temperatures
        )
        return values, punishment_values, predicted, score * 0.0, entropy * 0.0


def test_evaluate_actions_is_the_actors_score() -> None:
    model = CriticOnlyA2C("MlpPolicy", "CartPole-v1", n_steps=8, ent_coef=0.01, seed=0)
    critic_before = model.policy.value_net.weight.detach().clone()
    distance, model = learn(model, 64)
    assert distance == 0.0 and not th.equal(critic_before, model.policy.value_net.weight)
    assert learn(TwoDimA2C("MlpPolicy", "CartPole-v1", n_steps=8, ent_coef=0.01, seed=0), 64)[0] > 1e-4


class StaleRatioPPO(TwoDimPPO):
    """Stores each action's score 100 above the truth: every ratio is about ``exp(-100)``."""

    def _rollout_log_prob(
        self, latent_pi: th.Tensor, actions: th.Tensor, log_prob: th.Tensor, inverse_temperature: np.ndarray
    ) -> th.Tensor:
        return super()._rollout_log_prob(latent_pi, actions, log_prob, inverse_temperature) + 100.0


def test_rollout_log_prob_is_the_ratios_denominator() -> None:
    kwargs = dict(n_steps=32, batch_size=32, n_epochs=2, seed=0)
    distance, model = learn(StaleRatioPPO("MlpPolicy", "CartPole-v1", **kwargs), 64)
    assert model.rollout_buffer.log_probs.min() > 90.0
    assert distance < 1e-6  # a ratio of about 0 carries no gradient to the actor
    assert learn(TwoDimPPO("MlpPolicy", "CartPole-v1", **kwargs), 64)[0] > 1e-4
