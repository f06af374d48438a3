"""A minimum-time line inside a track's borders.

The line is the centre line's points moved sideways: p_i = b_i + a_i n_i, with each offset
a_i between the borders less the car's half-width and a small margin. Two quadratic costs
of the offsets make a quadratic programme with box bounds (`box_qp`):
- curvature: the squared second differences of the points, sum_i w_i |p_i-1 - 2 p_i +
  p_i+1|^2 (the minimum-curvature line of the DeepRacer community's notebooks, and of
  racing-line QPs such as TUM's);
- length: the squared first differences, sum_i |p_i+1 - p_i|^2 (the shortest line).
Neither alone is the fastest line: where the car is held back by a corner the curvature
is what costs time, on a straight or under braking it is the distance. So the weights are
found by lap time (`optimise_line`):
1. the minimum-curvature line;
2. where it still turns tighter than the car's steering can (a hairpin narrower than the
   car's turning circle allows, on a minimum of squares), more weight there, until no
   point does: a line the car cannot drive is no limit lap;
3. the points whose speed their corner caps keep that weight on curvature and the others
   a small one, a little weight on length is added, and each candidate is kept only if
   its flying lap (`sim.coach.speed_profile`) is faster and the car can drive it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import osqp
from scipy import sparse

from sim.coach.limits import CarLimits
from sim.coach.speed_profile import SpeedProfile, driven_corner_speeds, flying_profile
from sim.foundation.arrays import FloatArray
from sim.physics.car import DEEPRACER_CAR
from sim.physics.reference_driver import loop_curvature
from sim.tracks.track import Track

SPACING = 0.05  # metres between the line's points
# The car's centre keeps half the car's width, and this much more, inside the borders.
EDGE_MARGIN = 0.02
CURVATURE_SPAN = 0.15  # metres each side of a point its curvature is measured over
# Weights tried for the points a corner does not hold back, and for the line's length.
_FREE_WEIGHTS = (0.3, 0.1, 0.03)
_LENGTH_WEIGHTS = (0.0, 0.002, 0.01)
_ROUNDS = 3
_QP_ITERATIONS = 200_000
# A line may turn no tighter than this share of the car's tightest turn (at its slowest).
TURN_MARGIN = 0.95
_FEASIBILITY_ROUNDS = 10


@dataclass(frozen=True)
class RoadFrame:
    """Where a line across the road can be: the centre line resampled, its normals, and
    how far each point may move left (positive) or right."""

    base: FloatArray  # (n, 2)
    normal: FloatArray  # (n, 2) unit, pointing left
    low: FloatArray  # (n,) metres, most to the right
    high: FloatArray  # (n,) most to the left

    def points(self, offsets: FloatArray) -> FloatArray:
        return np.asarray(self.base + offsets[:, None] * self.normal)


def road_frame(track: Track, half_width: float = DEEPRACER_CAR.width / 2.0) -> RoadFrame:
    s, base, normal = track.resampled(SPACING)
    right, left = track.lateral_extents(s)
    keep = half_width + EDGE_MARGIN
    low, high = right + keep, left - keep
    # A road narrower than the car plus its margins: the middle of what there is.
    narrow = low > high
    middle = 0.5 * (low + high)
    return RoadFrame(base, normal, np.where(narrow, middle, low), np.where(narrow, middle, high))


def _difference_rows(frame: RoadFrame, order: int) -> tuple[sparse.csr_matrix, FloatArray]:
    """The x and y rows of the points' first (order 1) or second (order 2) differences
    round the loop, as a sparse matrix on the offsets, and the base points' own."""
    n = len(frame.base)
    index = np.arange(n)
    stencil: tuple[tuple[int, float], ...] = (
        ((0, -1.0), (1, 1.0)) if order == 1 else ((-1, 1.0), (0, -2.0), (1, 1.0))
    )
    rows, cols, values = [], [], []
    constant = np.zeros((n, 2))
    for shift, weight in stencil:
        neighbour = (index + shift) % n
        for axis in (0, 1):
            rows.append(2 * index + axis)
            cols.append(neighbour)
            values.append(weight * frame.normal[neighbour, axis])
        constant += weight * frame.base[neighbour]
    # In curvature's and direction's own units (1/m, unitless), not metres of spacing to
    # the first or second power: the solver's tolerances are absolute.
    scale = SPACING**-order
    matrix = sparse.csr_matrix(
        (scale * np.concatenate(values), (np.concatenate(rows), np.concatenate(cols))),
        shape=(2 * n, n),
    )
    return matrix, scale * constant.reshape(-1)


