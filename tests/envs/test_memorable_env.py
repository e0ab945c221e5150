"""NomadOfficeMemorable-v0: replay env semantics, ideal K=1 equivalence, determinism, batched."""

from collections import Counter

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from hypothesis import given
from hypothesis import strategies as st

from tests.envs.test_nomad_batched import assert_batched_equals_singles
from twodrl_envs import MAX_EPISODE_STEPS
from twodrl_envs.memorable.database import SensorDatabase
from twodrl_envs.memorable.env import HOLD_OUT, BatchedNomadOfficeMemorable, NomadOfficeMemorableEnv, split_readings
from twodrl_envs.memorable.recording import record_database
from twodrl_envs.nomad import sensors
from twodrl_envs.nomad.core import office_core
from twodrl_zoo.vec_env import make_train_env


@pytest.fixture(scope="module")
def ideal_db():
    return record_database(1)


def _rollout(env, actions, seed):
    obs, _ = env.reset(seed=seed)
    out = [(obs, 0.0, False, False, None)]
    for a in actions:
        obs, r, term, trunc, info = env.step(a)
        out.append((obs, r, term, trunc, info))
        if term or trunc:
            obs, _ = env.reset()
            out.append((obs, 0.0, False, False, None))
    return out


def test_check_env_and_registration():
    env = gym.make("twodrl_envs:NomadOfficeMemorable-v0")
    check_env(env.unwrapped, skip_render_check=True)
    assert env.spec.max_episode_steps == MAX_EPISODE_STEPS
    assert env.observation_space.shape == (34,)
    check_env(NomadOfficeMemorableEnv(observe_odometry=False), skip_render_check=True)


def test_ideal_k1_database_gives_exactly_the_ideal_observations(ideal_db):
    rng = np.random.default_rng(0)
    actions = rng.integers(0, 4, size=3000)
    # bias eastwards so episodes go through the shortcut and sometimes reach the goal
    actions[rng.random(3000) < 0.4] = 1
    ideal = _rollout(gym.make("twodrl_envs:NomadOffice-v0"), actions, seed=5)
    replay = _rollout(gym.make("twodrl_envs:NomadOfficeMemorable-v0", database=ideal_db), actions, seed=5)
    assert len(ideal) == len(replay)
    for (o1, r1, t1, u1, i1), (o2, r2, t2, u2, i2) in zip(ideal, replay, strict=True):
        assert o1.dtype == o2.dtype and np.array_equal(o1, o2)
        assert (r1, t1, u1) == (r2, t2, u2)
        assert i1 == i2
    infos = [step[4] for step in ideal if step[4] is not None]
    assert any(i["collision"] for i in infos)


def test_observations_are_recorded_readings_of_the_cell():
    env = NomadOfficeMemorableEnv()
    db = env.robot.database
    core = env.core
    obs, _ = env.reset(seed=1)
    seen = set()
    rng = np.random.default_rng(1)
    for _ in range(300):
        cell = env._cell
        rows = env.robot.readings[db.offsets[cell] : db.offsets[cell] + db.counts[cell]]
        match = np.flatnonzero((rows == obs[:32]).all(axis=1))
        assert len(match) == 1
        seen.add((cell, int(match[0])))
        assert np.array_equal(obs[32:], core.odometry(core.lattice.cells[cell]))
        obs, _, term, trunc, _ = env.step(int(rng.integers(4)))
        if term or trunc:
            obs, _ = env.reset()
    cells_seen = {c for c, _ in seen}
    assert len(seen) > len(cells_seen)  # different recordings of the same cell do turn up


def test_seeded_determinism():
    actions = np.random.default_rng(2).integers(0, 4, size=400)
    a = _rollout(gym.make("twodrl_envs:NomadOfficeMemorable-v0"), actions, seed=11)
    b = _rollout(gym.make("twodrl_envs:NomadOfficeMemorable-v0"), actions, seed=11)
    c = _rollout(gym.make("twodrl_envs:NomadOfficeMemorable-v0"), actions, seed=12)
    assert all(np.array_equal(x[0], y[0]) and x[1:4] == y[1:4] for x, y in zip(a, b, strict=True))
    assert any(not np.array_equal(x[0], y[0]) for x, y in zip(a, c, strict=False))


