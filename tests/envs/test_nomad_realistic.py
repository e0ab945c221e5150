"""The stand-in robot (twodrl_envs.nomad.realistic): one geometry test per artifact, drift, seeding, batching."""

import json

import gymnasium as gym
import numpy as np
import pytest

import twodrl_envs  # noqa: F401
from twodrl_envs.nomad import sensors
from twodrl_envs.nomad.core import office_core
from twodrl_envs.nomad.maps import load_map
from twodrl_envs.nomad.realistic import RealisticModel, Surface

PLASTER = Surface("plaster", 0.9, 7.5, 1.0)
# noise-free: every reading is the deterministic echo geometry
EXACT = {
    "sonar_sd_cm": 0.0,
    "sonar_sd_frac": 0.0,
    "sonar_miss_prob": 0.0,
    "sonar_resolution_cm": 0.0,
    "ir_intensity_sd": 0.0,
}
ROBOT = np.array([[500.0, 500.0]])


def office_with(tmp_path, walls, start=(500, 500)):
    data = {
        "bounds": [0, 0, 1000, 1000],
        "walls": walls,
        "start": list(start),
        "regions": {"goal": [900, 900, 950, 950], "shortcut": [0, 0, 10, 10], "detour": [20, 0, 30, 10]},
    }
    path = tmp_path / "room.json"
    path.write_text(json.dumps(data))
    return load_map(path)


def tilted_wall(distance, tilt_deg, half_length=400.0):
    """A wall whose foot of the perpendicular from the robot is ``distance`` cm north of the body, normal tilted."""
    tilt = np.deg2rad(tilt_deg)
    foot = ROBOT[0] + (30.0 + distance) * np.array([np.sin(tilt), np.cos(tilt)])
    along = np.array([np.cos(tilt), -np.sin(tilt)])
    return [[*(foot - half_length * along), *(foot + half_length * along)]]


def sonar(office, model, position=ROBOT, key=0, step=0):
    scene = model.scene(office)
    return scene.ranges(position, np.array([key], dtype=np.uint64), np.array([step]))[0]


def test_head_on_wall_reads_its_distance(tmp_path):
    office = office_with(tmp_path, tilted_wall(150.0, 0.0))
    reading = sonar(office, RealisticModel(surfaces=(PLASTER,), **EXACT))
    assert reading[0] == pytest.approx(150.0)


@pytest.mark.parametrize("tilt", [5.0, 20.0])
def test_wall_inside_beam_plus_critical_angle_reads_the_perpendicular(tmp_path, tilt):
    """Leonard and Durrant-Whyte: a specular plane returns along its normal (a region of constant depth)."""
    office = office_with(tmp_path, tilted_wall(150.0, tilt))
    reading = sonar(office, RealisticModel(surfaces=(PLASTER,), **EXACT))
    perpendicular = 30.0 + 150.0 - 30.0 * np.cos(np.deg2rad(tilt))  # from the transducer
    assert reading[0] == pytest.approx(perpendicular, rel=np.cos(np.deg2rad(7.5)) ** -1 - 1)


@pytest.mark.parametrize("tilt", [25.0, 50.0])
def test_wall_beyond_the_critical_angle_is_not_seen(tmp_path, tilt):
    office = office_with(tmp_path, tilted_wall(150.0, tilt))
    reading = sonar(office, RealisticModel(surfaces=(PLASTER,), **EXACT))
    assert reading[0] == sensors.SONAR_MAX_CM
    assert sensors.exact_ranges(office, ROBOT)[0, 0] < 300  # the ideal sonar sees it


def test_specular_corner_gives_a_longer_multipath_range(tmp_path):
    """A sonar aimed into a 90 degree corner at 45 degrees: walls go specular, the corner echoes back."""
    corner = ROBOT[0] + np.array([0.0, 250.0])
    walls = [[*corner, *(corner + np.array([-300, -300]))], [*corner, *(corner + np.array([300, -300]))]]
    office = office_with(tmp_path, walls)
    reading = sonar(office, RealisticModel(surfaces=(PLASTER,), crosstalk_prob=0.0, **EXACT))
    ideal = sensors.exact_ranges(office, ROBOT)[0, 0]
    assert ideal + 20 < reading[0] < sensors.SONAR_MAX_CM
    assert reading[0] == pytest.approx(250.0 - 30.0, abs=15.0)  # the corner's distance from the body


def test_ringing_hides_walls_nearer_than_the_blanking_distance(tmp_path):
    model = RealisticModel(surfaces=(PLASTER,), **EXACT)
    near = sonar(office_with(tmp_path, tilted_wall(35.0, 0.0)), model)
    assert near[0] == sensors.SONAR_MAX_CM  # the ideal sonar reads 40 (its minimum)
    assert sonar(office_with(tmp_path, tilted_wall(45.0, 0.0)), model)[0] == pytest.approx(45.0)


