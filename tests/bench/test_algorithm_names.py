"""A name means one class everywhere: the bench's one table extends the library's without overriding a name, its
other names are views of it, rl-zoo3 learns them only through ``register_zoo``, and the epoch protocol's fast stock
arms are named for what they are."""

from __future__ import annotations

import pytest
from stable_baselines3 import A2C, PPO

import sb3_twodrl
from twodrl_bench.algorithms import ALGOS, FAST_PATH, SUFFIXES, algo_class, fast_path, make_model, stock_algo
from twodrl_bench.algorithms.baselines import FastA2C, FastPPO
from twodrl_bench.settings import settings_algo


def test_the_bench_table_extends_the_library_s() -> None:
    assert all(ALGOS[name] is cls for name, cls in sb3_twodrl.ALGOS.items())
    assert ALGOS["a2c"] is A2C and ALGOS["ppo"] is PPO
    assert len(set(ALGOS.values())) == len(ALGOS)  # one name per class
    own = set(ALGOS) - set(sb3_twodrl.ALGOS)
    assert all(settings_algo(name) in sb3_twodrl.ALGOS and name.endswith(SUFFIXES) for name in own)


def test_rl_zoo3_names_are_the_same_classes() -> None:
    utils = pytest.importorskip("rl_zoo3.utils")
    from twodrl_zoo.zoo import register_zoo

    register_zoo(ALGOS)
    assert all(utils.ALGOS[name] is cls for name, cls in ALGOS.items())
    with pytest.raises(ValueError, match="algos: a2c name other classes in rl-zoo3's table"):
        register_zoo({"a2c": PPO})
    assert utils.ALGOS["a2c"] is A2C


def test_the_epoch_protocol_trains_the_stock_arms_on_the_fast_path() -> None:
    """The equivalence (SB3's parameters bit for bit) is tests/bench/test_fast.py's."""
    assert algo_class(fast_path("a2c")) is FastA2C and algo_class(fast_path("ppo")) is FastPPO
    assert fast_path("twoda2c") == "twoda2c" and FAST_PATH == {"a2c": "a2c_fast", "ppo": "ppo_fast"}
    with pytest.raises(ValueError, match=r"algo must be one of \[.*\], got 'a2c_batched'"):
        fast_path("a2c_batched")


def test_each_algorithm_s_stock_is_the_sb3_class_it_extends() -> None:
    stocks = {name: stock_algo(name) for name in ALGOS}
    assert stocks["twoda2c"] == stocks["twoda2c_auto"] == stocks["a2c_fast"] == stocks["twoda2c_variant"] == "a2c"
    assert stocks["twodppo"] == stocks["ppo_auto"] == "ppo" and set(stocks.values()) == {"a2c", "ppo"}


def test_make_model_builds_the_table_s_class_from_settings() -> None:
    model = make_model("a2c_fast", "CartPole-v1", {"policy": "MlpPolicy", "n_steps": 7}, seed=0, device="cpu")
    assert type(model) is FastA2C and model.n_steps == 7 and model.seed == 0
    with pytest.raises(ValueError, match="got 'nope'"):
        make_model("nope", "CartPole-v1")
