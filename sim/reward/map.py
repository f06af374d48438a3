"""What a reward function pays, everywhere on a track, before a single step of training.

A grid of cells (`spacing` metres) covers the road and a margin off it. In each cell a car
stands facing along the track (or a fixed heading), at a given speed with the wheels
straight, with progress and steps as if it had driven there from the start line; the
reward function is called with DeepRacer's params for that pose. Cells where it fails are
marked, and the first failure is kept in one sentence with its position.

`compute_map` runs the racer's code, so it runs only in the reward probe's child process
(`sim.reward.probe`), under a time limit per call. Numpy throughout; no Textual.
"""

from __future__ import annotations

import itertools
import math
import struct
import zlib
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from sim.physics.simulation import TrackSimulation
from sim.reward.errors import RewardFunctionError
from sim.reward.function import RewardFunction
from sim.tracks.track import Track

DEFAULT_SPACING = 0.1  # metres
DEFAULT_SPEED = 2.0  # m/s
MARGIN = 0.3  # metres off the road that the map still covers
MAX_CELLS = 200_000


@dataclass(frozen=True)
class MapOptions:
    spacing: float = DEFAULT_SPACING
    speed: float = DEFAULT_SPEED
    heading: float | None = None  # degrees; None: along the track where the car stands


@dataclass(frozen=True)
class RewardMap:
    """Rewards on a grid: `values[row][column]` (row 0 at the lowest y), None off the map
    or where the function failed (`failed` cells)."""

    track: str
    options: MapOptions
    origin: tuple[float, float]  # x, y of cell (0, 0)'s centre
    values: list[list[float | None]]
    failed: list[tuple[int, int]] = field(default_factory=list)  # (row, column)
    first_failure: str | None = None

    @property
    def shown(self) -> list[float]:
        return [value for row in self.values for value in row if value is not None]

    def to_json(self) -> dict[str, Any]:
        shown = self.shown
        return {
            "track": self.track,
            "spacing": self.options.spacing,
            "speed": self.options.speed,
            "heading": "track" if self.options.heading is None else self.options.heading,
            "origin": list(self.origin),
            "rows": len(self.values),
            "columns": len(self.values[0]) if self.values else 0,
            "values": self.values,
            "min": min(shown) if shown else None,
            "max": max(shown) if shown else None,
            "failed": [list(cell) for cell in self.failed],
            "first_failure": self.first_failure,
        }

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> RewardMap:
        heading = data["heading"]
        options = MapOptions(
            float(data["spacing"]),
            float(data["speed"]),
            None if heading == "track" else float(heading),
        )
        values = [[None if v is None else float(v) for v in row] for row in data["values"]]
        failed = [(int(r), int(c)) for r, c in data["failed"]]
        return cls(
            str(data["track"]),
            options,
            (float(data["origin"][0]), float(data["origin"][1])),
            values,
            failed,
            data.get("first_failure"),
        )