def test_crosstalk_shortens_some_readings_in_the_office():
    core = office_core()
    scene = RealisticModel(**EXACT).scene(core.office)
    own, crosstalk = scene.echoes(core.lattice.cells)
    assert np.any(crosstalk < own)
    keys = np.arange(len(own), dtype=np.uint64)
    steps = np.zeros(len(own), dtype=np.int64)
    always = RealisticModel(crosstalk_prob=1.0, **EXACT).scene(core.office).ranges(core.lattice.cells, keys, steps)
    never = RealisticModel(crosstalk_prob=0.0, **EXACT).scene(core.office).ranges(core.lattice.cells, keys, steps)
    expected = np.minimum(own, crosstalk)
    np.testing.assert_allclose(always[:, :16], np.where(np.isfinite(expected), expected, 600.0))
    np.testing.assert_allclose(never[:, :16], np.where(np.isfinite(own), own, 600.0))


def test_infrared_depends_on_the_surface_and_saturates(tmp_path):
    dark = Surface("fabric", 0.25, 25.0, 1.0)
    readings = {}
    for surface in (PLASTER, dark):
        model = RealisticModel(surfaces=(surface,), **EXACT)
        readings[surface.name] = [sonar(office_with(tmp_path, tilted_wall(d, 0.0)), model)[16] for d in (1, 3, 10, 15)]
    white, black = readings["plaster"], readings["fabric"]
    assert black[3] > white[3] + 10  # a dark surface reads far farther at the same 15 cm
    assert white[0] == pytest.approx(5.0, abs=0.1)  # saturated: 1 cm reads the saturation distance
    assert white[0] < white[1] < white[2] < white[3]  # monotone, compressed at close range
    assert white[1] - white[0] < 0.5 * (3 - 1)


def test_infrared_reads_farther_at_oblique_incidence(tmp_path):
    model = RealisticModel(surfaces=(PLASTER,), **EXACT)
    head_on = sonar(office_with(tmp_path, tilted_wall(15.0, 0.0)), model)[16]
    oblique = office_with(tmp_path, tilted_wall(2.0, 45.0))
    axis = sensors.exact_ranges(oblique, ROBOT)[0, 16]
    assert axis == pytest.approx(32.0 / np.cos(np.deg2rad(45)) - 30.0)
    assert sonar(oblique, model)[16] > head_on * (axis / 15.0) * 1.1  # cos(45) less light than head-on


def test_drift_grows_with_the_number_of_moves():
    model = RealisticModel()
    n = 2000
    keys = np.arange(n, dtype=np.uint64) * np.uint64(0x9E3779B97F4A7C15)
    rng = np.random.default_rng(0)
    error = np.zeros((n, 2))
    errors = {}
    for step in range(1, 51):
        actions = rng.integers(0, 4, n)
        error += (
            model.displacement(actions, keys, np.full(n, step))
            - 10.0 * np.array([[0, 1], [1, 0], [0, -1], [-1, 0]])[actions]
        )
        errors[step] = np.median(np.linalg.norm(error, axis=1))
    assert errors[5] < errors[20] < errors[50]
    assert errors[50] > 2.0 * errors[5]


def test_real_env_odometry_is_dead_reckoning_and_drifts(tmp_path):
    office_with(tmp_path, [[0, 0, 1000, 0], [1000, 0, 1000, 1000], [1000, 1000, 0, 1000], [0, 1000, 0, 0]])
    env = gym.make("twodrl_envs:NomadOfficeReal-v0", map=tmp_path / "room.json")
    obs, info = env.reset(seed=0)
    for _ in range(30):
        obs, _, terminated, _, info = env.step(1)  # east through an empty room
        assert not terminated
    odometry = obs[-2:] * 1000.0
    np.testing.assert_allclose(odometry, (500.0 + 300.0, 500.0), atol=1e-3)
    assert np.linalg.norm(np.array(info["position_cm"]) - odometry) > 0.5


def test_gap_is_systematic_and_straight_runs_drift_more():
    from twodrl_envs.analysis.gap import odometry_errors, systematic_difference

    core = office_core()
    diff = systematic_difference(core, RealisticModel(), draws=3, seed=0)
    assert diff.shape == (int(core.lattice.reachable.sum()), 32)
    assert np.mean(diff[:, :16] > 50) > 0.2
    exact = systematic_difference(core, RealisticModel(beam_half_angle_deg=11.25, **EXACT), draws=1, seed=0)
    assert np.mean(exact[:, :16] > 50) > 0.2  # not the noise: the geometry
    straight = odometry_errors(RealisticModel(), 50, 500, 0, straight=True)
    random = odometry_errors(RealisticModel(), 50, 500, 0)
    assert np.median(straight[49]) > np.median(random[49]) > np.median(random[4])


def test_vector_entry_point_is_the_batched_real_env():
    venv = gym.make_vec("twodrl_envs:NomadOfficeReal-v0", num_envs=2, vectorization_mode="vector_entry_point")
    obs, _ = venv.reset(seed=0)
    single, _ = gym.make("twodrl_envs:NomadOfficeReal-v0").reset(seed=1)
    np.testing.assert_array_equal(obs[1], single)


