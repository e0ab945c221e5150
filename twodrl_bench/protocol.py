"""What an epoch job's rows hold (section 3.4.1): the CSV columns, the test trials' seeds, env arguments.

An *epoch* is K learning trials (episodes; paper: 1000) followed by M test trials (paper: 100)
with other random numbers (:class:`~twodrl_bench.experiment.EpochProtocol`).
"""

from __future__ import annotations

from typing import Any

ROUTES = ("shortcut", "detour")
"""The office's route labels (``info["route"]``), whose shares are columns even when no test trial took one."""
METRICS = ("goal_rate", "reward_per_step", *(f"{route}_share" for route in ROUTES), "collision_rate")
LEARNING = ("interest_share", "mean_temperature")
"""Per epoch, over the learning steps of the rollouts that ended in it: the share of actions whose
temperature the interest (not a clamp) set, and the mean temperature (NaN for stock SB3 algorithms)."""
COLUMNS = ["env", "algo", "seed", "epoch", "learn_episodes", *METRICS, *LEARNING, "env_steps", "wall_s"]


def parse_env_kwargs(items: list[str] | None, name: str = "env_kwargs") -> dict[str, Any]:
    """``["key:value", ...]`` (rl-zoo3's ``--env-kwargs`` format, values as Python literals) as a dict;
    ``name`` is the option named in the error."""
    import ast

    out: dict[str, Any] = {}
    for item in items or []:
        key, sep, value = item.partition(":")
        try:
            if not (sep and key.isidentifier()):
                raise ValueError
            out[key] = ast.literal_eval(value)
        except (ValueError, SyntaxError):
            raise ValueError(f"{name} items must be key:value with a Python literal value, got {item!r}") from None
    return out


def trial_seed(seed: int, epoch: int) -> int:
    """Seed of epoch ``epoch``'s test trials: disjoint from the learning seeds (which are < 10**6)."""
    return 10**6 + 1_000 * (seed % 10**6) + epoch