def box_qp(
    hessian: sparse.csr_matrix,
    gradient: FloatArray,
    low: FloatArray,
    high: FloatArray,
    near: FloatArray | None = None,
) -> FloatArray:
    """argmin of x.H.x / 2 - g.x with low <= x <= high, for a sparse positive (semi)definite
    H, by OSQP (warm-started from `near`, a solution of a similar problem).

    scipy's bounded least squares (`lsq_linear`) meets these second-difference systems'
    conditioning (it grows as n^4) with an iterative inner solver that stops far from the
    optimum, and its exact modes are dense (seconds for a 60 m track); OSQP solves the
    sparse problem to 1e-7 in a fraction of a second. The answer is clipped to the bounds.
    """

    n = len(gradient)
    solver = osqp.OSQP()
    solver.setup(
        P=sparse.triu(hessian).tocsc(),
        q=-np.asarray(gradient, dtype=np.float64),
        A=sparse.identity(n, format="csc"),
        l=low,
        u=high,
        verbose=False,
        eps_abs=1e-7,
        eps_rel=1e-7,
        max_iter=_QP_ITERATIONS,
        polishing=False,  # (its C code prints to stdout when it finds nothing to polish)
    )
    if near is not None:
        solver.warm_start(x=near)
    x = solver.solve(raise_error=False).x  # a failed solve is said by x, handled below
    if x is None or not np.all(np.isfinite(x)):
        x = near if near is not None else np.zeros(n)
    return np.asarray(np.clip(x, low, high))


@dataclass(frozen=True)
class LineProblem:
    """The two costs of a line through one road frame, built once."""

    frame: RoadFrame
    bend: sparse.csr_matrix
    bend_base: FloatArray
    length_hessian: sparse.csr_matrix
    length_gradient: FloatArray

    @classmethod
    def of(cls, frame: RoadFrame) -> LineProblem:
        bend, bend_base = _difference_rows(frame, 2)
        length, length_base = _difference_rows(frame, 1)
        return cls(frame, bend, bend_base, (length.T @ length).tocsr(), -(length.T @ length_base))

    def solve(
        self, weights: FloatArray, length_weight: float, near: FloatArray | None = None
    ) -> FloatArray:
        """The offsets minimising sum_i weights_i |second difference_i|^2 + length_weight
        sum_i |first difference_i|^2 within the frame's bounds."""
        weighted = sparse.diags(np.repeat(weights, 2)) @ self.bend
        hessian = (self.bend.T @ weighted).tocsr()
        gradient = -(weighted.T @ self.bend_base)
        if length_weight > 0.0:
            hessian = (hessian + length_weight * self.length_hessian).tocsr()
            gradient = gradient + length_weight * self.length_gradient
        return box_qp(hessian, gradient, self.frame.low, self.frame.high, near)


@dataclass(frozen=True)
class LineFit:
    """A line through the road and its flying lap under the car's limits."""

    offsets: FloatArray
    points: FloatArray  # (n + 1, 2), closed
    curvature: FloatArray  # (n + 1,)
    profile: SpeedProfile


