"""The agent's-eye view: what the model sees, drawn in the terminal.

The training child does not stream observations (they would swamp the pipe), so the view
is rebuilt here from the latest sim-trace row (where the reported car was): the camera
frame at that pose as half-block characters (two grey pixels per cell), or the lidar
ranges as a polar plot with the car at the centre, heading up. The frame is the model's
own camera, DeepRacer's simulated one (`sim.sensors.camera`, docs/camera.md): the dark road and
its white bands, the orange dashes, the green field and the dark walls a model trained
in DeepRacer's simulator learnt from. `observe_at` does the
sensor work and belongs in a thread worker; the widget only draws what it is given.
"""

from __future__ import annotations

import math
import textwrap
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from rich.color import Color
from rich.segment import Segment
from rich.style import Style
from textual.strip import Strip
from textual.widget import Widget

from racer_tui.app.widgets.braille import braille_char, set_dots, styled_runs
from sim.physics.objects.field import ObjectField
from sim.sensors.batched import Camera, Lidar, LidarSpec
from sim.sensors.objects_drawn import object_solids
from sim.tracks.track import Track


@dataclass(frozen=True)
class Observation:
    """One sensor reading: a greyscale camera frame or lidar ranges, and its caption."""

    caption: str
    frame: NDArray[np.uint8] | None = None  # (H, W) greyscale
    ranges: NDArray[np.float32] | None = None  # metres, one per ray
    angles_deg: NDArray[np.float64] | None = None  # ray directions, 0 = ahead, CCW
    max_range: float = 2.0


# Sensors precompute rasters and tables per track: built once per track's content.
_CAMERAS: dict[str, Camera] = {}
_LIDARS: dict[str, Lidar] = {}


def _camera(track: Track) -> Camera:
    key = track.content_hash
    if key not in _CAMERAS:
        _CAMERAS.clear()  # one track at a time is watched; do not hoard rasters
        _CAMERAS[key] = Camera(track)
    return _CAMERAS[key]


def _lidar(track: Track) -> Lidar:
    key = track.content_hash
    if key not in _LIDARS:
        _LIDARS.clear()
        _LIDARS[key] = Lidar(track)
    return _LIDARS[key]


def observe_at(
    track: Track,
    sensors: tuple[str, ...],
    pose: tuple[float, float, float],
    caption: str,
    objects: ObjectField | None = None,
) -> Observation:
    """The model's sensor at a pose (sim-trace yaw is in degrees), seeing `objects` (car
    0's boxes or bots) if given. Lidar models get the lidar; every other model gets the
    camera (a vector model sees numbers, but the camera shows a racer where the car is)."""
    x, y, yaw_deg = pose
    yaw = math.radians(yaw_deg)
    if "lidar" in sensors or "sector_lidar" in sensors:
        lidar = _lidar(track)
        ranges = lidar.scan([x], [y], [yaw])[0]
        if objects is not None:
            seen = objects.ray_distances(
                np.array([0]),
                np.array([x]),
                np.array([y]),
                np.array([yaw]),
                angles=lidar.angles,
                max_range=lidar.spec.max_range,
            )[0]
            ranges = np.minimum(ranges, seen).astype(np.float32)
        spec: LidarSpec = lidar.spec
        return Observation(
            f"lidar · {caption}",
            ranges=ranges,
            angles_deg=np.asarray(spec.angles_deg),
            max_range=spec.max_range,
        )
    solids = None if objects is None else object_solids(objects, np.array([0]))
    frame = _camera(track).render([x], [y], [yaw], solids=solids)[0]
    label = "camera" if "camera" in sensors else "camera (the model sees the vector state)"
    return Observation(f"{label} · {caption}", frame=frame)


