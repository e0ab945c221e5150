"""Seeded generated offices: rooms, doors, corridors, furniture, a start and a goal desk area.

:func:`generate_map` returns a map as the JSON object of the map format (``docs/own_office.md``), made
deterministically from ``(seed, size)``: the floor is split recursively into rooms (for the larger sizes
on both sides of a corridor), each split wall gets a door, furniture stands against the walls away from
the doors, the start is in a corner room and the goal the floor in front of a desk (or a corner, where no
desk fits) in a room chosen to fit the size class.
The size class is the lattice shortest path (:func:`shortest_path_moves`), see :data:`SIZES`; a layout
that misses its class, or whose goal or a room the robot cannot reach, is redrawn from a derived seed.
Every coordinate is a multiple of 10 cm, so the robot's lattice is the 10 cm grid through the origin.

Envs take a generated office as ``map="generated:SEED"`` (size M) or ``map="generated:SIZE:SEED"``.

Seeds: 0-99 are the development seeds, the only ones to look at (print, plot, debug) or to tune this
generator on. Seeds >= 1000 are held out for studies: do not inspect them or tune on them (automatic
tests over seeds 0-999 are fine).
"""

from __future__ import annotations

import heapq
from dataclasses import dataclass, field

import numpy as np

from twodrl_envs.nomad.geometry import (
    GENERATED_PREFIX,
    Lattice,
    OfficeMap,
    build_lattice,
    check_goal_reachable,
    parse_map,
)

SIZES: dict[str, tuple[int, int]] = {"S": (10, 30), "M": (31, 80), "L": (81, 200)}
"""Size class -> (fewest, most) moves of the lattice shortest path from the start to the goal (S from 10: no
office is trivially short)."""
MAX_SIDE_CM = 1050
"""No generated office is wider or taller than this (cm)."""
MAX_ATTEMPTS = 100
"""Layouts drawn for one ``(seed, size)`` before :func:`generate_map` gives up."""

GRID_CM = 10
MIN_ROOM_CM = 120  # narrowest room: a 60 cm wide band of free centres
DOOR_WIDTHS_CM = (80, 90, 100)  # >= 80: a lattice row passes more than 30 cm from both jambs
CORRIDOR_WIDTHS_CM = (120, 130, 140, 150)
JAMB_MARGIN_CM = 20  # no wall meets a wall within this distance of a door
DOOR_ZONE_DEPTH_CM = 110  # kept clear of furniture in front of each door
DOOR_ZONE_SIDE_CM = 30  # ... and this far past each jamb
FREE_BAND_CM = 110  # furniture on opposite walls of a room leaves this much between them
DESK_DEPTH_CM = 50
GOAL_DEPTH_CM = 100  # the goal region reaches this far past the desk into the room
DESK_ROOM_CM = 150  # a room this deep (or deeper) from the desk's wall has room for a desk and the robot

Rect = tuple[int, int, int, int]


@dataclass(frozen=True)
class _Layout:
    """Ranges each size class draws from: floor width and height (cm), largest room side, corridor chance."""

    width: tuple[int, int]
    height: tuple[int, int]
    max_room: int
    corridor: float
    target: tuple[int, int]  # range of the estimated shortest path (moves) the goal room is chosen for


_LAYOUTS = {
    "S": _Layout((240, 400), (200, 340), 240, 0.0, (14, 24)),
    "M": _Layout((420, 620), (360, 560), 300, 0.5, (40, 70)),
    "L": _Layout((800, MAX_SIDE_CM), (700, MAX_SIDE_CM), 350, 0.8, (100, 170)),
}


