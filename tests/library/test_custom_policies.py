"""A user's ActorCriticPolicy subclass (as SB3's docs teach) gets the punishment head and the tempered distribution."""

from pathlib import Path

import numpy as np
import pytest
import torch as th
from stable_baselines3.common.policies import ActorCriticPolicy, BasePolicy
from torch import nn

from sb3_twodrl import TwoDimA2C, TwoDimPPO


class CustomNetwork(nn.Module):
    """SB3 docs' "advanced example": separate actor and critic MLPs of their own sizes."""

    def __init__(self, feature_dim: int, last_layer_dim_pi: int = 16, last_layer_dim_vf: int = 8):
        super().__init__()
        self.latent_dim_pi = last_layer_dim_pi
        self.latent_dim_vf = last_layer_dim_vf
        self.policy_net = nn.Sequential(nn.Linear(feature_dim, last_layer_dim_pi), nn.ReLU())
        self.value_net = nn.Sequential(nn.Linear(feature_dim, last_layer_dim_vf), nn.ReLU())

    def forward(self, features: th.Tensor) -> tuple[th.Tensor, th.Tensor]:
        return self.forward_actor(features), self.forward_critic(features)

    def forward_actor(self, features: th.Tensor) -> th.Tensor:
        return self.policy_net(features)

    def forward_critic(self, features: th.Tensor) -> th.Tensor:
        return self.value_net(features)


class CustomActorCriticPolicy(ActorCriticPolicy):
    def __init__(self, *args, **kwargs):
        kwargs["ortho_init"] = False
        super().__init__(*args, **kwargs)

    def _build_mlp_extractor(self) -> None:
        self.mlp_extractor = CustomNetwork(self.features_dim)


@pytest.mark.parametrize("algo", [TwoDimA2C, TwoDimPPO])
def test_custom_actor_critic_subclass_learns_saves_and_loads(algo: type, tmp_path: Path) -> None:
    kwargs = dict(batch_size=16) if algo is TwoDimPPO else {}
    model = algo(CustomActorCriticPolicy, "CartPole-v1", n_steps=16, seed=0, max_temperature=4.0, **kwargs).learn(64)
    policy = model.policy
    assert isinstance(policy, CustomActorCriticPolicy)
    assert isinstance(policy.mlp_extractor, CustomNetwork)
    assert policy.punishment_value_net.in_features == 8
    assert policy.max_temperature == 4.0
    assert np.abs(model.rollout_buffer.inverse_temperatures).sum() > 0

    model.save(tmp_path / "custom.zip")
    loaded = algo.load(tmp_path / "custom.zip")
    assert isinstance(loaded.policy, CustomActorCriticPolicy)
    obs = np.random.default_rng(0).normal(size=(20, 4)).astype(np.float32)
    np.testing.assert_array_equal(loaded.predict(obs, deterministic=True)[0], model.predict(obs, deterministic=True)[0])


def test_a_policy_that_is_no_actor_critic_is_a_clear_error() -> None:
    class OwnPolicy(BasePolicy):
        pass

    with pytest.raises(ValueError, match=r"subclass of stable_baselines3.s ActorCriticPolicy.*punishment critic head"):
        TwoDimA2C(OwnPolicy, "CartPole-v1")