def test_unrecorded_cells_are_obstacles(ideal_db):
    core = office_core()
    east = core.lattice.index((70.0, 85.0))
    counts = ideal_db.counts.copy()
    counts[east] = 0
    keep = np.repeat(counts > 0, ideal_db.counts)
    db = SensorDatabase(ideal_db.cells, counts, ideal_db.ranges_cm[keep], ideal_db.metadata)
    env = NomadOfficeMemorableEnv(database=db)
    env.reset(seed=0)
    _, reward, term, _, info = env.step(1)  # east of the start: free on the map, never recorded
    assert term and info["collision"] and reward == -1.0
    env.reset(seed=0)
    _, reward, term, _, info = env.step(0)  # north: recorded
    assert not term and reward == pytest.approx(-0.01)
    with pytest.raises(ValueError, match="not a recorded lattice cell"):
        env.reset(options={"position": (70.0, 85.0)})


def test_batched_matches_single_envs():
    n, seed, steps = 4, 7, 300
    batched = BatchedNomadOfficeMemorable(n)
    singles = [gym.make("twodrl_envs:NomadOfficeMemorable-v0") for _ in range(n)]
    rng = np.random.default_rng(3)
    assert_batched_equals_singles(batched, singles, seed, (rng.integers(0, 4, size=n) for _ in range(steps)))


def test_sb3_vec_env():
    venv = make_train_env("NomadOfficeMemorable-v0", 3, 0, "batched")
    obs = venv.reset()
    assert obs.shape == (3, 34)
    obs, _, _, infos = venv.step(np.array([0, 1, 2]))
    assert obs.shape == (3, 34) and len(infos) == 3 and "route" in infos[0]


@given(st.lists(st.integers(0, 12), min_size=1, max_size=30))
def test_held_out_recordings_are_the_last_quarter_of_each_cell_and_fit_the_rest(counts: list[int]) -> None:
    counts_ = np.array(counts)
    fit, held = split_readings(counts_, "fit"), split_readings(counts_, "held_out")
    assert split_readings(counts_, "all").all() and len(fit) == len(held) == sum(counts)
    cell = np.repeat(np.arange(len(counts)), counts)
    for c, n in enumerate(counts):
        f, h = fit[cell == c], held[cell == c]
        if n == 1:  # one recording cannot be split: both replay it
            assert f.all() and h.all()
        elif n >= 2:
            assert h.sum() == -(-n // HOLD_OUT) and (f ^ h).all() and h[-1] and f[0]


def test_a_robot_trained_on_fit_recordings_never_reads_a_held_out_one():
    db = record_database(8, map="generated:S:3", seed=0)
    fit, held = (
        NomadOfficeMemorableEnv(map="generated:S:3", database=db, readings=r).robot for r in ("fit", "held_out")
    )

    def rows(robot, cell):
        start = int(robot.offsets[cell])
        return Counter(tuple(r) for r in robot.readings[start : start + int(robot.counts[cell])])

    cells = np.flatnonzero(db.counts >= 2)
    keys = np.arange(len(cells), dtype=np.uint64) * np.uint64(7919)
    drawn = [fit.cell_readings(cells, keys, np.full(len(cells), step)) for step in range(20)]
    for i, cell in enumerate(cells):
        recorded = Counter(tuple(r) for r in sensors.normalise(db.cell_readings(cell)))
        assert rows(fit, cell) + rows(held, cell) == recorded  # a split: every recording in exactly one
        assert {tuple(d[i]) for d in drawn} <= set(rows(fit, cell))
    with pytest.raises(ValueError, match=r"readings must be one of .* got 'train'"):
        NomadOfficeMemorableEnv(map="generated:S:3", database=db, readings="train")


@pytest.mark.parametrize("readings", ["fit", "held_out"])
def test_split_and_noisy_replays_batched_equal_singles(readings):
    db = record_database(4, seed=0)  # the paper's office: info has routes
    options = {"database": db, "readings": readings, "sensor_noise": True, "max_episode_steps": 60}
    batched = BatchedNomadOfficeMemorable(3, **options)
    singles = [NomadOfficeMemorableEnv(**options) for _ in range(3)]
    actions = np.random.default_rng(0).integers(0, 4, size=(200, 3))
    assert assert_batched_equals_singles(batched, singles, 11, actions) > 0
    plain = NomadOfficeMemorableEnv(database=db, readings=readings)
    noisy = NomadOfficeMemorableEnv(**options)
    assert not np.array_equal(plain.reset(seed=1)[0], noisy.reset(seed=1)[0])  # the noise is on
