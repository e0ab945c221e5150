"""How the interest ``delta+`` (eq. 2) sets the softmax temperature (eq. 9) under function approximation.

Eq. 9 divides the preferences ``p(s, a)`` by ``delta+``. In the paper's tabular actor both have a
fixed scale; with neural critics and a neural actor neither has: the TD errors of a generalising
critic shrink everywhere at once, and the actor's outputs grow without bound. Two settings choose
how eq. 9 keeps its meaning (README, "Design notes"):

``interest`` (what sets ``T``):

- ``"paper"``: ``T = delta+`` of the transition that led into the current state, clamped to
  ``[min_temperature, max_temperature]``; an interest of exactly 0 (an episode's first step) means
  uniform actions. Eq. 9 literally.
- ``"relative"``: ``T = delta+ / mean(delta+)``, the same interest on a dimensionless scale: relative
  to the running mean of recent transitions' interest (:data:`INTEREST_SCALE_RATE`), so that
  ``T = 1`` means an ordinary surprise, whatever the size of the rewards or how settled the critics
  are. Clamped and 0 as in ``"paper"``.
- ``"learned"`` (``TwoDimA2C``'s default): ``T = I(s) / mean(delta+)``, ``I(s)`` a head of the
  critic network trained on the ``delta+`` of the transitions out of ``s``: an estimate of
  ``E[delta+ | s]``, the paper's "criticality" of a state, known before acting in it (eq. 9's
  ``delta+(t)`` depends on ``a(t)`` itself), and a smooth function of the state where the
  transition's interest is one noisy draw. Clamped; no uniform first step (the head has a value
  there); no head at a fixed temperature.

``preferences`` (what ``T`` divides, categorical actions only):

- ``"raw"``: the actor's outputs (eq. 9 literally).
- ``"bounded"``: the actor's outputs divided by ``max(1, sd_a p(s, .) / B)``: preferences whose
  spread over the actions is at most ``B`` (``preference_bound``, default 1). A temperature then has
  a fixed meaning however large the actor's outputs grow, and the clamp ``min_temperature`` bounds
  how deterministic the behaviour can get: no action's probability drops below a fixed share, so a
  failure the critics have come to predict (``delta+ = 0``, utility 0) is still tried against its
  alternatives. A Gaussian's mean is not a preference; its std is multiplied by ``T`` in every mode.
"""

import numpy as np
import torch as th

INTEREST_MODES = ("paper", "relative", "learned")
PREFERENCE_MODES = ("raw", "bounded")

INTEREST_SCALE_RATE = 0.01
"""Weight of each step's mean interest in the running scale of the ``"relative"`` and ``"learned"`` modes."""

PREFERENCE_BOUND = 1.0
"""Default largest standard deviation over the actions of the ``"bounded"`` preferences (``preference_bound``)."""


def check_interest_modes(interest: str, preferences: str) -> None:
    """Raise ``ValueError`` unless ``interest`` and ``preferences`` name modes of this module."""
    if interest not in INTEREST_MODES:
        raise ValueError(f"interest must be one of {INTEREST_MODES}, got {interest!r}")
    if preferences not in PREFERENCE_MODES:
        raise ValueError(f"preferences must be one of {PREFERENCE_MODES}, got {preferences!r}")


def relative_interest(interest: np.ndarray, scale: float) -> np.ndarray:
    """``interest / scale``; 1 while no scale is known yet (``scale = 0``), 0 stays 0."""
    if scale > 0.0:
        return interest * np.float32(1.0 / scale)
    return (interest > 0).astype(np.float32)


def updated_scale(scale: float, interest: np.ndarray, dones: np.ndarray) -> float:
    """Fold one vectorised step's mean interest (transitions that did not end an episode) into ``scale``."""
    live = interest[~dones]
    if not live.size:
        return scale
    mean = float(live.sum()) / live.size
    return mean if scale == 0.0 else scale + INTEREST_SCALE_RATE * (mean - scale)


def bounded_preferences(logits: th.Tensor, bound: float = PREFERENCE_BOUND) -> th.Tensor:
    """Preferences divided by ``max(1, sd over actions / bound)``: their spread is at most ``bound``."""
    spread = logits.std(dim=-1, unbiased=False, keepdim=True)
    return logits / th.clamp(spread / bound, min=1.0)
