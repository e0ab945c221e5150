"""Office geometry: map files, swept-disc collision and exact cone ranging (paper section 3.2).

All lengths are centimetres, x grows east and y grows north. Walls are line segments; an
obstacle polygon is stored as its edges. Every function is vectorised with numpy.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROBOT_RADIUS_CM = 30.0
STEP_CM = 10.0
ROUTE_REGIONS = ("shortcut", "detour")
"""The route regions' names, the route labels (:data:`twodrl_envs.nomad.core.ROUTE_CODES` gives their codes)."""


@dataclass(frozen=True)
class OfficeMap:
    """A validated office: wall segments ``(n, 4)`` as ``x0, y0, x1, y1`` and named rectangles.

    ``regions`` maps ``goal`` and, on a map with a route choice, ``shortcut`` and ``detour`` to
    ``(xmin, ymin, xmax, ymax)``: the goal is reached, and a route is committed to, when the robot's
    centre enters the rectangle.
    """

    name: str
    bounds: tuple[float, float, float, float]
    walls: np.ndarray
    start: tuple[float, float]
    regions: dict[str, tuple[float, float, float, float]]
    source: str
    obstacles: tuple[np.ndarray, ...] = ()
    """The obstacle polygons ``(k, 2)`` as drawn (their edges are among ``walls``): to say what lies inside one."""

    def inside_bounds(self, xy: np.ndarray) -> np.ndarray:
        """True where a point ``(..., 2)`` lies inside the map's bounding box."""
        return _in_rect(self.bounds, xy)

    @property
    def has_routes(self) -> bool:
        """Whether the map labels routes (``shortcut`` and ``detour`` regions); without them no route is reported."""
        return ROUTE_REGIONS[0] in self.regions

    def obstacle_at(self, xy: tuple[float, float] | np.ndarray) -> int | None:
        """The index of the obstacle polygon the point ``xy`` lies inside (even-odd rule), None if none."""
        x, y = float(xy[0]), float(xy[1])
        for index, poly in enumerate(self.obstacles):
            x0, y0 = poly[:, 0], poly[:, 1]
            x1, y1 = np.roll(x0, -1), np.roll(y0, -1)
            crosses = (y0 > y) != (y1 > y)
            with np.errstate(divide="ignore", invalid="ignore"):
                at = x0 + (y - y0) * (x1 - x0) / (y1 - y0)
            if int(np.count_nonzero(crosses & (x < at))) % 2 == 1:
                return index
        return None

    def in_region(self, name: str, xy: np.ndarray) -> np.ndarray:
        """True where a point ``(..., 2)`` lies in the named rectangle (nowhere for a region the map lacks)."""
        if name not in self.regions:
            return np.zeros(np.shape(xy)[:-1], dtype=bool)
        return _in_rect(self.regions[name], xy)


def _in_rect(rect: tuple[float, float, float, float], xy: np.ndarray) -> np.ndarray:
    x0, y0, x1, y1 = rect
    return (xy[..., 0] >= x0) & (xy[..., 0] <= x1) & (xy[..., 1] >= y0) & (xy[..., 1] <= y1)


MAPS_DIR = Path(__file__).with_name("maps")
SHIPPED_MAPS = ("office", "open", "corridor")
"""Built-in maps by name: ``office`` (the default, the dilemma), ``open`` (no dilemma), ``corridor`` (one route)."""
MAX_LATTICE_POINTS = 1_000_000
"""Largest lattice a map may span (bounds / 10 cm in x times in y): 100 m x 100 m."""


def default_map_path() -> Path:
    """The office shipped with the package (``map=None`` or ``map="office"``)."""
    return MAPS_DIR / "office.json"


def _number_list(value: object, length: int, what: str, source: str) -> tuple[float, ...]:
    if (
        not isinstance(value, list)
        or not all(isinstance(v, int | float) and not isinstance(v, bool) for v in value)
        or len(value) != length
    ):
        raise ValueError(f"map file {source}: {what} must be a list of {length} numbers, got {value!r}")
    try:
        out = tuple(float(v) for v in value)
    except OverflowError:
        out = (np.inf,)
    if not all(np.isfinite(out)):
        raise ValueError(f"map file {source}: {what} must be finite, got {value!r}")
    return out


