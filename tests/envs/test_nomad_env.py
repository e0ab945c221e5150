"""NomadOffice-v0 / NomadOfficeReal-v0: API checks, eq. 11-12 evaluations, routes, seeding, errors."""

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env as gym_check_env
from stable_baselines3.common.env_checker import check_env as sb3_check_env

from twodrl_envs import MAX_EPISODE_STEPS
from twodrl_envs.nomad.core import IdealRobot, office_core

IDS = ["twodrl_envs:NomadOffice-v0", "twodrl_envs:NomadOfficeReal-v0"]
N, E, S, W = 0, 1, 2, 3
SHORTCUT = [S] + [E] * 16  # from (60, 85) to the bent passage's junction row y = 75, then east through it
DETOUR = [N] * 11 + [E] * 16  # north to the corridor row y = 195, east over the partition


@pytest.mark.parametrize("env_id", IDS)
def test_checkers_pass(env_id):
    gym_check_env(gym.make(env_id, render_mode="rgb_array").unwrapped)
    sb3_check_env(gym.make(env_id).unwrapped)
    sb3_check_env(gym.make(env_id, observe_odometry=False).unwrapped)


def run(env, actions):
    rewards, infos = [], []
    for action in actions:
        _, reward, terminated, truncated, info = env.step(action)
        rewards.append(reward)
        infos.append(info)
        if terminated or truncated:
            break
    return rewards, infos, terminated


@pytest.mark.parametrize(("actions", "route"), [(SHORTCUT, "shortcut"), (DETOUR, "detour")])
def test_scripted_routes_reach_goal(actions, route):
    env = gym.make("twodrl_envs:NomadOffice-v0")
    env.reset(seed=0)
    rewards, infos, terminated = run(env, actions)
    assert terminated and len(rewards) == len(actions)
    assert infos[-1]["is_success"] and infos[-1]["route"] == route
    assert not any(info["is_success"] for info in infos[:-1])
    assert rewards[:-1] == [-0.01] * (len(actions) - 1)
    assert rewards[-1] == pytest.approx(4.99)
    assert all(r == (5.0 if i["is_success"] else 0.0) - i["punishment"] for r, i in zip(rewards, infos, strict=True))
    assert infos[-1]["position_cm"][0] == 220.0
    assert len(SHORTCUT) <= 0.65 * len(DETOUR)


def test_route_label_is_the_route_taken_to_the_goal():
    env = gym.make("twodrl_envs:NomadOffice-v0")
    env.reset(seed=0)
    # up into the corridor beside the start room: not yet the detour
    _, infos, _ = run(env, [N] * 11)
    assert all(info["route"] is None for info in infos)
    # east over the partition (the detour), then back, down and through the bent passage
    _, infos, terminated = run(env, [E] * 7 + [W] * 7 + [S] * 12 + [E] * 16)
    assert infos[6]["route"] == "detour"
    assert terminated and infos[-1]["is_success"] and infos[-1]["route"] == "shortcut"


def test_collision_into_wall_and_one_cm_clearance_along_wall():
    env = gym.make("twodrl_envs:NomadOffice-v0")
    env.reset(options={"position": (60.0, 40.0)})
    _, reward, terminated, _, info = env.step(S)  # centre would be 30 cm from the floor: touching
    assert terminated and info["collision"] and info["punishment"] == 1.0 and reward == -1.0
    assert info["position_cm"] == (60.0, 40.0) and not info["is_success"]
    env.reset(options={"position": (60.0, 31.0)})  # 1 cm clearance above the floor
    _, infos, terminated = run(env, [E, E, W])
    assert not terminated and not any(i["collision"] for i in infos)
    assert infos[-1]["position_cm"] == pytest.approx((70.0, 31.0))


@pytest.mark.parametrize("position", [(170.0, 110.0), (90.0, 20.0), (-50.0, 60.0), (90.0, 400.0), (1, 2, 3), "x"])
def test_reset_position_in_wall_or_outside_is_value_error(position):
    env = gym.make("twodrl_envs:NomadOffice-v0")
    with pytest.raises(ValueError, match="position"):
        env.reset(options={"position": position})


def test_reset_position_on_lattice_matches_walking_there():
    env = gym.make("twodrl_envs:NomadOffice-v0")
    env.reset(seed=0)
    walked, *_ = env.step(E)
    placed, info = env.reset(options={"position": (70.0, 85.0)})
    assert info["position_cm"] == (70.0, 85.0)
    np.testing.assert_array_equal(walked, placed)


def rollout(env_id, seed, **kwargs):
    env = gym.make(env_id, **kwargs)
    env.action_space.seed(seed)
    obs, _ = env.reset(seed=seed)
    trace = [obs]
    for _ in range(60):
        obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
        trace += [obs, reward, info["position_cm"]]
        if terminated or truncated:
            obs, _ = env.reset()
            trace.append(obs)
    return trace


