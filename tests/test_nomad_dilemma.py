"""The office poses the paper's dilemma under a random policy, before any learning (issue 4)."""

from scripts.check_dilemma import measure_dilemma


def test_detour_easy_to_find_shortcut_risky_and_short():
    result = measure_dilemma(n_walks=20_000, seed=0)
    assert result["entry_ratio_detour_over_shortcut"] >= 2.0
    assert result["collide_in_shortcut_given_entered"] > result["collide_in_detour_given_entered"]
    assert result["shortcut_moves"] <= 0.6 * result["detour_moves"]
