"""Top-down RGB frames of the office (numpy only, so ``VecVideoRecorder`` works headless)."""

from __future__ import annotations

import numpy as np

from twodrl_envs.nomad import sensors
from twodrl_envs.nomad.geometry import ROBOT_RADIUS_CM, ROUTE_REGIONS, OfficeMap, point_segment_distance

_WHITE = (255, 255, 255)
_REGION_COLOURS = dict(zip((*ROUTE_REGIONS, "goal"), ((255, 224, 178), (200, 225, 255), (190, 240, 190)), strict=True))
"""Colour of each region, drawn in this order: the route regions (orange, blue), then the goal (green)."""
_WALL = (30, 30, 30)
_CONE = (255, 246, 160)
_TRAIL = (220, 60, 60)
_ROBOT = (40, 90, 200)
_START = (20, 150, 20)


class OfficeRenderer:
    """Draws an :class:`OfficeMap` at ``scale`` pixels per cm with a ``margin`` in pixels."""

    def __init__(self, office: OfficeMap, scale: float = 1.5, margin: int = 8) -> None:
        self.office, self.scale, self.margin = office, scale, margin
        x0, y0, x1, y1 = office.bounds
        self.width = round((x1 - x0) * scale) + 2 * margin
        self.height = round((y1 - y0) * scale) + 2 * margin
        rows, cols = np.mgrid[0 : self.height, 0 : self.width]
        self._xy = np.stack([(cols - margin) / scale + x0, y1 - (rows - margin) / scale], axis=-1)
        self._background = self._draw_background()

    def _draw_background(self) -> np.ndarray:
        image = np.full((self.height, self.width, 3), _WHITE, dtype=np.uint8)
        for name, colour in _REGION_COLOURS.items():  # a region the map lacks is nowhere
            image[self.office.in_region(name, self._xy)] = colour
        for wall in self.office.walls:
            self._segment(image, wall[:2], wall[2:], _WALL, width_cm=3.0)
        start = np.array(self.office.start)
        image[np.abs(self._xy - start).max(axis=-1) <= 6] = _START
        return image

    def _segment(self, image: np.ndarray, a: np.ndarray, b: np.ndarray, colour: tuple, width_cm: float) -> None:
        image[point_segment_distance(self._xy, np.concatenate([a, b])[None])[..., 0] <= width_cm / 2] = colour

    def _dots(self, image: np.ndarray, points: np.ndarray, colour: tuple) -> None:
        x0, _, _, y1 = self.office.bounds
        cols = np.round((points[:, 0] - x0) * self.scale + self.margin).astype(int)
        rows = np.round((y1 - points[:, 1]) * self.scale + self.margin).astype(int)
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                image[np.clip(rows + dr, 0, self.height - 1), np.clip(cols + dc, 0, self.width - 1)] = colour

    def frame(self, position: np.ndarray, trajectory: list[tuple[float, float]]) -> np.ndarray:
        """An ``(H, W, 3)`` uint8 frame with the robot at ``position`` and its past ``trajectory``."""
        image = self._background.copy()
        rel = self._xy - position
        dist = np.hypot(rel[..., 0], rel[..., 1])
        sonar = np.clip(
            sensors.exact_ranges(self.office, np.asarray(position)[None])[0, : sensors.N_SONAR], 0, sensors.SONAR_MAX_CM
        )
        ccw_from_north = np.arctan2(-rel[..., 0], rel[..., 1])
        index = np.round(ccw_from_north / np.deg2rad(22.5)).astype(int) % sensors.N_SONAR
        cone = (dist > ROBOT_RADIUS_CM) & (dist - ROBOT_RADIUS_CM <= sonar[index])
        image[cone & (image == _WHITE).all(axis=-1)] = _CONE
        if len(trajectory) > 1:
            points = np.asarray(trajectory)
            t = np.linspace(0.0, 1.0, 12)[:, None, None]
            trail = (points[:-1] + t * (points[1:] - points[:-1])).reshape(-1, 2)
            self._dots(image, trail, _TRAIL)
        image[dist <= ROBOT_RADIUS_CM] = _ROBOT
        image[np.abs(dist - ROBOT_RADIUS_CM) <= 1.0] = _WALL
        self._segment(image, np.asarray(position), np.asarray(position) + np.array([0.0, ROBOT_RADIUS_CM]), _WHITE, 2.0)
        return image