def _grid(rng: np.random.Generator, lo: int, hi: int) -> int:
    """A random multiple of the grid in ``[lo, hi]`` (``lo <= hi``, ``lo`` a multiple)."""
    return lo + GRID_CM * int(rng.integers(0, (hi - lo) // GRID_CM + 1))


@dataclass(frozen=True)
class _Door:
    """A door in the wall line ``x = coord`` (``vertical``) or ``y = coord``, spanning ``lo`` to ``hi``."""

    vertical: bool
    coord: int
    lo: int
    hi: int

    @property
    def centre(self) -> tuple[float, float]:
        mid = (self.lo + self.hi) / 2
        return (self.coord, mid) if self.vertical else (mid, self.coord)


@dataclass
class _Plan:
    """A floor plan under construction: wall lines (with their doors), rooms, corridors, furniture."""

    rng: np.random.Generator
    width: int
    height: int
    lines: list[tuple[bool, int, int, int]] = field(default_factory=list)
    doors: list[_Door] = field(default_factory=list)
    rooms: list[Rect] = field(default_factory=list)
    corridors: list[Rect] = field(default_factory=list)
    furniture: list[Rect] = field(default_factory=list)
    desk: bool = False

    def grid(self, lo: int, hi: int) -> int:
        """A random multiple of the grid in ``[lo, hi]``."""
        return _grid(self.rng, lo, hi)

    def add_wall(self, vertical: bool, coord: int, lo: int, hi: int, door: bool) -> None:
        """A wall line from ``lo`` to ``hi``, with one door of random width and place if ``door``."""
        self.lines.append((vertical, coord, lo, hi))
        if door:
            self.add_door(vertical, coord, lo, hi)

    def add_door(self, vertical: bool, coord: int, lo: int, hi: int) -> None:
        """A door in the stretch ``lo``-``hi`` of an existing wall line, ``GRID_CM`` from either end."""
        width = int(self.rng.choice([w for w in DOOR_WIDTHS_CM if w <= hi - lo - 2 * GRID_CM]))
        start = self.grid(lo + GRID_CM, hi - GRID_CM - width)
        self.doors.append(_Door(vertical, coord, start, start + width))

    def blocks_door(self, vertical: bool, coord: int, rect: Rect) -> bool:
        """Whether a new wall ``x = coord`` (``vertical``) or ``y = coord`` across ``rect`` ends in a door."""
        ends = (rect[1], rect[3]) if vertical else (rect[0], rect[2])
        return any(
            d.vertical != vertical and d.coord in ends and d.lo - JAMB_MARGIN_CM < coord < d.hi + JAMB_MARGIN_CM
            for d in self.doors
        )


def parse_generated(source: str) -> tuple[str, int]:
    """``(size, seed)`` of a map source ``generated:SEED`` (size M) or ``generated:SIZE:SEED``."""
    if not isinstance(source, str) or not source.startswith(GENERATED_PREFIX):
        raise ValueError(f"map must start with {GENERATED_PREFIX!r} to name a generated office, got {source!r}")
    parts = source[len(GENERATED_PREFIX) :].split(":")
    size, seed = ("M", parts[0]) if len(parts) == 1 else (parts[0], parts[-1])
    if len(parts) > 2 or size not in SIZES or not (seed.isascii() and seed.isdigit()):
        raise ValueError(
            f"map {source!r}: a generated office is 'generated:SEED' or 'generated:SIZE:SEED' with SIZE one of "
            f"{', '.join(SIZES)} and SEED an integer >= 0 (e.g. 'generated:L:12')"
        )
    return size, int(seed)


def generated_source(seed: int, size: str) -> str:
    """The map source naming the office :func:`generate_map` makes from ``(seed, size)``."""
    return f"{GENERATED_PREFIX}{size}:{seed}"


def shortest_path_moves(office: OfficeMap, lattice: Lattice) -> int:
    """Fewest 10 cm moves from the start cell to the nearest goal cell on ``lattice`` (breadth-first search).

    Raises ``ValueError`` when no goal cell is reachable (see
    :func:`~twodrl_envs.nomad.geometry.check_goal_reachable` for a message that says why).
    """
    if not isinstance(office, OfficeMap):
        raise TypeError(f"office must be an OfficeMap, got {type(office).__name__}")
    if not isinstance(lattice, Lattice):
        raise TypeError(f"lattice must be a Lattice, got {type(lattice).__name__}")
    goal = office.in_region("goal", lattice.cells)
    seen = np.zeros(len(lattice.cells), dtype=bool)
    frontier = np.array([lattice.index(office.start)])
    seen[frontier] = True
    moves = 0
    while frontier.size:
        if goal[frontier].any():
            return moves
        nxt = lattice.moves[frontier].ravel()
        nxt = np.unique(nxt[nxt >= 0])
        frontier = nxt[~seen[nxt]]
        seen[frontier] = True
        moves += 1
    raise ValueError(f"map {office.source}: no goal cell is reachable from the start {office.start}")


def generate_map(seed: int, size: str = "M") -> dict:
    """A generated office as a map's JSON object, the same for the same ``(seed, size)``.

    ``size`` is the class of its lattice shortest path (:data:`SIZES`): ``"S"`` (<= 30 moves), ``"M"``
    (31-80) or ``"L"`` (81-200); the floor is at most :data:`MAX_SIDE_CM` on a side. The map passes every
    check an env makes on load. Raises ``RuntimeError`` if :data:`MAX_ATTEMPTS` layouts all miss.
    """
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer):
        raise TypeError(f"seed must be an int, got {type(seed).__name__}: {seed!r}")
    if seed < 0:
        raise ValueError(f"seed must be >= 0, got {seed!r}")
    if not isinstance(size, str):
        raise TypeError(f"size must be a str, one of {', '.join(SIZES)}, got {type(size).__name__}: {size!r}")
    if size not in SIZES:
        raise ValueError(f"size must be one of {', '.join(SIZES)}, got {size!r}")
    seed = int(seed)
    source = generated_source(seed, size)
    low, high = SIZES[size]
    for attempt in range(MAX_ATTEMPTS):
        rng = np.random.default_rng([seed, list(SIZES).index(size), attempt])
        plan, data = _draw(rng, _LAYOUTS[size])
        office = parse_map(data, source)
        lattice = build_lattice(office)
        try:
            check_goal_reachable(office, lattice)
        except ValueError:
            continue
        moves = shortest_path_moves(office, lattice)
        if low <= moves <= high and _rooms_reachable(plan, lattice):
            data["name"] = f"generated-{size}-{seed}"
            data["description"] = _describe(plan, seed, size, moves, attempt)
            return data
    raise RuntimeError(f"generate_map({seed}, {size!r}): no layout of {MAX_ATTEMPTS} landed in class {size}")


def _draw(rng: np.random.Generator, layout: _Layout) -> tuple[_Plan, dict]:
    """One random layout: the plan and its map object (name and description still to come)."""
    plan = _Plan(rng, _grid(rng, *layout.width), _grid(rng, *layout.height))
    floor = (0, 0, plan.width, plan.height)
    for vertical, coord, length in ((False, 0, plan.width), (False, plan.height, plan.width)):
        plan.add_wall(vertical, coord, 0, length, door=False)
    for vertical, coord, length in ((True, 0, plan.height), (True, plan.width, plan.height)):
        plan.add_wall(vertical, coord, 0, length, door=False)
    if rng.random() < layout.corridor:
        _corridor_floor(plan, floor, layout)
    else:
        _split(plan, floor, layout, force=True)
    start_room = _corner_room(plan)
    start = _start_point(plan, start_room)
    desk, goal = _place_goal(plan, start_room, start, int(rng.integers(layout.target[0], layout.target[1] + 1)))
    keep_clear = [goal, _around(start, 70), *_door_zones(plan)]
    if desk is not None:
        plan.furniture.append(desk)
        plan.desk = True
    for room in plan.rooms:
        _furnish(plan, room, keep_clear)
    data = {
        "name": "",
        "description": "",
        "units": "cm",
        "bounds": [0, 0, plan.width, plan.height],
        "walls": _wall_segments(plan),
        "obstacles": [[[x0, y0], [x1, y0], [x1, y1], [x0, y1]] for x0, y0, x1, y1 in plan.furniture],
        "start": list(start),
        "regions": {"goal": list(goal)},
    }
    return plan, data


def _corridor_floor(plan: _Plan, floor: Rect, layout: _Layout) -> None:
    """A corridor across the whole floor, rooms on both sides, each side with at least one door onto it."""
    vertical = bool(plan.rng.integers(2))
    span = plan.width if vertical else plan.height
    width = int(plan.rng.choice(CORRIDOR_WIDTHS_CM))
    if span - width < 2 * MIN_ROOM_CM:
        _split(plan, floor, layout, force=True)
        return
    lo = plan.grid(MIN_ROOM_CM, span - MIN_ROOM_CM - width)
    hi = lo + width
    length = plan.height if vertical else plan.width
    plan.add_wall(vertical, lo, 0, length, door=False)
    plan.add_wall(vertical, hi, 0, length, door=False)
    corridor = (lo, 0, hi, length) if vertical else (0, lo, length, hi)
    plan.corridors.append(corridor)
    sides = ((0, 0, lo, length), (hi, 0, span, length)) if vertical else ((0, 0, length, lo), (0, hi, length, span))
    for side, line in zip(sides, (lo, hi), strict=True):
        first = len(plan.rooms)
        _split(plan, side, layout, force=False)
        along = [r for r in plan.rooms[first:] if line in ((r[0], r[2]) if vertical else (r[1], r[3]))]
        opened = [r for r in along if plan.rng.random() < 0.6] or [along[int(plan.rng.integers(len(along)))]]
        for room in opened:
            lo_, hi_ = (room[1], room[3]) if vertical else (room[0], room[2])
            plan.add_door(vertical, line, lo_, hi_)


def _split(plan: _Plan, rect: Rect, layout: _Layout, force: bool) -> None:
    """Split ``rect`` by a wall with a door, recursively, into rooms (``force``: at least once)."""
    x0, y0, x1, y1 = rect
    options = []
    for vertical, lo, hi in ((True, x0, x1), (False, y0, y1)):
        cuts = [
            c for c in range(lo + MIN_ROOM_CM, hi - MIN_ROOM_CM + 1, GRID_CM) if not plan.blocks_door(vertical, c, rect)
        ]
        if cuts:
            options.append((hi - lo, vertical, cuts))
    too_big = max(x1 - x0, y1 - y0) > layout.max_room
    if not options or not (force or too_big or plan.rng.random() < 0.3):
        plan.rooms.append(rect)
        return
    longest = max(options)[0]
    _, vertical, cuts = options[int(plan.rng.integers(len(options)))] if longest <= layout.max_room else max(options)
    cut = int(plan.rng.choice(cuts))
    if vertical:
        plan.add_wall(True, cut, y0, y1, door=True)
        halves = ((x0, y0, cut, y1), (cut, y0, x1, y1))
    else:
        plan.add_wall(False, cut, x0, x1, door=True)
        halves = ((x0, y0, x1, cut), (x0, cut, x1, y1))
    for half in halves:
        _split(plan, half, layout, force=False)


def _corner_room(plan: _Plan) -> Rect:
    """The room in a random corner of the floor."""
    x = GRID_CM if plan.rng.integers(2) else plan.width - GRID_CM
    y = GRID_CM if plan.rng.integers(2) else plan.height - GRID_CM
    return next(r for r in plan.rooms if r[0] <= x <= r[2] and r[1] <= y <= r[3])


def _start_point(plan: _Plan, room: Rect) -> tuple[int, int]:
    """A grid point at least 50 cm inside ``room``."""
    x0, y0, x1, y1 = room
    return plan.grid(x0 + 50, x1 - 50), plan.grid(y0 + 50, y1 - 50)


def _on_boundary(door: _Door, room: Rect) -> bool:
    x0, y0, x1, y1 = room
    if door.vertical:
        return door.coord in (x0, x1) and y0 <= door.lo and door.hi <= y1
    return door.coord in (y0, y1) and x0 <= door.lo and door.hi <= x1


def _manhattan(a: tuple[float, float], b: tuple[float, float]) -> float:
    return abs(a[0] - b[0]) + abs(a[1] - b[1])


def _door_distances(plan: _Plan, start_room: Rect, start: tuple[int, int]) -> list[float]:
    """Estimated path length (cm) from ``start`` to each door: door to door, Manhattan within a room."""
    spaces = plan.rooms + plan.corridors
    doors = plan.doors
    dist = [np.inf] * len(doors)
    queue = [(_manhattan(start, d.centre), i) for i, d in enumerate(doors) if _on_boundary(d, start_room)]
    heapq.heapify(queue)
    while queue:
        here, i = heapq.heappop(queue)
        if here >= dist[i]:
            continue
        dist[i] = here
        for space in (s for s in spaces if _on_boundary(doors[i], s)):
            for j, other in enumerate(doors):
                if j != i and _on_boundary(other, space):
                    heapq.heappush(queue, (here + _manhattan(doors[i].centre, other.centre), j))
    return dist


def _place_goal(plan: _Plan, start_room: Rect, start: tuple[int, int], target: int) -> tuple[Rect | None, Rect]:
    """The desk (or None) and goal region of the room whose estimated shortest path is nearest ``target`` moves.

    Every room but the start room gets a goal (:func:`_goal_desk`) behind its nearest door (its entry);
    the estimate is the door-to-door distance to the entry plus the entry's distance to the goal region.
    """
    dist = _door_distances(plan, start_room, start)
    best: tuple[float, Rect | None, Rect] | None = None
    for room in plan.rooms:
        doors = [i for i, d in enumerate(plan.doors) if _on_boundary(d, room)]
        if room == start_room or not doors:
            continue
        entry = min(doors, key=lambda i: dist[i])
        desk, goal = _goal_desk(plan, room, plan.doors[entry], start)
        x, y = plan.doors[entry].centre
        nearest = (min(max(x, goal[0]), goal[2]), min(max(y, goal[1]), goal[3]))
        miss = abs((dist[entry] + _manhattan((x, y), nearest)) / GRID_CM - target)
        if best is None or miss < best[0]:
            best = (miss, desk, goal)
    assert best is not None  # every floor is split at least once
    return best[1], best[2]


def _goal_desk(plan: _Plan, room: Rect, entry: _Door, start: tuple[int, int]) -> tuple[Rect | None, Rect]:
    """A desk against the wall of ``room`` farthest from its entry, and the goal region: the desk and the
    floor in front of it. Where no desk fits (a small room, doors in the way), the goal is a corner area."""
    x0, y0, x1, y1 = room
    ex, ey = entry.centre
    sides = sorted(range(4), key=lambda s: -abs((ey - y0, x1 - ex, y1 - ey, ex - x0)[s]))
    zones = [*_door_zones(plan), _around(start, 70)]
    for side in sides[:2]:
        along = (x1 - x0) if side in (0, 2) else (y1 - y0)
        depth = (y1 - y0) if side in (0, 2) else (x1 - x0)
        if depth < DESK_ROOM_CM or along < 100:
            continue
        length = plan.grid(100, min(160, along))
        desk = _against_wall(plan, room, side, length, DESK_DEPTH_CM, zones)
        if desk is not None:
            reach = min(DESK_DEPTH_CM + GOAL_DEPTH_CM, depth)
            return desk, _against(room, side, _offset(room, side, desk), length, reach)
    corner_x = x0 if abs(ex - x0) > abs(ex - x1) else x1 - 100
    corner_y = y0 if abs(ey - y0) > abs(ey - y1) else y1 - 100
    return None, (corner_x, corner_y, corner_x + 100, corner_y + 100)


def _door_zones(plan: _Plan) -> list[Rect]:
    """The floor in front of every door, on both sides, kept free of furniture."""
    zones = []
    for d in plan.doors:
        lo, hi = d.lo - DOOR_ZONE_SIDE_CM, d.hi + DOOR_ZONE_SIDE_CM
        a, b = d.coord - DOOR_ZONE_DEPTH_CM, d.coord + DOOR_ZONE_DEPTH_CM
        zones.append((a, lo, b, hi) if d.vertical else (lo, a, hi, b))
    return zones


def _around(point: tuple[int, int], radius: int) -> Rect:
    return point[0] - radius, point[1] - radius, point[0] + radius, point[1] + radius


def _overlap(a: Rect, b: Rect) -> bool:
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


def _against(room: Rect, side: int, offset: int, length: int, depth: int) -> Rect:
    """The rectangle ``length`` along wall ``side`` (0 south, 1 east, 2 north, 3 west) of ``room`` from
    ``offset`` on, reaching ``depth`` into the room."""
    x0, y0, x1, y1 = room
    if side == 0:
        return (offset, y0, offset + length, y0 + depth)
    if side == 2:
        return (offset, y1 - depth, offset + length, y1)
    if side == 3:
        return (x0, offset, x0 + depth, offset + length)
    return (x1 - depth, offset, x1, offset + length)


def _offset(room: Rect, side: int, rect: Rect) -> int:
    return rect[0] if side in (0, 2) else rect[1]


def _against_wall(plan: _Plan, room: Rect, side: int, length: int, depth: int, keep_clear: list[Rect]) -> Rect | None:
    """A random rectangle against wall ``side`` of ``room`` clear of ``keep_clear`` and furniture, or None."""
    lo, hi = (room[0], room[2]) if side in (0, 2) else (room[1], room[3])
    fits = [
        rect
        for offset in range(lo, hi - length + 1, GRID_CM)
        if not any(_overlap(rect := _against(room, side, offset, length, depth), k) for k in keep_clear)
        and not any(_overlap(rect, f) for f in plan.furniture)
    ]
    return fits[int(plan.rng.integers(len(fits)))] if fits else None


def _furnish(plan: _Plan, room: Rect, keep_clear: list[Rect]) -> None:
    """Up to three pieces against the walls of ``room``, leaving a free band between opposite walls."""
    x0, y0, x1, y1 = room
    used = [0, 0, 0, 0]  # deepest piece against each wall
    for _ in range(int(plan.rng.integers(0, 4))):
        side = int(plan.rng.integers(4))
        along, across = ((x1 - x0), (y1 - y0)) if side in (0, 2) else ((y1 - y0), (x1 - x0))
        room_for = min(70, across - FREE_BAND_CM - used[(side + 2) % 4])
        if room_for < 40 or along < 80:
            continue
        depth = plan.grid(40, room_for - room_for % GRID_CM)
        piece = _against_wall(plan, room, side, plan.grid(60, min(160, along - 20)), depth, keep_clear)
        if piece is not None:
            plan.furniture.append(piece)
            used[side] = max(used[side], depth)


def _wall_segments(plan: _Plan) -> list[list[int]]:
    """Every wall line cut at its doors, as ``[x0, y0, x1, y1]`` segments."""
    segments = []
    for vertical, coord, lo, hi in plan.lines:
        cuts = sorted((d.lo, d.hi) for d in plan.doors if d.vertical == vertical and d.coord == coord and lo <= d.lo)
        cuts = [(a, b) for a, b in cuts if b <= hi]
        ends = [lo, *(v for cut in cuts for v in cut), hi]
        for a, b in zip(ends[::2], ends[1::2], strict=True):
            segments.append([coord, a, coord, b] if vertical else [a, coord, b, coord])
    return segments


def _rooms_reachable(plan: _Plan, lattice: Lattice) -> bool:
    """Whether the robot can reach a cell inside every room and corridor."""
    cells = lattice.cells[lattice.reachable]
    return all(
        np.any((cells[:, 0] > x0) & (cells[:, 0] < x1) & (cells[:, 1] > y0) & (cells[:, 1] < y1))
        for x0, y0, x1, y1 in plan.rooms + plan.corridors
    )


def _describe(plan: _Plan, seed: int, size: str, moves: int, attempt: int) -> str:
    low, high = SIZES[size]
    corridor = ", a corridor" if plan.corridors else ""
    goal = "the floor in front of a desk" if plan.desk else "a corner"
    return (
        f"Generated office (twodrl_envs.nomad.generator.generate_map({seed}, {size!r}), layout {attempt + 1}): "
        f"{len(plan.rooms)} rooms{corridor}, {len(plan.doors)} doors, {len(plan.furniture)} furniture obstacles; "
        f"start in a corner room, goal {goal} in a far room, shortest path {moves} moves (class {size}: "
        f"{low}-{high}). All lengths in cm, x east, y north; walls are [x0, y0, x1, y1] segments, obstacles "
        "closed polygons, regions [xmin, ymin, xmax, ymax] rectangles tested on the robot's centre."
    )
