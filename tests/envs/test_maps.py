"""Map files as a user writes them: checked on load, route regions optional, the record command (docs/own_office.md)."""

import json
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import twodrl_envs  # noqa: F401  (registers the IDs)
from sb3_twodrl.callbacks import EpisodeTracker, summarize_episodes
from twodrl_envs.analysis.cli import main as record_main
from twodrl_envs.analysis.dilemma import measure
from twodrl_envs.nomad.core import office_core
from twodrl_envs.nomad.geometry import SHIPPED_MAPS
from twodrl_envs.nomad.maps import load_map
from twodrl_zoo.vec_env import make_train_env

VEC = {"num_envs": 2, "vectorization_mode": "vector_entry_point"}


def write_map(tmp_path: Path, name: str = "room.json", **changes: object) -> Path:
    """A 300 x 120 cm room split by a wall at x = 150 (floor to ceiling): start west, goal east."""
    data = {
        "units": "cm",
        "bounds": [0, 0, 300, 120],
        "walls": [[0, 0, 300, 0], [300, 0, 300, 120], [300, 120, 0, 120], [0, 120, 0, 0], [150, 0, 150, 120]],
        "start": [60, 60],
        "regions": {"goal": [200, 0, 300, 120]},
        **changes,
    }
    path = tmp_path / name
    path.write_text(json.dumps(data))
    return path


def test_walled_off_goal_is_refused_with_counts(tmp_path):
    path = write_map(tmp_path)
    load_map(path)  # the file itself is well formed ...
    message = r"goal \[200.0, 0.0, 300.0, 120.0\] cannot be reached from the start \(60, 60\): 40 of 80 free lattice"
    with pytest.raises(ValueError, match=message) as err:  # ... but its goal is walled off
        office_core(path)
    assert str(path) in str(err.value) and "walled off" in str(err.value)
    with pytest.raises(ValueError, match="cannot be reached"):
        gym.make("NomadOffice-v0", map=str(path))
    with pytest.raises(ValueError, match="cannot be reached"):
        gym.make_vec("NomadOfficeMemorable-v0", map=path, **VEC)


def test_gap_narrower_than_the_robot_walls_off_the_goal(tmp_path):
    walls = [[0, 0, 300, 0], [300, 0, 300, 120], [300, 120, 0, 120], [0, 120, 0, 0]]
    narrow = write_map(tmp_path, "narrow.json", walls=[*walls, [150, 0, 150, 70]])  # a 50 cm gap: the robot is 60
    with pytest.raises(ValueError, match="cannot be reached"):
        office_core(narrow)
    wide = write_map(tmp_path, "wide.json", walls=[*walls, [150, 0, 150, 40]])  # 80 cm: the lattice row y = 80 passes
    assert office_core(wide).lattice.reachable.all()


def test_goal_without_a_free_cell(tmp_path):
    path = write_map(tmp_path, regions={"goal": [280, 0, 300, 120]})  # closer to the wall than the robot's radius
    with pytest.raises(ValueError, match=r"goal region \[280.0, 0.0, 300.0, 120.0\] holds no free lattice cell"):
        office_core(path)


def test_route_regions_come_as_a_pair(tmp_path):
    path = write_map(tmp_path, regions={"goal": [200, 0, 300, 120], "detour": [0, 0, 10, 10]})
    with pytest.raises(ValueError, match=r"regions\.detour needs regions\.shortcut"):
        load_map(path)


@pytest.mark.parametrize("bad", ["", " "])
def test_empty_map_path_names_map_and_the_builtin_maps(bad):
    expected = r"map must be a built-in map name \(office, open, corridor\), the path of a map JSON file or 'generated"
    with pytest.raises(ValueError, match=expected):
        gym.make("NomadOffice-v0", map=bad)
    with pytest.raises(ValueError, match=expected):
        gym.make_vec("NomadOffice-v0", map=bad, **VEC)


def test_missing_map_file_and_directory(tmp_path):
    with pytest.raises(ValueError, match=r"nope\.json does not exist \(map must be a built-in map name \(office"):
        gym.make("NomadOffice-v0", map=str(tmp_path / "nope.json"))
    with pytest.raises(ValueError, match="is a directory"):
        gym.make("NomadOfficeReal-v0", map=tmp_path)


@pytest.mark.parametrize("name", SHIPPED_MAPS)
def test_shipped_maps_load_and_reach_their_goal(name):
    core = office_core(name)
    assert core.lattice.reachable.all() and (core.goal & core.lattice.reachable).any()
    assert core.office.has_routes == (name != "corridor")


def test_goal_only_map_runs_without_route_metrics():
    env = gym.make("NomadOffice-v0", map="corridor", render_mode="rgb_array")
    obs, info = env.reset(seed=0)
    assert obs.shape == (34,) and "route" not in info
    for _ in range(20):  # east along the corridor
        obs, reward, terminated, _, info = env.step(1)
    assert reward == pytest.approx(-0.01) and not terminated and "route" not in info
    assert info["position_cm"] == (240.0, 50.0) and env.render().shape[2] == 3
    for _ in range(9):  # north through the door into the room: the goal (29 moves)
        obs, reward, terminated, _, info = env.step(0)
    assert terminated and info["is_success"] and reward == pytest.approx(4.99)
    memorable = gym.make("NomadOfficeMemorable-v0", map="corridor")  # its shipped database
    assert "route" not in memorable.reset(seed=0)[1] and "route" not in memorable.step(1)[4]
    adapter = make_train_env("NomadOffice-v0", 2, 0, env_kwargs={"map": "corridor"})
    adapter.reset()
    assert all("route" not in info for info in adapter.step(np.array([1, 1]))[3])


