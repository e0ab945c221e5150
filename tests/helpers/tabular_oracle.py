"""A plain numpy actor-critic on tables, per-step updates: the test oracle of ``docs/tabular.md``.

With two streams (reward, punishment), ``actor_update="preference"`` and ``temperature="interest"``
it is the paper's 2D-RL (Okada et al., eq. 5-10); with one stream, ``actor_update="log_prob"`` and
``temperature=1.0`` it is the textbook one-step actor-critic that SB3's A2C becomes on a table.
"""

from collections.abc import Sequence

import numpy as np

ACTOR_UPDATES = ("preference", "log_prob")


def softmax(z: np.ndarray) -> np.ndarray:
    """``exp(z) / sum(exp(z))``, shifted by the maximum."""
    e = np.exp(z - z.max())
    return e / e.sum()


class TabularActorCritic:
    """Critic tables ``V_i[s]`` (one per evaluation stream), a preference table ``p[s, a]`` and the softmax of eq. 9.

    :param preferences: the initial ``p`` ``(n_states, n_actions)``
    :param values: the initial critics ``(n_streams, n_states)``
    :param gammas: each stream's discount (eq. 5-6)
    :param alphas: each critic's step size: ``V_i[s] += alpha_i * delta_i``
    :param signs: each stream's sign in the utility ``delta- = sum_i sign_i * delta_i`` (eq. 1: ``(1, -1)``)
    :param beta: the actor's step size
    :param actor_update: ``"preference"`` (eq. 10: ``p[s, a] += beta * delta-``) or ``"log_prob"``
        (``p[s, :] += beta * delta- * (1[a] - pi(.|s))``, the gradient of ``log pi(a|s)`` of the softmax)
    :param temperature: ``"interest"`` (eq. 9 with ``T = delta+ = sum_i |delta_i|`` of the transition into
        the state, eq. 2, clamped to ``[min_temperature, max_temperature]``; uniform when it is 0, as at
        an episode's start) or a fixed temperature
    """

    def __init__(
        self,
        preferences: np.ndarray,
        values: np.ndarray,
        gammas: Sequence[float],
        alphas: Sequence[float],
        signs: Sequence[float],
        beta: float,
        actor_update: str,
        temperature: str | float,
        min_temperature: float = 0.0,
        max_temperature: float = np.inf,
    ) -> None:
        if actor_update not in ACTOR_UPDATES:
            raise ValueError(f"actor_update must be one of {ACTOR_UPDATES}, got {actor_update!r}")
        self.preferences = np.array(preferences, dtype=np.float64)
        self.values = np.array(values, dtype=np.float64)
        self.gammas, self.alphas, self.signs = (np.array(x, dtype=np.float64) for x in (gammas, alphas, signs))
        self.beta = beta
        self.actor_update = actor_update
        self.temperature = temperature
        self.min_temperature, self.max_temperature = min_temperature, max_temperature
        self.interest = 0.0  # delta+ of the transition into the current state; none at an episode's start

    def policy(self, state: int) -> np.ndarray:
        """``pi(state, .)`` of eq. 9: softmax of ``p[state] / T``; uniform at ``delta+ = 0`` (interest mode)."""
        if self.temperature == "interest":
            if self.interest == 0.0:
                return np.full(self.preferences.shape[1], 1.0 / self.preferences.shape[1])
            temperature = min(max(self.interest, self.min_temperature), self.max_temperature)
        else:
            temperature = float(self.temperature)
        return softmax(self.preferences[state] / temperature)

    def step(
        self,
        state: int,
        action: int,
        evaluations: Sequence[float],
        next_state: int,
        terminated: bool,
        truncated: bool,
    ) -> None:
        """One transition: TD errors (eq. 7-8), critics (eq. 5-6 as targets), actor (eq. 10).

        A terminal step (``terminated``) has no successor value. A time-limit cut (``truncated``)
        bootstraps on the state it reached (``next_state``), as SB3 does. After either, the next
        state starts an episode: interest 0.
        """
        bootstrap = 0.0 if terminated else 1.0
        deltas = (
            np.asarray(evaluations, dtype=np.float64)
            + bootstrap * self.gammas * self.values[:, next_state]
            - self.values[:, state]
        )
        utility = float(self.signs @ deltas)
        self.values[:, state] += self.alphas * deltas
        if self.actor_update == "preference":
            self.preferences[state, action] += self.beta * utility
        else:
            pi = softmax(self.preferences[state])  # the untempered policy, whose log-probability is differentiated
            self.preferences[state] += self.beta * utility * (np.eye(len(pi))[action] - pi)
        self.interest = 0.0 if terminated or truncated else float(np.abs(deltas).sum())
