"""Generated offices: each passes the map checks, is reproducible, lands in its size class and fits in
10.5 m x 10.5 m; ``map="generated:..."`` works for every env; ``sb3-twodrl-map`` writes a loadable file."""

import json

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import twodrl_envs  # noqa: F401  (registers the IDs)
from twodrl_envs.analysis.dilemma import distance_to_goal
from twodrl_envs.memorable.database import save_database
from twodrl_envs.memorable.recording import record_database
from twodrl_envs.nomad import generator
from twodrl_envs.nomad.core import office_core
from twodrl_envs.nomad.generator import SIZES, generate_map, shortest_path_moves
from twodrl_envs.nomad.geometry import (
    SHIPPED_MAPS,
    build_lattice,
    check_goal_reachable,
    parse_map,
)
from twodrl_envs.nomad.map_cli import main as map_main
from twodrl_envs.nomad.maps import load_map, map_source

MAX_SIDE_CM = 1050  # the bound this file holds every generated office to
SEEDS = st.integers(0, 999)
VEC = {"num_envs": 2, "vectorization_mode": "vector_entry_point"}


def check_office(seed: int, size: str) -> None:
    """The properties every generated office has."""
    data = generate_map(seed, size)
    assert json.loads(json.dumps(data)) == data  # plain JSON
    office = parse_map(data, f"generated:{size}:{seed}")  # the checks a map file gets ...
    lattice = build_lattice(office)
    check_goal_reachable(office, lattice)  # ... and those an env makes on load
    low, high = SIZES[size]
    assert low <= shortest_path_moves(office, lattice) <= high
    x0, y0, x1, y1 = office.bounds
    assert x1 - x0 <= MAX_SIDE_CM and y1 - y0 <= MAX_SIDE_CM
    assert generate_map(seed, size) == data