@pytest.mark.parametrize(("env_id", "kwargs"), [(IDS[0], {}), (IDS[0], {"sensor_noise": True}), (IDS[1], {})])
def test_same_seed_same_episode(env_id, kwargs):
    a, b, c = rollout(env_id, 3, **kwargs), rollout(env_id, 3, **kwargs), rollout(env_id, 4, **kwargs)
    assert all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))
    if kwargs or env_id == IDS[1]:
        assert not all(np.array_equal(x, y) for x, y in zip(a, c, strict=False))


def test_real_model_is_noisy_and_slips():
    env = gym.make("twodrl_envs:NomadOfficeReal-v0")
    obs0, _ = env.reset(seed=1)
    _, _, _, _, info = env.step(E)
    assert info["position_cm"] != (70.0, 85.0)
    assert obs0[-2:] == pytest.approx(np.array([60 / 290, 85 / 305]))  # odometry is dead reckoning
    ideal, _ = gym.make("twodrl_envs:NomadOffice-v0").reset(seed=1)
    assert not np.array_equal(obs0[:32], ideal[:32])


def test_truncated_by_time_limit():
    env = gym.make("twodrl_envs:NomadOffice-v0")
    env.reset(seed=0)
    for t in range(MAX_EPISODE_STEPS):
        *_, terminated, truncated, info = env.step(E if t % 2 == 0 else W)
    assert truncated and not terminated and not info["is_success"]


@pytest.mark.filterwarnings("ignore:.*not in the possible render_modes")  # gymnasium warns before we raise
@pytest.mark.parametrize(
    ("kwargs", "error", "message"),
    [
        ({"map": "/no/such/office.json"}, ValueError, "/no/such/office.json"),
        ({"sensor_noise": "yes"}, TypeError, "sensor_noise"),
        ({"step_sd_cm": -1.0}, ValueError, "step_sd_cm"),
        ({"slip_sd_cm": float("nan")}, ValueError, "slip_sd_cm"),
        ({"observe_odometry": "no"}, TypeError, "observe_odometry"),
        ({"render_mode": "ansi"}, ValueError, "render_mode"),
    ],
)
def test_bad_constructor_arguments(kwargs, error, message):
    with pytest.raises(error, match=message):
        gym.make("twodrl_envs:NomadOffice-v0", **kwargs)


@pytest.mark.parametrize(
    ("env_id", "kwargs", "draws"),
    [
        ("twodrl_envs:NomadOffice-v0", {"step_sd_cm": 2.0, "slip_sd_cm": 1.0}, True),
        ("twodrl_envs:NomadOffice-v0", {"sensor_noise": True}, False),
        ("twodrl_envs:NomadOfficeReal-v0", {}, False),
    ],
)
def test_only_the_ideal_robots_move_noise_draws_from_the_envs_generator(env_id, kwargs, draws):
    env = gym.make(env_id, **kwargs).unwrapped
    env.reset(seed=0)
    before = env.np_random.bit_generator.state
    env.step(N)
    assert (env.np_random.bit_generator.state != before) == draws  # the others' randomness is counter-based
    with pytest.raises(ValueError, match="generators"):
        IdealRobot(env.core, step_sd_cm=1.0)  # move noise needs the envs' generators


def test_bad_action_and_options():
    env = gym.make("twodrl_envs:NomadOffice-v0").unwrapped
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action"):
        env.step(4)
    with pytest.raises(ValueError, match="options"):
        env.reset(options={"pos": (60, 85)})


def test_render_rgb_array():
    env = gym.make("twodrl_envs:NomadOffice-v0", render_mode="rgb_array")
    env.reset(seed=0)
    run(env, [N, E, E])
    frame = env.render()
    assert frame.ndim == 3 and frame.shape[2] == 3 and frame.dtype == np.uint8


@pytest.mark.parametrize(
    ("env_id", "kwargs", "start"),
    [
        ("twodrl_envs:NomadOffice-v0", {}, (60.0, 85.0)),
        ("twodrl_envs:NomadOffice-v0", {"map": "open"}, (90.0, 60.0)),
        ("twodrl_envs:NomadOfficeOpen-v0", {}, (90.0, 60.0)),
        ("twodrl_envs:NomadOfficeMemorableOpen-v0", {}, (90.0, 60.0)),  # with the open office's own database
        ("twodrl_envs:NomadOfficeMemorable-v0", {"map": "office"}, (60.0, 85.0)),
    ],
)
def test_shipped_maps_by_name_and_id(env_id, kwargs, start):
    env = gym.make(env_id, **kwargs)
    _, info = env.reset(seed=0)
    assert info["position_cm"] == start and env.spec.max_episode_steps == MAX_EPISODE_STEPS