def fit_of(frame: RoadFrame, offsets: FloatArray, limits: CarLimits) -> LineFit:
    points = frame.points(offsets)
    span = max(1, round(CURVATURE_SPAN / SPACING))
    curvature = loop_curvature(points, span)
    steps = np.hypot(*(np.roll(points, -1, axis=0) - points).T)
    profile = flying_profile(driven_corner_speeds(curvature, steps, limits), steps, limits)
    closed = np.vstack([points, points[:1]])
    return LineFit(offsets, closed, np.append(curvature, curvature[0]), profile)


def _corner_weights(fit: LineFit, limits: CarLimits, free: float) -> FloatArray:
    """Full weight on curvature where the corner caps the speed (and a little round it),
    `free` elsewhere."""
    corner = limits.corner_speed(fit.curvature[:-1])
    capped = fit.profile.speeds[:-1] >= 0.97 * corner
    window = max(1, round(0.5 / SPACING))
    spread = np.convolve(
        np.concatenate([capped[-window:], capped, capped[:window]]).astype(float),
        np.ones(2 * window + 1),
        mode="same",
    )[window:-window]
    return np.where(spread > 0.0, 1.0, free)


def _smoothed(values: FloatArray, metres: float) -> FloatArray:
    """A running mean round the loop over `metres`."""
    window = max(1, round(metres / SPACING))
    padded = np.concatenate([values[-window:], values, values[:window]])
    kernel = np.ones(2 * window + 1) / (2 * window + 1)
    return np.asarray(np.convolve(padded, kernel, mode="same")[window:-window])


def tightest_turn(limits: CarLimits) -> float:
    """The largest curvature a line may ask of the car (1/m): its sharpest steering, at
    its slowest, with a margin."""
    widest = max(level.steering_deg for level in limits.levels)
    return TURN_MARGIN * float(limits.steering_curvature(widest, np.asarray(limits.crawl)))


def _drivable(fit: LineFit, cap: float) -> bool:
    return bool(np.max(np.abs(fit.curvature)) <= cap)


def optimise_line(
    track: Track,
    limits: CarLimits,
    *,
    half_width: float = DEEPRACER_CAR.width / 2.0,
    on_candidate: Callable[[LineFit], None] | None = None,
    frame: RoadFrame | None = None,
) -> LineFit:
    """The fastest line found (module docstring), beginning with the minimum-curvature
    one. `on_candidate` hears every line tried (the benchmark counts them). `frame` is
    where the line may go when it is not the road less `half_width` (`sim.coach.lap_floor`
    widens it by what a car may cut)."""
    frame = frame if frame is not None else road_frame(track, half_width)
    problem = LineProblem.of(frame)
    n = len(frame.base)
    cap = tightest_turn(limits)

    def tried(weights: FloatArray, length_weight: float, near: LineFit | None = None) -> LineFit:
        start = near.offsets if near is not None else None
        fit = fit_of(frame, problem.solve(weights, length_weight, start), limits)
        if on_candidate is not None:
            on_candidate(fit)
        return fit

    # 1-2: the minimum-curvature line, then weight where it turns tighter than the car can.
    base = np.ones(n)
    best = tried(base, 0.0)
    for _ in range(_FEASIBILITY_ROUNDS):
        if _drivable(best, cap):
            break
        over = np.abs(best.curvature[:-1]) > cap
        base = np.maximum(_smoothed(np.where(over, base * 4.0, base), 0.25), 1.0)
        candidate = tried(base, 0.0, best)
        tighter = np.max(np.abs(candidate.curvature)) < np.max(np.abs(best.curvature))
        if _drivable(candidate, cap) or tighter:
            best = candidate
    # 3: by lap time, among lines the car can drive.
    for _ in range(_ROUNDS):
        improved = False
        for free in _FREE_WEIGHTS:
            weights = base * _corner_weights(best, limits, free)
            for length_weight in _LENGTH_WEIGHTS:
                candidate = tried(weights, length_weight, best)
                faster = candidate.profile.lap_seconds < best.profile.lap_seconds - 1e-6
                if faster and (_drivable(candidate, cap) or not _drivable(best, cap)):
                    best, improved = candidate, True
        if not improved:
            break
    return best
