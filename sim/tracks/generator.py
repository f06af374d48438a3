"""Seeded procedural tracks: the same seed always gives the same, valid track.

A shape is a ring of control points around a centre whose radius is a few random low
harmonics of the angle, stretched sideways. Taken in order of increasing angle (so the
loop runs counter-clockwise), they are joined by a periodic spline and scaled to the
wanted length. Shapes whose turns are too tight for the road, or whose road comes close
to itself, are thrown away and the next attempt draws from a fresh stream derived from
the seed; after a bounded number of attempts a plain stadium of the same length is
returned, so a caller always gets a track.
"""

from __future__ import annotations

import math

import numpy as np

from sim.foundation.arrays import FloatArray
from sim.tracks.builder import (
    Arc,
    Straight,
    TrackDesignError,
    build_from_segments,
    centre_line_from_control_points,
    track_from_centre_line,
)
from sim.tracks.track import Track, TrackError

MIN_LENGTH = 12.0
MAX_LENGTH = 40.0
# Narrower than twice the car (0.196 m) leaves a model no room to learn a line.
MIN_WIDTH = 0.4
MAX_WIDTH = 1.5
# Random lengths stay clear of the extremes: short tracks leave no room for shape, long
# ones take minutes per lap for a beginner's model.
_RANDOM_LENGTHS = (14.0, 36.0)
# Generated tracks keep gentler turns than the built-in minimum, so a beginner's model
# meets no corner tighter than a wide hairpin.
_RADIUS_MARGIN = 0.15
_MAX_ATTEMPTS = 64
_CONTROL_POINTS = 24


def generate_track(seed: int, *, width: float = 0.76, target_length: float | None = None) -> Track:
    """A valid counter-clockwise track named `generated-<seed>`, identical for equal arguments."""
    _check_arguments(seed, width, target_length)
    name = f"generated-{seed}"
    for attempt in range(_MAX_ATTEMPTS):
        rng = np.random.default_rng([seed, attempt])
        length = (
            target_length if target_length is not None else float(rng.uniform(*_RANDOM_LENGTHS))
        )
        try:
            return _random_shape(rng, name, width, length, seed)
        except TrackError:
            continue
    return _stadium(name, width, target_length or sum(_RANDOM_LENGTHS) / 2, seed)


def _check_arguments(seed: int, width: float, target_length: float | None) -> None:
    if seed < 0:
        raise TrackDesignError(f"seed {seed} is negative; give a whole number of 0 or more.")
    if not MIN_WIDTH <= width <= MAX_WIDTH:
        raise TrackDesignError(
            f"a width of {width:g} m is not possible; give {MIN_WIDTH:g} to {MAX_WIDTH:g} m "
            "(DeepRacer tracks are 0.76 or 1.07 m)."
        )
    if target_length is not None and not MIN_LENGTH <= target_length <= MAX_LENGTH:
        raise TrackDesignError(
            f"a length of {target_length:g} m is not possible; give {MIN_LENGTH:g} to "
            f"{MAX_LENGTH:g} m."
        )


def _control_points(rng: np.random.Generator) -> FloatArray:
    """Points around the origin in increasing angle, on a stretched, wavy circle.

    The radius is a few low harmonics of the angle rather than independent draws, so the
    outline bends into bays and bulges instead of zig-zagging into unusable kinks.
    """
    angles = np.arange(_CONTROL_POINTS) * (2 * math.pi / _CONTROL_POINTS)
    harmonics = np.arange(2, 5)
    amplitudes = rng.uniform(0.0, 0.3, len(harmonics)) / np.sqrt(harmonics - 1)
    phases = rng.uniform(0.0, 2 * math.pi, len(harmonics))
    waves = amplitudes[:, None] * np.cos(harmonics[:, None] * angles + phases[:, None])
    radii = 1.0 + waves.sum(axis=0)
    # DeepRacer tracks are wider than tall; a random stretch gives that family of shapes.
    stretch = np.array([rng.uniform(1.0, 1.9), 1.0])
    points = np.stack([np.cos(angles), np.sin(angles)], axis=1) * radii[:, None] * stretch
    return np.asarray(points, dtype=np.float64)


def _random_shape(
    rng: np.random.Generator, name: str, width: float, length: float, seed: int
) -> Track:
    unit = _control_points(rng)
    # The spline through scaled points is the scaled spline, so one rescale hits the length.
    scale = length / centre_line_from_control_points(unit).length
    line = centre_line_from_control_points(unit * scale)
    needed = width / 2 + _RADIUS_MARGIN
    if line.min_radius < needed:
        raise TrackDesignError(f"tightest turn {line.min_radius:.2f} m is under {needed:.2f} m")
    return track_from_centre_line(
        line,
        name,
        width=width,
        description=_describe(seed, line.length, width),
    )


def _stadium(name: str, width: float, length: float, seed: int) -> Track:
    radius = 1.0 + width / 2
    straight = (length - 2 * math.pi * radius) / 2
    segments = (Straight(straight), Arc(radius, 180), Straight(straight), Arc(radius, 180))
    return build_from_segments(
        name,
        segments,
        width=width,
        description=_describe(seed, length, width),
    )


def _describe(seed: int, length: float, width: float) -> str:
    return f"Generated from seed {seed}: {length:.1f} m long, {width:g} m wide."