def test_unknown_map_name_is_value_error():
    with pytest.raises(ValueError, match=r"closed.*does not exist"):
        gym.make("twodrl_envs:NomadOffice-v0", map="closed")


@pytest.mark.parametrize("env_id", ["NomadOffice-v0", "NomadOfficeMemorable-v0", "NomadOfficeReal-v0"])
def test_exploring_starts_draw_reachable_cells_outside_the_goal(env_id):
    """``starts="uniform"``: each episode starts at a cell drawn from the robot's start cells (reachable, not in the
    goal, with a way to it), seeded; the default starts every episode at the map's start."""
    env = gym.make(env_id, starts="uniform")
    robot = env.unwrapped.robot
    cells = robot.start_cells
    assert (
        len(cells) > 100 and not env.unwrapped.core.goal[cells].any() and np.isfinite(robot.goal_distance[cells]).all()
    )
    starts = [env.reset(seed=0 if i == 0 else None)[1]["position_cm"] for i in range(200)]
    allowed = {tuple(xy) for xy in env.unwrapped.core.lattice.cells[cells].tolist()}
    assert set(starts) <= allowed and len(set(starts)) > 100
    again = gym.make(env_id, starts="uniform")
    assert [again.reset(seed=0 if i == 0 else None)[1]["position_cm"] for i in range(200)] == starts
    plain = gym.make(env_id)
    start = tuple(float(v) for v in plain.unwrapped.core.office.start)
    assert {plain.reset(seed=i)[1]["position_cm"] for i in range(5)} == {start}


def test_exploring_starts_refuse_an_unknown_value():
    with pytest.raises(ValueError, match="starts must be one of"):
        gym.make("NomadOffice-v0", starts="random")


def test_the_raw_input_stage_gives_the_envs_observation():
    """:class:`RawObservation` on ranges (cm) and positions (cm) equals the env's observation, bit for bit."""
    import torch as th

    from twodrl_envs.nomad.deploy import RawObservation
    from twodrl_envs.nomad.realistic import RealisticModel

    core = office_core("generated:M:3")
    raw = np.concatenate([core.ranges, core.lattice.cells], axis=1)
    expected = np.concatenate([core.readings, core.cell_odometry], axis=1)
    np.testing.assert_array_equal(RawObservation("generated:M:3")(th.as_tensor(raw)).numpy(), expected)
    without = RawObservation("generated:M:3", observe_odometry=False)(th.as_tensor(core.ranges)).numpy()
    np.testing.assert_array_equal(without, core.readings)
    scene = RealisticModel().scene(core.office)  # the stand-in robot's saturated readings, off the lattice
    poses = core.lattice.cells[:50] + 3.3
    keys, steps = np.arange(50, dtype=np.uint64), np.ones(50, dtype=np.int64)
    got = RawObservation("generated:M:3", observe_odometry=False)(th.as_tensor(scene.ranges(poses, keys, steps)))
    np.testing.assert_array_equal(got.numpy(), scene.readings(poses, keys, steps))


def test_the_progress_signal_rewards_moves_closer_and_punishes_moves_away():
    """``progress=k``: a move one step closer to the goal adds ``k`` to ``r_R``, one farther adds ``k`` to ``r_P``
    (both streams stay >= 0); a collision adds nothing; eq. 11-12 otherwise."""
    k = 0.05
    env = gym.make("NomadOffice-v0", map="corridor", progress=k)
    plain = gym.make("NomadOffice-v0", map="corridor")
    distance = env.unwrapped.robot.goal_distance
    core = env.unwrapped.core
    rng = np.random.default_rng(0)
    env.reset(seed=0), plain.reset(seed=0)
    seen = set()
    for _ in range(400):
        before = distance[core.lattice.index(np.array(env.unwrapped._pos))]
        action = int(rng.integers(4))
        _, reward, terminated, truncated, info = env.step(action)
        _, base_reward, *_, base_info = plain.step(action)
        gain = 0.0 if info["collision"] else before - distance[core.lattice.index(np.array(info["position_cm"]))]
        assert reward == pytest.approx(base_reward + k * gain)
        assert info["punishment"] == pytest.approx(base_info["punishment"] + k * max(-gain, 0.0))
        assert info["punishment"] >= 0 and reward + info["punishment"] >= 0  # r_P >= 0, r_R >= 0
        seen.add(gain)
        if terminated or truncated:
            env.reset(), plain.reset()
    assert seen == {-1.0, 0.0, 1.0}
    with pytest.raises(ValueError, match="progress"):
        gym.make("NomadOfficeReal-v0", progress=k)
    with pytest.raises(ValueError, match="progress"):
        gym.make("NomadOffice-v0", progress=-1.0)
