"""What the robot measures, turned into the env's observation by a torch module: the input stage of a deployed policy.

A policy trained on ``NomadOffice-v0`` (or its stand-in and replay variants) reads normalised readings and an
odometry position scaled by the map's bounds. On the robot, :class:`RawObservation` takes what the robot
measures, float64 ``(n, 34)``: the 16 sonar and 16 IR ranges in cm (sensor order of :mod:`twodrl_envs.nomad.sensors`)
then the odometry ``(x, y)`` in cm (``(n, 32)`` without odometry), and gives the observation exactly as the env
computes it (:func:`~twodrl_envs.nomad.sensors.normalise`, :meth:`~twodrl_envs.nomad.core.OfficeCore.odometry`, in
float64, then float32). ``sb3-twodrl-export --input-stage`` puts it in front of the actor, so the exported graph
holds the normalisation and the map's bounds.
"""

from pathlib import Path

import numpy as np
import torch
from torch import nn

from twodrl_envs.nomad import sensors
from twodrl_envs.nomad.maps import load_map


class RawObservation(nn.Module):
    """Raw ranges (cm) and odometry (cm) -> the observation of an env on ``map`` (module docstring)."""

    input_dtype = torch.float64
    low: torch.Tensor
    inv_scale: torch.Tensor
    origin: torch.Tensor
    extent: torch.Tensor

    def __init__(self, map: str | Path | None = None, observe_odometry: bool = True) -> None:
        super().__init__()
        if not isinstance(observe_odometry, bool):
            raise TypeError(f"observe_odometry must be a bool, got {observe_odometry!r}")
        x0, y0, x1, y1 = load_map(map).bounds
        self.observe_odometry = observe_odometry
        self.input_shape = (sensors.N_READINGS + (2 if observe_odometry else 0),)
        self.register_buffer("low", torch.as_tensor(sensors.LOW_CM, dtype=torch.float64))
        self.register_buffer(
            "inv_scale", torch.as_tensor(1.0 / (sensors.HIGH_CM - sensors.LOW_CM), dtype=torch.float64)
        )
        self.register_buffer("origin", torch.as_tensor(np.array([x0, y0]), dtype=torch.float64))
        self.register_buffer("extent", torch.as_tensor(np.array([x1 - x0, y1 - y0]), dtype=torch.float64))

    def forward(self, raw: torch.Tensor) -> torch.Tensor:
        raw = raw.double()
        readings = torch.clamp((raw[:, : sensors.N_READINGS] - self.low) * self.inv_scale, 0.0, 1.0)
        if not self.observe_odometry:
            return readings.float()
        odometry = torch.clamp((raw[:, sensors.N_READINGS :] - self.origin) / self.extent, 0.0, 1.0)
        return torch.cat([readings.float(), odometry.float()], dim=1)
