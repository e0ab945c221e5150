"""Nomad 200 range sensors: 16 sonar and 16 infrared around the body (paper section 3.2).

Sensor ``i`` of each ring sits on the 60 cm body at ``i * 22.5`` degrees counter-clockwise from
north (0 = north, 4 = west, 8 = south, 12 = east), as the Nomad numbers them; the heading is
fixed north, so bearings never change. Readings are distances from the body surface:

* sonar: nearest return inside a 22.5 degree cone (the cones tile the circle), valid 40-600 cm;
  closer returns read 40 (the transducer is still ringing), no return reads 600;
* infrared: a single narrow beam along the sensor axis, valid 0-40 cm; farther reads 40.

Normalised readings are ``(sonar - 40) / 560`` and ``ir / 40``, both in [0, 1].

The noise model is counter-based: the noise of a reading is a hash of (episode key, step,
sensor), so N robots stepped in one numpy call get exactly the noise N single robots get.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from functools import cache, cached_property
from statistics import NormalDist

import numpy as np

from twodrl_envs.nomad.geometry import ROBOT_RADIUS_CM, OfficeMap, cone_ranges

N_SONAR = 16
N_IR = 16
N_READINGS = N_SONAR + N_IR
SONAR_MIN_CM, SONAR_MAX_CM = 40.0, 600.0
IR_MAX_CM = 40.0
SONAR_HALF_ANGLE = np.deg2rad(22.5) / 2
BEARINGS = -np.deg2rad(22.5) * np.arange(16)  # clockwise-from-north bearings of sensors 0..15
_OFFSETS = ROBOT_RADIUS_CM * np.stack([np.sin(BEARINGS), np.cos(BEARINGS)], axis=1)


def per_sensor(sonar: float, ir: float) -> np.ndarray:
    """A ``(32,)`` array holding ``sonar`` for the 16 sonar and ``ir`` for the 16 IR readings."""
    return np.concatenate([np.full(N_SONAR, sonar), np.full(N_IR, ir)])


LOW_CM = per_sensor(SONAR_MIN_CM, 0.0)  # valid range of each reading, cm
HIGH_CM = per_sensor(SONAR_MAX_CM, IR_MAX_CM)
_INV_SCALE = 1.0 / (HIGH_CM - LOW_CM)


def exact_ranges(office: OfficeMap, positions: np.ndarray) -> np.ndarray:
    """Ideal (unsaturated) ranges ``(n, 32)`` in cm at robot centres ``(n, 2)``: 16 sonar, then 16 IR."""
    origins = positions[:, None, :] + _OFFSETS
    sonar = cone_ranges(origins, BEARINGS, SONAR_HALF_ANGLE, office.walls)
    ir = cone_ranges(origins, BEARINGS, 0.0, office.walls)
    return np.concatenate([sonar, ir], axis=1)


def normalise(ranges_cm: np.ndarray) -> np.ndarray:
    """Saturate ranges ``(..., 32)`` as the real sensors do and scale them to [0, 1] (float32)."""
    scaled = (ranges_cm - LOW_CM) * _INV_SCALE
    return np.clip(scaled, 0.0, 1.0, out=scaled).astype(np.float32)


@cache
def _normal_table() -> np.ndarray:
    """65,536 standard-normal quantiles, indexed by 16 hash bits."""
    dist = NormalDist()
    return np.array([dist.inv_cdf((k + 0.5) / 65536) for k in range(65536)])


def standard_normal(lanes: np.ndarray) -> np.ndarray:
    """Standard-normal draws from 16-bit hash lanes (any shape), by the quantile table."""
    return _normal_table()[lanes]


_SENSOR_IDS = np.arange(1, N_SONAR + 1, dtype=np.uint64)


def counter_hash(keys: np.ndarray, steps: np.ndarray) -> np.ndarray:
    """SplitMix64 of (key, step, sensor pair): ``(n, 16)`` uint64 from keys and steps ``(n,)``.

    Word ``j`` feeds sonar ``j`` and infrared ``j``: its four 16-bit lanes are the sonar drop-out
    draw, (unused), the infrared Gaussian index and the sonar Gaussian index.
    """
    x = keys[:, None] + (steps.astype(np.uint64)[:, None] * np.uint64(64) + _SENSOR_IDS) * np.uint64(0x9E3779B97F4A7C15)
    x ^= x >> np.uint64(30)
    x *= np.uint64(0xBF58476D1CE4E5B9)
    x ^= x >> np.uint64(27)
    x *= np.uint64(0x94D049BB133111EB)
    x ^= x >> np.uint64(31)
    return x


@dataclass(frozen=True)
class NoiseModel:
    """Per-step sensor noise: Gaussian with ``sd = sd_cm + sd_frac * range`` and sonar drop-outs.

    A drop-out (probability ``dropout``) is a specular reflection that never returns: the sonar
    reads its maximum range.
    """

    sonar_sd_cm: float = 2.0
    sonar_sd_frac: float = 0.02
    ir_sd_cm: float = 1.0
    ir_sd_frac: float = 0.05
    dropout: float = 0.05

    def __post_init__(self) -> None:
        for name in ("sonar_sd_cm", "sonar_sd_frac", "ir_sd_cm", "ir_sd_frac"):
            value = getattr(self, name)
            if not isinstance(value, int | float) or not value >= 0:
                raise ValueError(f"NoiseModel.{name} must be a number >= 0, got {value!r}")
        if not isinstance(self.dropout, int | float) or not 0 <= self.dropout <= 1:
            raise ValueError(f"NoiseModel.dropout must be in [0, 1], got {self.dropout!r}")

    @cached_property
    def _sd_terms(self) -> tuple[np.ndarray, np.ndarray]:
        return per_sensor(self.sonar_sd_cm, self.ir_sd_cm), per_sensor(self.sonar_sd_frac, self.ir_sd_frac)

    def sd(self, ranges_cm: np.ndarray) -> np.ndarray:
        """Noise standard deviation ``(..., 32)`` of exact ranges (cm)."""
        base, frac = self._sd_terms
        return base + frac * ranges_cm

    def apply(
        self, ranges_cm: np.ndarray, keys: np.ndarray, steps: np.ndarray, sd: np.ndarray | None = None
    ) -> np.ndarray:
        """Noisy ranges ``(n, 32)`` in cm from exact ranges, episode keys and step counters ``(n,)``.

        ``sd`` may pass ``self.sd(ranges_cm)`` precomputed (e.g. per lattice cell).
        """
        lanes = counter_hash(keys, steps).view(np.uint16).reshape(len(keys), N_SONAR, 4)
        if sys.byteorder == "big":
            lanes = lanes[..., ::-1]
        table = _normal_table()
        sd = self.sd(ranges_cm) if sd is None else sd
        noisy = np.empty_like(ranges_cm)
        np.multiply(sd[:, :N_SONAR], table[lanes[..., 3]], out=noisy[:, :N_SONAR])
        np.multiply(sd[:, N_SONAR:], table[lanes[..., 2]], out=noisy[:, N_SONAR:])
        noisy += ranges_cm
        np.copyto(noisy[:, :N_SONAR], SONAR_MAX_CM, where=lanes[..., 0] < round(self.dropout * 65536))
        return noisy

    def sample(self, ranges_cm: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Independent noisy ranges ``(n, 32)`` in cm: each row the first step of a fresh episode key from ``rng``."""
        keys = rng.integers(0, 2**63, size=len(ranges_cm), dtype=np.uint64)
        return self.apply(ranges_cm, keys, np.zeros(len(ranges_cm), dtype=np.int64))


def realistic_readings(
    office: OfficeMap, positions: np.ndarray, noise: NoiseModel, rng: np.random.Generator
) -> np.ndarray:
    """Normalised noisy readings ``(n, 32)`` at arbitrary poses (ray cast, then :meth:`NoiseModel.sample`)."""
    return normalise(noise.sample(exact_ranges(office, positions), rng))
