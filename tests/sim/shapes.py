"""Simple hand-checkable tracks for tests."""

from __future__ import annotations

import numpy as np

from sim.tracks.track import Track

HALF = 0.38  # half of a 0.76 m road


def rectangle_track(width: float = 6.0, height: float = 4.0, spacing: float = 0.5) -> Track:
    """Centre line: the rectangle (0,0)-(width,height), counter-clockwise, waypoints every
    `spacing` m; borders 0.38 m either side (inner inside the rectangle)."""
    centre: list[tuple[float, float]] = []
    for x in np.arange(0.0, width, spacing):
        centre.append((x, 0.0))
    for y in np.arange(0.0, height, spacing):
        centre.append((width, y))
    for x in np.arange(width, 0.0, -spacing):
        centre.append((x, height))
    for y in np.arange(height, 0.0, -spacing):
        centre.append((0.0, y))
    centre.append(centre[0])
    rows = []
    for x, y in centre:
        # Inner border: the rectangle shrunk by HALF; outer: grown by HALF.
        ix, iy = np.clip(x, HALF, width - HALF), np.clip(y, HALF, height - HALF)
        ox = x if 0.0 < x < width else (-HALF if x == 0.0 else width + HALF)
        oy = y if 0.0 < y < height else (-HALF if y == 0.0 else height + HALF)
        rows.append([x, y, ix, iy, ox, oy])
    return Track.from_array(np.array(rows, dtype=np.float64), "rectangle")


def ring_track(radius: float = 2.0, half_width: float = HALF, points: int = 120) -> Track:
    angles = np.linspace(0.0, 2.0 * np.pi, points + 1)
    angles[-1] = 0.0
    unit = np.stack([np.cos(angles), np.sin(angles)], axis=1)
    rows = np.hstack([unit * radius, unit * (radius - half_width), unit * (radius + half_width)])
    return Track.from_array(rows + 3.0, "ring")