def test_seeded_real_env_repeats_exactly():
    def trace(seed):
        env = gym.make("twodrl_envs:NomadOfficeReal-v0")
        env.action_space.seed(seed)
        out = [env.reset(seed=seed)[0]]
        for _ in range(40):
            obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
            out += [obs, np.array(info["position_cm"]), np.array([reward])]
            if terminated or truncated:
                out.append(env.reset()[0])
        return out

    a, b, c = trace(5), trace(5), trace(6)
    assert all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))
    assert not all(np.array_equal(x, y) for x, y in zip(a, c, strict=False))


def test_batched_readings_equal_single_readings():
    core = office_core()
    scene = RealisticModel().scene(core.office)
    rng = np.random.default_rng(1)
    cells = core.lattice.cells[rng.choice(len(core.lattice.cells), 40)] + rng.normal(0, 3, (40, 2))
    keys = rng.integers(0, 2**63, 40, dtype=np.uint64)
    steps = rng.integers(0, 200, 40)
    batch = scene.ranges(cells, keys, steps)
    single = np.concatenate([scene.ranges(cells[i : i + 1], keys[i : i + 1], steps[i : i + 1]) for i in range(40)])
    np.testing.assert_array_equal(batch, single)
    actions = rng.integers(0, 4, 40)
    moves = RealisticModel().displacement(actions, keys, steps)
    one = [RealisticModel().displacement(actions[i : i + 1], keys[i : i + 1], steps[i : i + 1]) for i in range(40)]
    np.testing.assert_array_equal(moves, np.concatenate(one))


def test_readings_are_valid_and_the_ideal_simulator_stays_exact():
    core = office_core()
    cells = core.lattice.cells
    ranges = (
        RealisticModel()
        .scene(core.office)
        .ranges(cells, np.arange(len(cells), dtype=np.uint64), np.ones(len(cells), int))
    )
    assert np.all((ranges >= sensors.LOW_CM) & (ranges <= sensors.HIGH_CM))
    ideal = gym.make("twodrl_envs:NomadOffice-v0")
    obs, _ = ideal.reset(seed=0)
    np.testing.assert_array_equal(obs[:32], core.readings[core.start_cell])


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"beam_half_angle_deg": 0.0}, "beam_half_angle_deg"),
        ({"rays_per_beam": 0}, "rays_per_beam"),
        ({"crosstalk_prob": 1.5}, "crosstalk_prob"),
        ({"blank_cm": float("nan")}, "blank_cm"),
        ({"scale_bias": -1.0}, "scale_bias"),
        ({"surfaces": ()}, "surfaces"),
    ],
)
def test_bad_parameters_are_named(kwargs, name):
    with pytest.raises(ValueError, match=name):
        RealisticModel(**kwargs)


def test_real_env_rejects_a_model_of_the_wrong_type():
    with pytest.raises(TypeError, match="model"):
        gym.make("twodrl_envs:NomadOfficeReal-v0", model="realistic")


def test_batched_real_env_equals_single_envs():
    from twodrl_envs.nomad.realistic import BatchedNomadOfficeReal

    n, steps = 3, 260
    batched = BatchedNomadOfficeReal(n)
    singles = [gym.make("twodrl_envs:NomadOfficeReal-v0") for _ in range(n)]
    obs_b, _ = batched.reset(seed=10)
    obs_s = [env.reset(seed=10 + i)[0] for i, env in enumerate(singles)]
    np.testing.assert_array_equal(obs_b, np.stack(obs_s))
    rng = np.random.default_rng(0)
    ends = 0
    for _ in range(steps):
        actions = rng.choice(4, n, p=[0.2, 0.5, 0.2, 0.1])
        obs_b, rew_b, term_b, trunc_b, info_b = batched.step(actions)
        for i, env in enumerate(singles):
            obs, reward, terminated, truncated, info = env.step(int(actions[i]))
            assert (reward, terminated, truncated) == (rew_b[i], term_b[i], trunc_b[i])
            assert info["position_cm"] == tuple(info_b["position_cm"][i]) and info["route"] == info_b["route"][i]
            if terminated or truncated:
                np.testing.assert_array_equal(info_b["final_obs"][i], obs)
                obs, _ = env.reset()
                ends += 1
            np.testing.assert_array_equal(obs_b[i], obs)
    assert ends >= 3


def test_batched_real_env_trains_with_sb3():
    from stable_baselines3 import A2C

    from twodrl_zoo.vec_env import make_train_env

    venv = make_train_env("NomadOfficeReal-v0", 4, 0, "batched", env_kwargs={"observe_odometry": False})
    assert venv.observation_space.shape == (32,)
    A2C("MlpPolicy", venv, n_steps=5, seed=0, device="cpu").learn(40)