def fast(examples: int) -> settings:
    return settings(max_examples=examples, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@fast(25)
@given(seed=SEEDS)
def test_small_offices(seed: int) -> None:
    check_office(seed, "S")


@fast(10)
@given(seed=SEEDS)
def test_medium_offices(seed: int) -> None:
    check_office(seed, "M")


@fast(2)
@given(seed=SEEDS)
def test_large_offices(seed: int) -> None:
    check_office(seed, "L")


@pytest.mark.slow
@fast(60)
@given(seed=SEEDS, size=st.sampled_from(list(SIZES)))
def test_many_offices(seed: int, size: str) -> None:
    check_office(seed, size)


def test_seeds_and_sizes_give_different_offices() -> None:
    assert generate_map(3, "S") != generate_map(4, "S")
    assert generate_map(3, "S") != generate_map(3, "M")
    assert generate_map(3) == generate_map(3, "M")


@pytest.mark.parametrize(
    ("args", "error", "message"),
    [
        ((-1,), ValueError, "seed must be >= 0, got -1"),
        ((1.5,), TypeError, "seed must be an int, got float: 1.5"),
        ((True,), TypeError, "seed must be an int, got bool"),
        ((1, "XL"), ValueError, "size must be one of S, M, L, got 'XL'"),
        ((1, 2), TypeError, "size must be a str"),
    ],
)
def test_bad_seed_or_size(args: tuple, error: type, message: str) -> None:
    with pytest.raises(error, match=message):
        generate_map(*args)


def test_gives_up_after_its_attempts(monkeypatch) -> None:
    monkeypatch.setattr(generator, "MAX_ATTEMPTS", 0)
    with pytest.raises(RuntimeError, match=r"generate_map\(3, 'L'\): no layout of 0 landed in class L"):
        generate_map(3, "L")


@pytest.mark.parametrize("name", SHIPPED_MAPS)
def test_shortest_path_agrees_with_the_goal_distances(name: str) -> None:
    core = office_core(name)
    assert shortest_path_moves(core.office, core.lattice) == distance_to_goal(core)[core.start_cell]


def test_shortest_path_of_a_walled_off_goal() -> None:
    box = [[0, 0, 300, 0], [300, 0, 300, 120], [300, 120, 0, 120], [0, 120, 0, 0]]
    data = {"bounds": [0, 0, 300, 120], "walls": [*box, [150, 0, 150, 120]], "start": [60, 60]}
    office = parse_map({**data, "regions": {"goal": [200, 0, 300, 120]}}, "two rooms")
    with pytest.raises(ValueError, match="no goal cell is reachable"):
        shortest_path_moves(office, build_lattice(office))
    with pytest.raises(TypeError, match="lattice must be a Lattice"):
        shortest_path_moves(office, None)
    same_room = parse_map({**data, "regions": {"goal": [0, 0, 100, 120]}}, "goal in the start room")
    assert shortest_path_moves(same_room, build_lattice(same_room)) == 0


def test_generated_map_option_single_env() -> None:
    env = gym.make("twodrl_envs:NomadOffice-v0", map="generated:S:5")
    obs, info = env.reset(seed=0)
    assert info["position_cm"] == tuple(float(v) for v in generate_map(5, "S")["start"])
    for action in (0, 1, 2, 3):
        obs, _, _, _, info = env.step(action)
        assert env.observation_space.contains(obs) and info["punishment"] > 0
    assert load_map("generated:S:5").name == "generated-S-5"
    assert office_core("generated:5") is office_core("generated:M:5")  # SIZE defaults to M; computed once


def test_generated_map_option_batched_and_real_envs() -> None:
    venv = gym.make_vec("NomadOffice-v0", map="generated:S:5", **VEC)
    venv.reset(seed=0)
    _, _, _, _, info = venv.step(np.array([0, 1]))
    lattice = office_core("generated:S:5").lattice
    assert len(info["position_cm"]) == 2 and all(lattice.index(xy) >= 0 for xy in info["position_cm"])
    real = gym.make("NomadOfficeReal-v0", map="generated:S:5")
    real.reset(seed=0)
    assert np.isfinite(real.step(0)[0]).all()


def test_generated_map_option_memorable_env(tmp_path) -> None:
    with pytest.raises(ValueError, match="record one with `sb3-twodrl-record-database --map generated:S:5"):
        gym.make("NomadOfficeMemorable-v0", map="generated:S:5")
    database = save_database(record_database(1, map="generated:S:5"), tmp_path / "s5.npz")
    env = gym.make("NomadOfficeMemorable-v0", map="generated:S:5", database=str(database))
    env.reset(seed=0)
    assert env.observation_space.contains(env.step(1)[0])


@pytest.mark.parametrize("bad", ["generated:", "generated:X:3", "generated:-1", "generated:S:3:4", "generated:S:x"])
def test_bad_generated_map_names_the_form(bad: str) -> None:
    with pytest.raises(ValueError, match=r"'generated:SEED' or 'generated:SIZE:SEED'") as err:
        gym.make("NomadOffice-v0", map=bad)
    assert repr(bad) in str(err.value)


def test_generated_source_is_canonical() -> None:
    assert map_source("generated:7") == map_source("generated:M:007") == "generated:M:7"


def test_map_command_writes_a_map_file(tmp_path, capsys) -> None:
    out = tmp_path / "my_office.json"
    map_main(["--seed", "7", "--size", "S", "--out", str(out)])
    assert json.loads(out.read_text()) == generate_map(7, "S")
    office = load_map(out)
    assert office.name == "generated-S-7" and office.source == str(out)
    printed = capsys.readouterr().out
    moves = shortest_path_moves(office, build_lattice(office))
    assert f"shortest path {moves} moves" in printed and f"wrote {out}" in printed


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--seed", "-1"], "argument --seed: must be an integer >= 0, got '-1'"),
        (["--seed", "1", "--size", "XL"], "argument --size: invalid choice: 'XL'"),
        (["--seed", "1", "--out", "map.txt"], "--out must end in .json"),
        (["--seed", "1", "--out", "exists.json"], "exists (pass --force to overwrite it)"),
        (["--seed", "1", "--out", "nowhere/map.json"], "--out: directory"),
    ],
)
def test_map_command_bad_arguments(tmp_path, capsys, monkeypatch, argv: list[str], message: str) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "exists.json").write_text("{}")
    if "--out" not in argv:
        argv = [*argv, "--out", "map.json"]
    with pytest.raises(SystemExit):
        map_main(argv)
    assert message in capsys.readouterr().err
    assert not (tmp_path / "map.json").exists()
