"""A name means one class everywhere: the bench's table joins the library's and its own without overriding a name,
rl-zoo3's names are the same classes, and the epoch protocol's fast stock arms are named for what they are."""

from __future__ import annotations

import pytest
from stable_baselines3 import A2C, PPO

import sb3_twodrl
from twodrl_bench.algorithms import ALGOS, FAST_PATH, epoch_class
from twodrl_bench.algorithms.auto_entropy import AUTO_ENTROPY_ALGOS
from twodrl_bench.algorithms.baselines import BASELINE_ALGOS, BatchedA2C, BatchedPPO
from twodrl_bench.algorithms.variants import VARIANT_ALGOS


def test_the_bench_table_joins_tables_that_share_no_name() -> None:
    tables = (sb3_twodrl.ALGOS, BASELINE_ALGOS, VARIANT_ALGOS, AUTO_ENTROPY_ALGOS)
    assert sum(len(table) for table in tables) == len(ALGOS)
    assert all(ALGOS[name] is cls for name, cls in sb3_twodrl.ALGOS.items())
    assert ALGOS["a2c"] is A2C and ALGOS["ppo"] is PPO


def test_rl_zoo3_names_are_the_same_classes() -> None:
    utils = pytest.importorskip("rl_zoo3.utils")
    from twodrl_zoo.zoo import register_zoo

    register_zoo()
    assert all(utils.ALGOS[name] is ALGOS[name] for name in set(utils.ALGOS) & set(ALGOS))


def test_the_epoch_protocol_trains_the_stock_arms_on_the_fast_path() -> None:
    """The equivalence (SB3's parameters bit for bit) is tests/bench/test_fast.py's."""
    assert epoch_class("a2c") is BatchedA2C and epoch_class("ppo") is BatchedPPO
    assert epoch_class("twoda2c") is sb3_twodrl.TwoDimA2C and set(FAST_PATH.values()) == set(BASELINE_ALGOS)