def map_grid(track: Track, spacing: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cell centres (x, y arrays of the grid's shape) and which cells the map covers: the
    road and MARGIN metres off it."""
    points = track.points
    xs_all, ys_all = points[:, 0::2], points[:, 1::2]  # centre, inner and outer lines
    low_x, high_x = xs_all.min() - MARGIN, xs_all.max() + MARGIN
    low_y, high_y = ys_all.min() - MARGIN, ys_all.max() + MARGIN
    columns = max(1, math.ceil((high_x - low_x) / spacing))
    rows = max(1, math.ceil((high_y - low_y) / spacing))
    if rows * columns > MAX_CELLS:
        raise ValueError(
            f"a {spacing:g} m grid over {track.name} has {rows * columns:,} cells; "
            f"use a coarser spacing (at most {MAX_CELLS:,} cells)"
        )
    xs, ys = np.meshgrid(
        low_x + spacing * (np.arange(columns) + 0.5), low_y + spacing * (np.arange(rows) + 0.5)
    )
    flat = np.column_stack([xs.ravel(), ys.ravel()])
    _, _, foot = track.centerline.project(flat)
    from_centre = np.hypot(*(flat - foot).T)
    half_width = float(np.hypot(*(points[:, 4:6] - points[:, 2:4]).T).max()) / 2
    covered = (from_centre <= half_width + MARGIN).reshape(rows, columns)
    return xs, ys, covered


def compute_map(reward: RewardFunction, track: Track, options: MapOptions) -> RewardMap:
    """Call `reward` in every covered cell (this runs the racer's code: the probe only)."""
    xs, ys, covered = map_grid(track, options.spacing)
    cell_x, cell_y = xs[covered], ys[covered]
    if options.heading is None:
        segment, _, _ = track.centerline.project(np.column_stack([cell_x, cell_y]))
        vectors = track.centerline.vectors[segment]
        yaw = np.arctan2(vectors[:, 1], vectors[:, 0])
    else:
        yaw = np.full(len(cell_x), math.radians(options.heading))
    sim = TrackSimulation(track, len(cell_x))
    sim.pose_all(cell_x, cell_y, yaw, options.speed, 0.0)
    values = np.full(covered.shape, np.nan)
    failed_mask = np.zeros(covered.shape, dtype=bool)
    first_failure: str | None = None
    flat_values = np.full(len(cell_x), np.nan)
    failed = np.zeros(len(cell_x), dtype=bool)
    for index, params in enumerate(sim.all_params()):
        try:
            flat_values[index] = reward(params)
        except RewardFunctionError as error:
            if "did not return within" in error.reason:
                raise  # a function this slow would take hours over the map
            failed[index] = True
            if first_failure is None:
                first_failure = (
                    f"{error} (first at x={params['x']:.2f}, y={params['y']:.2f}, "
                    f"progress {params['progress']:.1f} %)"
                )
    values[covered] = flat_values
    failed_mask[covered] = failed
    rows = [[None if math.isnan(v) else float(v) for v in row] for row in values.tolist()]
    failed_cells = [(int(r), int(c)) for r, c in np.argwhere(failed_mask)]
    origin = (float(xs[0, 0]), float(ys[0, 0]))
    return RewardMap(track.name, options, origin, rows, failed_cells, first_failure)


# --- drawing -------------------------------------------------------------------------------

# Low to high: dark blue, teal, green, yellow (readable on dark and light terminals).
_STOPS = ((0.0, (35, 40, 110)), (0.35, (30, 130, 150)), (0.7, (90, 190, 80)), (1.0, (250, 225, 60)))
FAILED_COLOUR = (220, 40, 40)
EMPTY_COLOUR = (0, 0, 0)


def colour(fraction: float) -> tuple[int, int, int]:
    """The map's colour for a value `fraction` of the way from its minimum to its maximum."""
    f = min(max(fraction, 0.0), 1.0)
    for (f0, c0), (f1, c1) in itertools.pairwise(_STOPS):
        if f <= f1:
            t = (f - f0) / (f1 - f0)
            return tuple(round(a + (b - a) * t) for a, b in zip(c0, c1, strict=True))  # type: ignore[return-value]
    return _STOPS[-1][1]


def pixel_rows(reward_map: RewardMap) -> list[list[tuple[int, int, int]]]:
    """RGB per cell, top row first (north up)."""
    shown = reward_map.shown
    low, high = (min(shown), max(shown)) if shown else (0.0, 1.0)
    span = high - low or 1.0
    failed = set(reward_map.failed)
    rows: list[list[tuple[int, int, int]]] = []
    for r in range(len(reward_map.values) - 1, -1, -1):
        line = []
        for c, value in enumerate(reward_map.values[r]):
            if (r, c) in failed:
                line.append(FAILED_COLOUR)
            elif value is None:
                line.append(EMPTY_COLOUR)
            else:
                line.append(colour((value - low) / span))
        rows.append(line)
    return rows


BORDER_COLOUR = (170, 170, 170)
CENTRE_COLOUR = (255, 255, 255)
START_COLOUR = (230, 30, 30)


def png_bytes(reward_map: RewardMap, scale: int = 4, track: Track | None = None) -> bytes:
    """The map as a PNG image, `scale` pixels per cell; with `track`, its borders, centre
    line and start line drawn over the colours, one pixel wide."""
    rows = pixel_rows(reward_map)
    height, width = len(rows) * scale, (len(rows[0]) if rows else 0) * scale
    image = np.zeros((height, width, 3), dtype=np.uint8)
    for r, row in enumerate(rows):
        image[r * scale : (r + 1) * scale] = np.repeat(np.array(row, dtype=np.uint8), scale, axis=0)
    if track is not None:
        for line, rgb in (
            (track.inner, BORDER_COLOUR),
            (track.outer, BORDER_COLOUR),
            (track.center, CENTRE_COLOUR),
            (start_line(track), START_COLOUR),
        ):
            _draw(image, reward_map, scale, line, rgb)
    raw = b"".join(b"\x00" + image[y].tobytes() for y in range(height))  # filter 0 per line

    def chunk(kind: bytes, data: bytes) -> bytes:
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)  # 8-bit RGB
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", header)
        + chunk(b"IDAT", zlib.compress(raw, 9))
        + chunk(b"IEND", b"")
    )


def start_line(track: Track) -> np.ndarray:
    """The start line's two ends, across the road at the track's first point."""
    return track.points[0, 2:6].reshape(2, 2)


def polyline_samples(line: np.ndarray, apart: float) -> np.ndarray:
    """Points along a polyline in metres, at most `apart` metres from one to the next, so
    every cell of that size the line crosses gets one."""
    points = np.asarray(line, dtype=float)
    lengths = np.hypot(*np.diff(points, axis=0).T)
    return np.vstack(
        [
            np.linspace(start, end, max(2, int(np.ceil(length / apart)) + 1))
            for start, end, length in zip(points[:-1], points[1:], lengths, strict=True)
        ]
    )


def _draw(
    image: np.ndarray,
    reward_map: RewardMap,
    scale: int,
    line: np.ndarray,
    rgb: tuple[int, int, int],
) -> None:
    """A polyline in metres onto the image, sampled finer than a pixel."""
    spacing = reward_map.options.spacing
    origin_x, origin_y = reward_map.origin
    rows = len(reward_map.values)
    xy = polyline_samples(line, spacing / scale)
    column = np.floor(((xy[:, 0] - origin_x) / spacing + 0.5) * scale).astype(int)
    row = np.floor((rows - 0.5 - (xy[:, 1] - origin_y) / spacing) * scale).astype(int)
    inside = (row >= 0) & (row < image.shape[0]) & (column >= 0) & (column < image.shape[1])
    image[row[inside], column[inside]] = rgb
