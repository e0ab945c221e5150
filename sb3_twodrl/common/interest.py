"""How the interest ``delta+`` (eq. 2) sets the softmax temperature (eq. 9) under function approximation.

Eq. 9 divides the preferences ``p(s, a)`` by ``delta+``. In the paper's tabular actor both have a
fixed scale; with neural critics and a neural actor neither has: the TD errors of a generalising
critic shrink everywhere at once, and the actor's outputs grow without bound. So the temperature
is the interest on a dimensionless scale (README, "Design notes"; ``docs/interest.md``):

``T = I(s) / mean(delta+)``, ``I(s)`` a head of the critic network trained on the ``delta+`` of the
transitions out of ``s``: an estimate of ``E[delta+ | s]``, the paper's "criticality" of a state,
known before acting in it (eq. 9's ``delta+(t)`` depends on ``a(t)`` itself), and a smooth function
of the state where the transition's interest is one noisy draw; divided by the running mean of
recent transitions' interest (:data:`INTEREST_SCALE_RATE`), so that ``T = 1`` means an ordinary
surprise, whatever the size of the rewards or how settled the critics are; clamped to
``[min_temperature, max_temperature]``.

A policy without the head gets each transition's ``delta+`` instead (eq. 9 as written), and a subclass
may map it to ``1 / T`` otherwise: :class:`~sb3_twodrl.common.policies.TwoDimPolicyMixin`, its extension points.
"""

import numpy as np

INTEREST_SCALE_RATE = 0.01
"""Weight of each step's mean interest in the running scale ``mean(delta+)``."""


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
