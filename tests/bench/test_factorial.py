"""The factorial's registered metrics and rules (docs/factorial.md) on rows whose answers are known."""

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from twodrl_bench.folders import read_spec
from twodrl_bench.protocol import COLUMNS
from twodrl_bench.reports import factorial, find_parts


def rows(seed: int, detour: list[float], shortcut_end: float = 1.0, reward: float = 0.28, algo: str = "a2c"):
    """200 epochs: detour shares as given per epoch block, goal rate 1 from epoch 3."""
    epochs = np.arange(1, 201)
    detour_share = np.repeat(detour, 200 // len(detour))
    detour_share[-20:] = 1.0 - shortcut_end
    return pd.DataFrame(
        {
            "env": "NomadOffice-v0",
            "algo": algo,
            "seed": seed,
            "epoch": epochs,
            "learn_episodes": epochs * 1000,
            "goal_rate": np.where(epochs >= 3, 1.0, 0.0),
            "reward_per_step": reward,
            "shortcut_share": 1.0 - detour_share,
            "detour_share": detour_share,
            "collision_rate": 0.0,
            "interest_share": math.nan,
            "mean_temperature": math.nan,
            "env_steps": epochs * 20_000,
            "wall_s": epochs * 0.5,
        }
    )[COLUMNS]


def test_run_metrics_take_the_paper_windows() -> None:
    df = rows(0, [0.9, 0.9, 0.9, 0.0], shortcut_end=0.75)  # detour 0.9 over epochs 1-150
    df.loc[df["epoch"] == 10, "detour_share"] = math.nan  # an epoch with no labelled trial is left out
    m = factorial.run_metrics(df)
    assert m["early_detour_share"] == pytest.approx(0.9)
    assert m["final_shortcut_share"] == pytest.approx(0.75) and m["final_detour_share"] == pytest.approx(0.25)
    assert (m["learned"], m["epochs_to_half"], m["reward_per_step"]) == (1.0, 3.0, pytest.approx(0.28))


def test_a_cell_read_at_fewer_epochs_has_the_metrics_of_those_epochs(tmp_path: Path) -> None:
    write_arm(tmp_path / "cell" / "a2c", [rows(0, [0.9, 0.9, 0.9, 0.0], shortcut_end=0.75)])
    (full,), (short,) = (read_cells(tmp_path, n)["cell"]["a2c"] for n in (None, 20))
    assert (full["epochs"], full["final_shortcut_share"]) == (200, pytest.approx(0.75))
    assert (short["epochs"], short["final_shortcut_share"]) == (20, pytest.approx(0.1))
    assert short["early_detour_share"] == pytest.approx(0.9) and short["epochs_to_half"] == 3.0
    with pytest.raises(ValueError, match="epochs must be >= 1, got 0"):
        read_cells(tmp_path, 0)


def write_arm(folder: Path, frames: list[pd.DataFrame], ent_coef: float = 0.0, **rules) -> None:
    """The rows of arm ``folder.name`` in the run folder of cell ``folder.parent`` (its spec made or extended)."""
    cell, arm = folder.parent, folder.name
    spec = read_spec(cell) or {"name": f"factorial/{cell.name}", "arms": {}, "report": "factorial"}
    spec["rules"] = {**factorial.RULES, **rules}
    spec["arms"][arm] = {"algo": arm, "hyperparams": {"ent_coef": ent_coef}}
    (cell / "rows").mkdir(parents=True, exist_ok=True)
    (cell / "spec.yml").write_text(yaml.safe_dump(spec))
    for df in frames:
        df.insert(0, "arm", arm)
        df.to_csv(cell / "rows" / f"{arm}_seed{df['seed'][0]}.csv", index=False)


def read_cells(root: Path, epochs: int | None = None):
    return factorial.read_cells(find_parts(root, "factorial"), epochs)


def test_the_rules_turn_on_where_the_paper_result_is_and_off_where_it_is_not(tmp_path: Path) -> None:
    rng = np.random.default_rng(0)
    paper, ours = tmp_path / "paper_like", tmp_path / "ours"
    write_arm(paper / "a2c", [rows(s, [0.95] * 3 + [0.9], shortcut_end=rng.uniform(0, 0.1)) for s in range(5)])
    write_arm(
        paper / "learned_skip_uniform",
        [rows(s, [0.5], shortcut_end=rng.uniform(0.9, 1.0), algo="twoda2c") for s in range(5)],
    )
    write_arm(ours / "a2c", [rows(s, [0.0], reward=0.28 + rng.normal(0, 1e-3)) for s in range(5)])
    write_arm(ours / "learned_skip_uniform", [rows(s, [0.0], algo="twoda2c") for s in range(5)])
    cells = read_cells(tmp_path)
    lines = factorial.verdicts(cells).splitlines()[2:]
    assert [line.split("|")[1].strip() for line in lines] == ["ours", "paper_like"]
    assert lines[0].rstrip(" |").endswith("False") and "| False |" in lines[0]
    assert lines[1].rstrip(" |").endswith("True") and "| True |" in lines[1]
    assert factorial.table(cells).count("\n") == 1 + 4
    per_seed = factorial.seeds_table(cells).splitlines()[2:]
    assert len(per_seed) == 20 and per_seed[0].startswith("| ours | a2c | 0 | 1.000 | 3.000 | 0.000 |")


def test_no_rows_is_an_error(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="no run folder of it"):
        read_cells(tmp_path)
    write_arm(tmp_path / "ent0" / "a2c", [])
    with pytest.raises(ValueError, match="no cell with rows"):
        read_cells(tmp_path)


def test_figures_draw_each_cell_with_every_arm(tmp_path: Path) -> None:
    pytest.importorskip("matplotlib")
    write_arm(tmp_path / "runs" / "cell" / "a2c", [rows(s, [0.5]) for s in range(2)])
    write_arm(tmp_path / "runs" / "cell" / "twoda2c", [rows(0, [0.0], algo="twoda2c")])
    text = factorial.report(find_parts(tmp_path / "runs", "factorial"), tmp_path / "out")
    names = sorted(p.name for p in (tmp_path / "out" / "cell").iterdir())
    assert names == ["fig3_goal_rate.png", "fig4_reward_per_step.png", "fig5_route_share.png"]
    assert text == (tmp_path / "out" / "table.md").read_text() and "| cell | a2c |" in text


def test_a_cell_stating_other_rules_is_refused(tmp_path: Path) -> None:
    write_arm(tmp_path / "cell" / "a2c", [rows(0, [0.5])], detour_on=0.5)
    with pytest.raises(ValueError, match=r"factorial/cell: rules differ.*detour_on: 0\.3 != 0\.5"):
        factorial.report(find_parts(tmp_path, "factorial"), tmp_path / "out")


def bonus_cells(tmp_path: Path, twoda2c_reward: float) -> Path:
    """Cells ``ent0`` (A2C fails) and ``ent0.05`` (A2C learns at 0.28), TwoDimA2C at 0 as given."""
    rng = np.random.default_rng(1)
    failed = [rows(s, [1.0], reward=-0.06 + rng.normal(0, 1e-3)).assign(goal_rate=0.0) for s in range(10)]
    write_arm(tmp_path / "ent0" / "a2c", failed)
    write_arm(
        tmp_path / "ent0" / "twoda2c",
        [rows(s, [0.0], reward=twoda2c_reward + rng.normal(0, 1e-3), algo="twoda2c") for s in range(10)],
    )
    write_arm(tmp_path / "ent0.05" / "a2c", [rows(s, [0.0], reward=0.28 + rng.normal(0, 1e-3)) for s in range(10)])
    return tmp_path


@pytest.mark.parametrize(("reward", "verdict"), [(0.28, "holds"), (0.25, "fails")])
def test_the_bonus_claim_compares_the_2d_arm_without_bonus_to_a2c_at_its_best(
    tmp_path: Path, reward: float, verdict: str
) -> None:
    claim = factorial.bonus_claim(read_cells(bonus_cells(tmp_path, reward)))
    assert f"its best, `ent0.05`): **{verdict}**" in claim
    assert "provisional: short of 10 seeds or cells: ent0.01)" in claim and "bonus matters: True" in claim


def test_the_bonus_claim_is_untested_when_a2c_does_best_without_bonus(tmp_path: Path) -> None:
    runs = bonus_cells(tmp_path, 0.28)
    for csv in (runs / "ent0.05" / "rows").glob("a2c_seed*.csv"):
        pd.read_csv(csv).assign(reward_per_step=-0.5).to_csv(csv, index=False)
    assert "**untested: the entropy bonus does not matter" in factorial.bonus_claim(read_cells(runs))


def test_a_bonus_cell_at_another_ent_coef_is_refused(tmp_path: Path) -> None:
    write_arm(tmp_path / "ent0.01" / "a2c", [rows(0, [0.5])], ent_coef=0.05)
    with pytest.raises(ValueError, match=r"'ent0\.01' arm 'a2c' has ent_coef 0\.05"):
        factorial.check_bonus_cells(find_parts(tmp_path, "factorial"))


def test_effects_measure_each_cell_against_the_protocol_cell(tmp_path: Path) -> None:
    lines = factorial.effects(read_cells(bonus_cells(tmp_path, 0.28))).splitlines()[2:]
    assert len(lines) == 1 and lines[0].startswith("| ent0 | a2c | 0/10 vs 10/10 | +1.000 [+1.000, +1.000] | +0.000 ")
    diff = float(lines[0].split("|")[-2].split()[0])
    assert diff == pytest.approx(-0.34, abs=0.01)


def test_an_arm_without_finished_rows_is_left_out(tmp_path: Path) -> None:
    write_arm(tmp_path / "ent0" / "a2c", [rows(0, [0.5]), rows(1, [0.5])])
    write_arm(tmp_path / "ent0.05" / "a2c", [])
    assert list(read_cells(tmp_path)) == ["ent0"]


def test_an_arm_that_never_reaches_a_route_has_no_shortcut_difference(tmp_path: Path) -> None:
    """An arm whose runs all end without a labelled trial: "-" for its share difference, and the rule off."""
    write_arm(tmp_path / "cell" / "a2c", [rows(s, [0.0]) for s in range(3)])
    never = [rows(s, [math.nan], algo="twoda2c").assign(shortcut_share=math.nan) for s in range(3)]
    write_arm(tmp_path / "cell" / "twoda2c", never)
    line = factorial.verdicts(read_cells(tmp_path)).splitlines()[2]
    assert line.split("|")[4].strip() == "-" and line.rstrip(" |").endswith("False") and "nan" not in line


def long_rows(seed: int, window_detour: float, shortcut_end: float, algo: str) -> pd.DataFrame:
    """1000 epochs: detour share ``window_detour`` over epochs 151-400, routes split otherwise."""
    df = pd.concat([rows(seed, [0.5], algo=algo)] * 5, ignore_index=True)
    df["epoch"] = np.arange(1, 1001)
    detour = np.where(df["epoch"].between(151, 400), window_detour, 0.5)
    detour[-100:] = 1.0 - shortcut_end
    return df.assign(detour_share=detour, shortcut_share=1.0 - detour)


def test_the_paper_result_is_read_from_a_complete_long_cell(tmp_path: Path) -> None:
    rng = np.random.default_rng(1)
    for cell, a2c_detour in (("paper_like", 0.9), ("ours", 0.1)):
        write_arm(tmp_path / cell / "a2c", [long_rows(s, a2c_detour, rng.uniform(0, 0.1), "a2c") for s in range(10)])
        frames = [long_rows(s, 0.5, rng.uniform(0.9, 1.0), "twoda2c") for s in range(10)]
        write_arm(tmp_path / cell / "twoda2c", frames)
    write_arm(tmp_path / "short" / "a2c", [rows(s, [0.9]) for s in range(10)])  # 200 epochs: not read here
    cells = read_cells(tmp_path)
    assert cells["paper_like"]["a2c"][0]["window_detour_share"] == pytest.approx(0.9)
    assert math.isnan(cells["short"]["a2c"][0]["window_detour_share"])
    lines = factorial.paper_result(cells).splitlines()[2:]
    assert [line.split("|")[1].strip() for line in lines] == ["ours", "paper_like"]
    assert lines[0].rstrip(" |").endswith("False") and lines[1].rstrip(" |").endswith("True")


def test_a_long_cell_short_of_seeds_has_no_rule_read(tmp_path: Path) -> None:
    """Amendment 8: the rules at 1000 epochs wait for every seed of both arms."""
    write_arm(tmp_path / "cell_1000" / "a2c", [long_rows(s, 0.9, 0.0, "a2c") for s in range(3)])
    write_arm(tmp_path / "cell_1000" / "twoda2c", [long_rows(s, 0.5, 1.0, "twoda2c") for s in range(2)])
    cells = read_cells(tmp_path)
    for text in (factorial.verdicts(cells), factorial.paper_result(cells)):
        line = text.splitlines()[2]
        assert "not read (3 and 2 of 10 seeds)" in line and "True" not in line and "False" not in line


def test_every_packaged_cell_states_the_registered_rules() -> None:
    from twodrl_bench.reports import Part
    from twodrl_bench.spec import load_spec, packaged_specs

    cells = [load_spec(name) for name in packaged_specs() if name.startswith("factorial/")]
    assert len(cells) == 6
    parts = [Part(spec["name"], spec["name"].split("/")[1], spec, pd.DataFrame(), Path()) for spec in cells]
    assert factorial.check_rules(parts) == [20]