@pytest.mark.parametrize("mode", ["batched", "dummy"])
def test_route_metrics_absent_without_route_regions_present_with(mode):
    summaries = {}
    for name in ("corridor", "office"):
        venv = make_train_env("NomadOffice-v0", 8, seed=0, mode=mode, env_kwargs={"map": name})
        venv.reset()
        tracker, records, rng = EpisodeTracker(8), [], np.random.default_rng(0)
        for _ in range(60):
            _, rewards, dones, infos = venv.step(rng.integers(0, 4, 8))
            records += tracker.step(infos, dones, rewards)
        summaries[name] = summarize_episodes(records)
    assert summaries["corridor"]["episodes"] > 0 and "goal_rate" in summaries["corridor"]
    assert "shortcut_share" not in summaries["corridor"] and "labelled_episodes" not in summaries["corridor"]
    assert "shortcut_share" in summaries["office"]


def test_user_map_without_database_says_how_to_record_one(tmp_path):
    data = json.loads(Path(office_core("corridor").office.source).read_text())
    data["start"] = [50, 45]
    path = tmp_path / "my_corridor.json"
    path.write_text(json.dumps(data))
    with pytest.raises(ValueError, match=r"record one with `sb3-twodrl-record-database --map .*my_corridor\.json"):
        gym.make("NomadOfficeMemorable-v0", map=str(path))


# --- sb3-twodrl-record-database -------------------------------------------------------------------


def test_record_command_checks_a_map(capsys):
    record_main(["--map", "corridor", "--check"])
    out = capsys.readouterr().out
    assert "OK" in out and "189 free lattice cells, 189 reachable" in out and "shortest path 29 moves" in out


def test_record_command_refuses_a_walled_off_map(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_:
        record_main(["--map", str(write_map(tmp_path)), "--check"])
    assert exit_.value.code == 2 and "--map: map file" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--map", "corridor"], "--out is required"),
        (["--map", "corridor", "--out", "db.txt"], "--out must end in .npz"),
        (["--map", "corridor", "--out", "no/such/dir/db.npz"], "directory 'no/such/dir' does not exist"),
        (["--map", "corridor", "--out", "db.npz", "--k", "0"], "--k must be >= 1"),
        (["--map", "", "--check"], "--map: map must be a built-in map name"),
        (["--model", "perfect", "--out", "db.npz"], "invalid choice: 'perfect'"),
    ],
)
def test_record_command_bad_arguments(argv, message, capsys):
    with pytest.raises(SystemExit) as exit_:
        record_main(argv)
    assert exit_.value.code == 2 and message in capsys.readouterr().err


def test_record_command_writes_a_database_the_env_replays(tmp_path, capsys):
    out = tmp_path / "corridor_ideal.npz"
    record_main(["--map", "corridor", "--model", "ideal", "--k", "1", "--out", str(out)])
    assert "wrote" in capsys.readouterr().out
    replay = gym.make("NomadOfficeMemorable-v0", map="corridor", database=str(out))
    ideal = gym.make("NomadOffice-v0", map="corridor")
    np.testing.assert_array_equal(replay.reset(seed=0)[0], ideal.reset(seed=0)[0])  # exact readings, one per cell
    np.testing.assert_array_equal(replay.step(1)[0], ideal.step(1)[0])


def test_dilemma_figures_need_route_regions():
    with pytest.raises(ValueError, match="has no route regions"):
        measure(office_core("corridor"), 300)


def _desk_map(tmp_path, start, goal):
    import json

    data = {
        "bounds": [0, 0, 400, 200],
        "walls": [
            [0, 0, 400, 0],
            [400, 0, 400, 200],
            [400, 200, 0, 200],
            [0, 200, 0, 0],
            [200, 0, 200, 60],
            [200, 140, 200, 200],
        ],
        "obstacles": [[[260, 20], [390, 20], [390, 180], [260, 180]]],
        "start": start,
        "regions": {"goal": goal},
    }
    path = tmp_path / "desk.json"
    path.write_text(json.dumps(data))
    return str(path)


def test_a_goal_or_a_start_inside_a_desk_is_named_as_such(tmp_path):
    import gymnasium as gym
    import pytest

    with pytest.raises(ValueError, match=r"the goal \[290.0, 60.0, 360.0, 140.0\] lies inside obstacles\[0\]"):
        gym.make("NomadOffice-v0", map=_desk_map(tmp_path, [60, 100], [290, 60, 360, 140]))
    with pytest.raises(ValueError, match=r"start \(300.0, 100.0\) is inside obstacles\[0\]; move it onto the floor"):
        gym.make("NomadOffice-v0", map=_desk_map(tmp_path, [300, 100], [60, 0, 150, 200]))
    gym.make("NomadOffice-v0", map=_desk_map(tmp_path, [60, 100], [210, 60, 240, 140])).close()  # in front: fine