_MAP_CHOICES = f"a built-in map name ({', '.join(SHIPPED_MAPS)}), the path of a map JSON file or 'generated:SIZE:SEED'"


GENERATED_PREFIX = "generated:"
"""A map source ``generated:SEED`` or ``generated:SIZE:SEED`` is an office made by
:func:`twodrl_envs.nomad.generator.generate_map` (size ``M`` when omitted), not a file."""
MAP_KEYS = ("name", "description", "units", "bounds", "walls", "obstacles", "start", "regions")
REGION_KEYS = ("goal", *ROUTE_REGIONS)


def is_generated(source: str) -> bool:
    """Whether a resolved map source (:func:`map_source`) names a generated office rather than a file."""
    return source.startswith(GENERATED_PREFIX)


def _check_keys(data: dict, required: tuple[str, ...], allowed: tuple[str, ...], where: str, source: str) -> None:
    """``ValueError`` naming the missing and the unknown keys of an object (``where``: e.g. ``"regions."``)."""
    missing = [where + key for key in required if key not in data]
    unknown = [where + str(key) for key in data if key not in allowed]
    problems = [f"missing keys {missing}"] if missing else []
    if unknown:
        problems.append(f"unknown keys {unknown} (allowed: {', '.join(where + key for key in allowed)})")
    if problems:
        raise ValueError(f"map file {source}: {'; '.join(problems)}")


def _overlaps(rect: tuple[float, ...], bounds: tuple[float, ...]) -> bool:
    return rect[0] <= bounds[2] and rect[2] >= bounds[0] and rect[1] <= bounds[3] and rect[3] >= bounds[1]


def parse_map(data: dict, source: str) -> OfficeMap:
    """Validate a map's JSON object (the format of ``docs/own_office.md``) into an :class:`OfficeMap`.

    ``source`` names the map in messages and in the result. Raises ``ValueError`` naming the source and
    the offending entry.
    """
    if not isinstance(data, dict):
        raise TypeError(f"data must be a dict (a map's JSON object), got {type(data).__name__}")
    _check_keys(data, ("bounds", "walls", "start", "regions"), MAP_KEYS, "", source)
    if data.get("units", "cm") != "cm":
        raise ValueError(f"map file {source}: units must be 'cm', got {data['units']!r}")
    bounds = _number_list(data["bounds"], 4, "bounds", source)
    if not (bounds[0] < bounds[2] and bounds[1] < bounds[3]):
        raise ValueError(f"map file {source}: bounds must be [xmin, ymin, xmax, ymax] with min < max, got {bounds}")
    segments: list[tuple[float, ...]] = []
    polygons: list[np.ndarray] = []
    if not isinstance(data["walls"], list) or not data["walls"]:
        raise ValueError(f"map file {source}: walls must be a non-empty list of segments, got {data['walls']!r}")
    for i, wall in enumerate(data["walls"]):
        segments.append(_number_list(wall, 4, f"walls[{i}]", source))
    if not isinstance(data.get("obstacles", []), list):
        raise ValueError(f"map file {source}: obstacles must be a list of polygons, got {data['obstacles']!r}")
    for i, poly in enumerate(data.get("obstacles", [])):
        if not isinstance(poly, list) or len(poly) < 3:
            raise ValueError(f"map file {source}: obstacles[{i}] must list at least 3 vertices, got {poly!r}")
        verts = [_number_list(v, 2, f"obstacles[{i}] vertex", source) for v in poly]
        segments += [(*verts[k], *verts[(k + 1) % len(verts)]) for k in range(len(verts))]
        polygons.append(np.array(verts, dtype=np.float64))
    walls = np.array(segments, dtype=np.float64)
    if np.any(np.hypot(walls[:, 2] - walls[:, 0], walls[:, 3] - walls[:, 1]) == 0.0):
        raise ValueError(f"map file {source}: a wall segment has zero length")
    start = _number_list(data["start"], 2, "start", source)
    if not isinstance(data["regions"], dict):
        raise ValueError(f"map file {source}: regions must be an object, got {data['regions']!r}")
    _check_keys(data["regions"], ("goal",), REGION_KEYS, "regions.", source)
    given = [name for name in ROUTE_REGIONS if name in data["regions"]]
    if len(given) == 1:
        other = ROUTE_REGIONS[1 - ROUTE_REGIONS.index(given[0])]
        raise ValueError(
            f"map file {source}: regions.{given[0]} needs regions.{other} (route regions come as a pair), "
            f"regions.{other} is missing"
        )
    regions: dict[str, tuple[float, float, float, float]] = {}
    for name in ("goal", *given):
        rect = _number_list(data["regions"][name], 4, f"regions.{name}", source)
        if not (rect[0] <= rect[2] and rect[1] <= rect[3]):
            raise ValueError(f"map file {source}: regions.{name} must be [xmin, ymin, xmax, ymax], got {rect}")
        if not _overlaps(rect, bounds):
            raise ValueError(f"map file {source}: regions.{name} {list(rect)} lies outside the bounds {list(bounds)}")
        regions[name] = rect  # type: ignore[assignment]
    office = OfficeMap(str(data.get("name", Path(source).stem)), bounds, walls, start, regions, source, tuple(polygons))  # type: ignore[arg-type]
    start_xy = np.array(start)
    inside = office.obstacle_at(start_xy)
    if inside is not None:
        raise ValueError(f"map file {source}: start {start} is inside obstacles[{inside}]; move it onto the floor")
    if not office.inside_bounds(start_xy) or clearance(start_xy[None], walls)[0] <= ROBOT_RADIUS_CM:
        raise ValueError(f"map file {source}: start {start} is outside the map or the robot there touches a wall")
    points = np.prod([np.floor((hi - lo) / STEP_CM) + 1 for lo, hi in ((bounds[0], bounds[2]), (bounds[1], bounds[3]))])
    if points > MAX_LATTICE_POINTS:
        raise ValueError(
            f"map file {source}: bounds {bounds} span {points:.3g} lattice points of {STEP_CM:.0f} cm, "
            f"more than {MAX_LATTICE_POINTS:,} (are the units cm?)"
        )
    return office


