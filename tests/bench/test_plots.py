"""The results tables of the experiment runner's CSV."""

import numpy as np
import pandas as pd

from twodrl_bench.plots import window_table


def rows(epochs: int, seeds: int = 2) -> pd.DataFrame:
    epoch = np.tile(np.arange(1, epochs + 1), seeds)
    return pd.DataFrame(
        {
            "algo": "a2c",
            "seed": np.repeat(np.arange(seeds), epochs),
            "epoch": epoch,
            "goal_rate": (epoch > 150).astype(float),
            "reward_per_step": 0.1,
            "shortcut_share": np.where(epoch > 150, 0.0, np.nan),
            "collision_rate": 0.0,
        }
    )


def test_window_table_averages_each_paper_window_and_cuts_the_last_to_the_epochs_run() -> None:
    lines = window_table(rows(200)).splitlines()[2:]
    assert [line.split(" | ")[1] for line in lines] == ["1-150", "151-200"]
    first, second = (line.split(" | ") for line in lines)
    assert first[3] == "0.00 ± 0.00" and second[3] == "1.00 ± 0.00"
    assert first[5] == "n/a" and second[5] == "0.00 ± 0.00"  # no routed episode in the first window


def test_window_table_of_no_rows() -> None:
    assert window_table(rows(0)) == "(no results)\n"