def half_block_lines(frame: NDArray[np.uint8], columns: int, rows: int) -> list[Strip]:
    """The frame scaled into columns x rows cells, two pixels per cell (upper half block
    in the top pixel's grey on the bottom pixel's grey), aspect ratio kept."""
    height, width = frame.shape
    # A cell is about twice as tall as wide, so one half-block pixel is square.
    scale = min(columns / width, (rows * 2) / height)
    out_w, out_h = max(1, int(width * scale)), max(2, int(height * scale) // 2 * 2)
    xs = np.minimum((np.arange(out_w) / scale).astype(np.int64), width - 1)
    ys = np.minimum((np.arange(out_h) / scale).astype(np.int64), height - 1)
    small = frame[np.ix_(ys, xs)]
    pad = " " * ((columns - out_w) // 2)
    lines = []
    for row in range(out_h // 2):
        top, bottom = small[2 * row], small[2 * row + 1]
        segments = [Segment(pad)]
        for upper, lower in zip(top.tolist(), bottom.tolist(), strict=True):
            style = Style(
                color=Color.from_rgb(upper, upper, upper),
                bgcolor=Color.from_rgb(lower, lower, lower),
            )
            segments.append(Segment("▀", style))
        lines.append(Strip(Segment.simplify(segments)))
    return lines


def polar_lines(
    ranges: NDArray[np.float32],
    angles_deg: NDArray[np.float64],
    max_range: float,
    size: tuple[int, int],
    style: Style,
) -> list[Strip]:
    """Lidar hits as braille dots around the car (centre), straight ahead is up;
    `size` is (columns, rows)."""
    columns, rows = size
    dots_w, dots_h = columns * 2, rows * 4
    # Braille dots are about twice as tall as wide: scale x by 1 dot, y by 2 dots per unit.
    radius = min((dots_w - 1) / 2, (dots_h - 1))  # in x-dots
    grid = np.zeros((rows, columns), dtype=np.int32)
    hit = ranges < max_range - 1e-6
    angle = np.radians(angles_deg[hit])
    distance = ranges[hit] / max_range * radius
    # 0 degrees = ahead = up; positive angles turn left (counter-clockwise).
    dx = np.round(dots_w / 2 - np.sin(angle) * distance).astype(np.int64)
    dy = np.round(dots_h / 2 - np.cos(angle) * distance / 2).astype(np.int64)
    keep = (dx >= 0) & (dx < dots_w) & (dy >= 0) & (dy < dots_h)
    set_dots(grid, dx[keep], dy[keep])
    centre_row, centre_col = rows // 2, columns // 2
    lines = []
    for row in range(rows):
        cells: list[tuple[str, Style | None]] = []
        for col in range(columns):
            if (row, col) == (centre_row, centre_col):
                cells.append(("▲", Style(bold=True)))
                continue
            bits = int(grid[row, col])
            cells.append((braille_char(bits) if bits else " ", style if bits else None))
        lines.append(Strip(styled_runs(cells)))
    return lines


MAX_CAPTION_LINES = 3


class AgentView(Widget):
    """Draws the latest `Observation`; repaints only when a new one is shown."""

    DEFAULT_CSS = """
    AgentView { height: 1fr; min-height: 6; }
    """

    def __init__(self, *, id: str | None = None) -> None:
        super().__init__(id=id)
        self.observation: Observation | None = None
        self.message = "no observation yet"
        self._lines: list[Strip] | None = None

    def show(self, observation: Observation) -> None:
        self.observation = observation
        self._lines = None
        self.refresh()

    def show_message(self, message: str) -> None:
        self.observation, self.message = None, message
        self._lines = None
        self.refresh()

    def on_resize(self) -> None:
        self._lines = None

    def render_line(self, y: int) -> Strip:
        if self._lines is None:
            self._lines = self._draw()
        return self._lines[y] if y < len(self._lines) else Strip.blank(self.size.width)

    def _draw(self) -> list[Strip]:
        width, height = self.size.width, self.size.height
        dim = Style(dim=True)
        observation = self.observation
        if observation is None:
            return [Strip([Segment(self.message[:width], dim)])]
        # The caption wraps rather than being cut (a vector model's says what it sees).
        wrapped = textwrap.wrap(observation.caption, max(width, 1))[:MAX_CAPTION_LINES]
        captions = [Strip([Segment(line, dim)]) for line in wrapped or [""]]
        body_rows = height - len(captions)
        if body_rows < 1 or width < 4:
            return captions
        if observation.frame is not None:
            return [*captions, *half_block_lines(observation.frame, width, body_rows)]
        if observation.ranges is not None and observation.angles_deg is not None:
            accent = Style(color="cyan")
            body = polar_lines(
                observation.ranges,
                observation.angles_deg,
                observation.max_range,
                (width, body_rows),
                accent,
            )
            return [*captions, *body]
        return captions