def point_segment_distance(points: np.ndarray, walls: np.ndarray) -> np.ndarray:
    """Distances ``(..., m)`` from points ``(..., 2)`` to wall segments ``(m, 4)``."""
    a, d = walls[:, :2], walls[:, 2:] - walls[:, :2]
    rel = points[..., None, :] - a
    t = _nearest_param(rel, d)
    return np.linalg.norm(rel - t[..., None] * d, axis=-1)


def _nearest_param(rel: np.ndarray, d: np.ndarray) -> np.ndarray:
    """``t`` in [0, 1] of the point ``a + t * d`` of each segment nearest to ``a + rel``."""
    return np.clip(np.einsum("...mk,mk->...m", rel, d) / np.einsum("mk,mk->m", d, d), 0.0, 1.0)


def clearance(points: np.ndarray, walls: np.ndarray) -> np.ndarray:
    """Distance ``(...)`` from each point ``(..., 2)`` to the nearest wall."""
    return point_segment_distance(points, walls).min(axis=-1)


def _cross(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


def swept_clearance(p0: np.ndarray, p1: np.ndarray, walls: np.ndarray) -> np.ndarray:
    """Distance ``(n,)`` between each move segment ``p0 -> p1`` (``(n, 2)`` each) and the nearest wall.

    The swept disc of radius R touches a wall exactly when this is ``<= R``.
    """
    a, b = walls[:, :2], walls[:, 2:]
    seg = p1 - p0
    wall = b - a
    # proper or touching intersection of the two segments means distance 0
    d1 = _cross(seg[:, None, :], a - p0[:, None, :])
    d2 = _cross(seg[:, None, :], b - p0[:, None, :])
    d3 = _cross(wall, p0[:, None, :] - a)
    d4 = _cross(wall, p1[:, None, :] - a)
    crossing = (d1 * d2 <= 0) & (d3 * d4 <= 0) & ~((d1 == 0) & (d2 == 0))
    ends = np.minimum(point_segment_distance(p0, walls), point_segment_distance(p1, walls))
    moving = np.hypot(seg[:, 0], seg[:, 1]) > 0
    tips = np.full(ends.shape, np.inf)
    if moving.any():
        move_segs = np.concatenate([p0[moving], p1[moving]], axis=1)
        # distance from each wall end point to each move segment
        tips[moving] = np.minimum(point_segment_distance(a, move_segs).T, point_segment_distance(b, move_segs).T)
    dist = np.minimum(ends, tips)
    return np.where(crossing & moving[:, None], 0.0, dist).min(axis=1)


def _ray_hits(origins: np.ndarray, angles: np.ndarray, walls: np.ndarray) -> np.ndarray:
    """Range ``(..., m)`` along rays (bearing ``angles``, broadcast with origins ``(..., 2)``) to each wall."""
    direction = np.stack([np.sin(angles), np.cos(angles)], axis=-1)[..., None, :]
    a, e = walls[:, :2], walls[:, 2:] - walls[:, :2]
    rel = a - origins[..., None, :]
    denom = _cross(direction, e)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = _cross(rel, e) / denom
        s = _cross(rel, direction) / denom
    hit = (denom != 0) & (t >= 0) & (s >= 0) & (s <= 1)
    return np.where(hit, t, np.inf)


def cone_ranges(origins: np.ndarray, bearings: np.ndarray, half_angle: float, walls: np.ndarray) -> np.ndarray:
    """Exact distance from each origin to the nearest wall point inside a cone.

    ``origins`` ``(..., s, 2)`` are sensor positions, ``bearings`` ``(s,)`` the cone axes in radians
    clockwise from north, ``half_angle`` the cone's half width (0 gives a single ray). The nearest
    point of a segment clipped to a convex cone is a clipped end or the segment's closest point, so
    the minimum over those candidates is exact. Returns ``(..., s)``; ``inf`` where nothing is seen.
    """
    if half_angle == 0.0:
        return _ray_hits(origins, bearings, walls).min(axis=-1)
    best = np.minimum(
        _ray_hits(origins, bearings - half_angle, walls), _ray_hits(origins, bearings + half_angle, walls)
    ).min(axis=-1)
    axis = np.stack([np.sin(bearings), np.cos(bearings)], axis=-1)[..., None, :]
    cos_half = np.cos(half_angle)
    a, d = walls[:, :2], walls[:, 2:] - walls[:, :2]
    rel = origins[..., None, :] - a
    t = _nearest_param(rel, d)
    for point in (a + t[..., None] * d, np.broadcast_to(a, rel.shape), np.broadcast_to(walls[:, 2:], rel.shape)):
        vec = point - origins[..., None, :]
        dist = np.linalg.norm(vec, axis=-1)
        inside = np.einsum("...k,...k->...", vec, axis) >= cos_half * dist - 1e-9
        best = np.minimum(best, np.where(inside, dist, np.inf).min(axis=-1))
    return best


@dataclass(frozen=True)
class Lattice:
    """The free cells of the 10 cm lattice through the start, and the move table between them.

    ``cells`` ``(n, 2)`` are centre positions whose disc clears every wall; ``moves`` ``(n, 4)`` gives,
    for actions N, E, S, W, the next cell index or -1 when the swept disc would touch a wall (or leave
    the map); ``reachable`` marks cells reachable from the start without collision.
    """

    cells: np.ndarray
    moves: np.ndarray
    reachable: np.ndarray
    origin: tuple[float, float]
    shape: tuple[int, int]
    grid: np.ndarray

    def index(self, xy: np.ndarray | tuple[float, float]) -> int:
        """Cell index of a position on the lattice, or -1 when it is off the lattice or not free."""
        gx = (xy[0] - self.origin[0]) / STEP_CM
        gy = (xy[1] - self.origin[1]) / STEP_CM
        ix, iy = round(gx), round(gy)
        if abs(gx - ix) > 1e-9 or abs(gy - iy) > 1e-9 or not (0 <= ix < self.shape[0] and 0 <= iy < self.shape[1]):
            return -1
        return int(self.grid[ix, iy])


DIRECTIONS = ((0, 1), (1, 0), (0, -1), (-1, 0))  # lattice steps of actions N, E, S, W
MOVES_CM = STEP_CM * np.array(DIRECTIONS, dtype=np.float64)


def build_lattice(office: OfficeMap) -> Lattice:
    """Enumerate free lattice cells of ``office`` and their exact move outcomes (swept-disc test)."""
    x0, y0, x1, y1 = office.bounds
    sx, sy = office.start
    xs = sx + STEP_CM * np.arange(np.ceil((x0 - sx) / STEP_CM), np.floor((x1 - sx) / STEP_CM) + 1)
    ys = sy + STEP_CM * np.arange(np.ceil((y0 - sy) / STEP_CM), np.floor((y1 - sy) / STEP_CM) + 1)
    gx, gy = np.meshgrid(xs, ys, indexing="ij")
    points = np.stack([gx.ravel(), gy.ravel()], axis=1)
    free = clearance(points, office.walls) > ROBOT_RADIUS_CM
    cells = points[free]
    grid = np.full(gx.shape, -1, dtype=np.int64)
    grid.ravel()[np.flatnonzero(free)] = np.arange(len(cells))
    origin = (float(xs[0]), float(ys[0]))
    n = len(cells)
    moves = np.full((n, 4), -1, dtype=np.int64)
    ij = np.argwhere(grid >= 0)  # row-major, as the cell indices were assigned: row k is cell k
    for action, (dx, dy) in enumerate(DIRECTIONS):
        ti, tj = ij[:, 0] + dx, ij[:, 1] + dy
        ok = (ti >= 0) & (ti < grid.shape[0]) & (tj >= 0) & (tj < grid.shape[1])
        target = np.full(n, -1)
        target[ok] = grid[ti[ok], tj[ok]]
        has = target >= 0
        clear = swept_clearance(cells[has], cells[target[has]], office.walls) > ROBOT_RADIUS_CM
        moves[np.flatnonzero(has)[clear], action] = target[has][clear]
    start = int(grid[round((sx - origin[0]) / STEP_CM), round((sy - origin[1]) / STEP_CM)])
    return Lattice(cells, moves, reachable_from(moves, start), origin, grid.shape, grid)


def reachable_from(moves: np.ndarray, start: int) -> np.ndarray:
    """Cells ``(n_cells,)`` reachable from cell ``start`` by the move table ``moves`` (next cell or -1)."""
    reached = np.zeros(len(moves), dtype=bool)
    reached[start] = True
    frontier = np.array([start])
    while len(frontier):
        nxt = moves[frontier].ravel()
        nxt = np.unique(nxt[nxt >= 0])
        frontier = nxt[~reached[nxt]]
        reached[frontier] = True
    return reached


def check_goal_reachable(office: OfficeMap, lattice: Lattice) -> None:
    """Raise ``ValueError`` unless a goal cell is reachable from the start on ``lattice``.

    Reachable means by the env's own moves: 10 cm N/E/S/W steps whose swept robot disc clears every
    wall (:func:`build_lattice`). The message says how many free cells the start reaches and where.
    """
    start, goal = _xy(office.start), list(office.regions["goal"])
    in_goal = office.in_region("goal", lattice.cells)
    reached = int(lattice.reachable.sum())
    if not in_goal.any():
        raise ValueError(
            f"map file {office.source}: the goal region {goal} holds no free lattice cell: the robot "
            f"(a {ROBOT_RADIUS_CM:.0f} cm radius disc on the {STEP_CM:.0f} cm lattice through the start {start}) "
            "cannot stand in it; widen it or move its walls"
        )
    if not (in_goal & lattice.reachable).any():
        inside = [office.obstacle_at(xy) for xy in lattice.cells[in_goal]]
        obstacles = sorted({index for index in inside if index is not None})
        if None not in inside:
            raise ValueError(
                f"map file {office.source}: the goal {goal} lies inside obstacles{obstacles} (every free "
                "lattice cell of the goal is inside the polygon, where the robot cannot go); put the goal region on "
                "the floor, e.g. in front of the obstacle"
            )
        raise ValueError(
            f"map file {office.source}: the goal {goal} cannot be reached from the start {start}: "
            f"{reached} of {len(lattice.cells)} free lattice cells are reachable, none in the goal; the goal's "
            f"{int(in_goal.sum())} free cells (e.g. {_xy(lattice.cells[np.argmax(in_goal)])}) are walled off for "
            f"a {ROBOT_RADIUS_CM:.0f} cm radius robot moving {STEP_CM:.0f} cm N/E/S/W; widen the passages (the "
            f"robot's centre stays more than {ROBOT_RADIUS_CM:.0f} cm from every wall, on the {STEP_CM:.0f} cm "
            "lattice through the start)"
        )


def _xy(xy: tuple[float, float] | np.ndarray) -> str:
    return f"({float(xy[0]):g}, {float(xy[1]):g})"
