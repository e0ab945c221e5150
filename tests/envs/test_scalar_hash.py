"""The single env's Python-integer hash equals the batched env's numpy hash (so single == batched stays exact)."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from twodrl_envs.nomad.core import counter_word, episode_key, episode_keys
from twodrl_envs.nomad.sensors import counter_hash

U64 = st.integers(0, 2**64 - 1)


@given(U64, st.integers(0, 10**9))
def test_counter_word_is_word_zero_of_counter_hash(key, step):
    expected = counter_hash(np.array([key], dtype=np.uint64), np.array([step]))[0, 0]
    assert counter_word(key, step) == int(expected)


@given(st.integers(0, 2**63 - 1), st.integers(0, 10**9))
def test_episode_key_matches_episode_keys(base, episode):
    assert episode_key(base, episode) == int(episode_keys(np.array([base], dtype=np.uint64), np.array([episode]))[0])
