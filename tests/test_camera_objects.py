"""The front camera sees solid objects on the track: DeepRacer's boxes and head-to-bot's bot
cars, drawn as upright boxes standing on the road in front of the walls."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sim.sensors import camera_scene as scene
from sim.sensors.camera import Camera, CameraSpec, Solids
from sim.tracks.catalog import resolve_track
from sim.tracks.track import Track

# DeepRacer's box obstacle and car body, in metres: length, width, height.
BOX = (0.4, 0.3, 0.25)
BOT_CAR = (0.3235, 0.1961, 0.16)
Pose = tuple[float, float, float]


@pytest.fixture(scope="module")
def reinvent() -> Track:
    return resolve_track("reinvent_base")


@pytest.fixture(scope="module")
def camera(reinvent: Track) -> Camera:
    return Camera(reinvent)


def start_pose(track: Track) -> Pose:
    """The first waypoint, heading for the second: where DeepRacer starts a car, on
    re:Invent 2018's long bottom straight."""
    (x0, y0), (x1, y1) = track.center[0], track.center[1]
    return float(x0), float(y0), math.atan2(y1 - y0, x1 - x0)


def ahead_of(pose: Pose, ahead: float, left: float = 0.0, turn: float = 0.0) -> Pose:
    """A place `ahead` metres in front of the car's centre and `left` to its left, facing
    the car's way turned by `turn` radians."""
    x, y, yaw = pose
    c, s = math.cos(yaw), math.sin(yaw)
    return x + ahead * c - left * s, y + ahead * s + left * c, yaw + turn


def solids(
    *places: Pose,
    size: tuple[float, float, float] = BOX,
    side: int = scene.BOX_SIDE,
    top: int = scene.BOX_TOP,
    sides: list[int] | None = None,
) -> Solids:
    """One car's objects, at `places`, all of one size; tones `side` and `top`, or a side
    tone each from `sides`."""
    k = len(places)
    x, y, heading = (np.array([[p[i] for p in places]]) for i in range(3))
    return Solids(
        x=x,
        y=y,
        heading=heading,
        length=np.full(k, size[0]),
        width=np.full(k, size[1]),
        height=np.full(k, size[2]),
        side_tone=np.array(sides if sides is not None else [side] * k, dtype=np.uint8),
        top_tone=np.full(k, top, dtype=np.uint8),
    )


def frame(camera: Camera, pose: Pose, objects: Solids | None = None) -> np.ndarray:
    return camera.render(*pose, solids=objects)[0]


def block(pixels: np.ndarray) -> tuple[int, int, int, int]:
    """Rows and columns spanned by the True pixels: top, bottom, left, right (inclusive)."""
    rows, columns = np.nonzero(pixels)
    return int(rows.min()), int(rows.max()), int(columns.min()), int(columns.max())


def test_a_box_ahead_shows_as_a_solid_block_of_box_tone_in_the_middle(
    camera: Camera, reinvent: Track
) -> None:
    pose = start_pose(reinvent)
    plain = frame(camera, pose)
    seen = frame(camera, pose, solids(ahead_of(pose, 1.0)))
    # Nothing in the empty scene has the box's grey: the box cannot blend in.
    assert not np.any(plain == scene.BOX_SIDE)
    box = seen == scene.BOX_SIDE
    assert np.array_equal(box, seen != plain)  # all that changed is box
    top, bottom, left, right = block(box)
    # A solid block, centred across the frame, standing on the road below the horizon
    # and rising above it (the box is taller than the camera is high).
    assert box[top : bottom + 1, left : right + 1].mean() > 0.9
    assert abs((left + right + 1) / 2 - 80) <= 2
    assert camera.horizon_row < bottom < 90
    assert top < camera.horizon_row
    # 0.3 m wide seen from about 0.66 m (the lens is 0.145 m ahead of the car's centre,
    # the box's near face 0.2 m before its centre): some 58 of 160 columns.
    assert 50 <= right - left + 1 <= 66
    # Its sides only: DeepRacer's camera (0.127 m up) is lower than the box's top.
    assert not np.any(seen == scene.BOX_TOP)


def test_a_nearer_box_looks_wider_and_stands_lower_in_the_frame(
    camera: Camera, reinvent: Track
) -> None:
    pose = start_pose(reinvent)
    near = block(frame(camera, pose, solids(ahead_of(pose, 0.6))) == scene.BOX_SIDE)
    far = block(frame(camera, pose, solids(ahead_of(pose, 1.5))) == scene.BOX_SIDE)
    near_width, far_width = near[3] - near[2] + 1, far[3] - far[2] + 1
    # From the lens the near face is 0.255 m and 1.155 m away: about 4.5 times as wide.
    assert near_width > 3.5 * far_width
    assert near[1] > far[1]  # its foot is lower down the frame


def test_a_box_to_the_left_shows_left_of_centre_and_one_to_the_right_right_of_it(
    camera: Camera, reinvent: Track
) -> None:
    pose = start_pose(reinvent)
    middle = block(frame(camera, pose, solids(ahead_of(pose, 1.2))) == scene.BOX_SIDE)
    left = block(frame(camera, pose, solids(ahead_of(pose, 1.2, 0.25))) == scene.BOX_SIDE)
    right = block(frame(camera, pose, solids(ahead_of(pose, 1.2, -0.25))) == scene.BOX_SIDE)
    assert left[3] < middle[3] and left[2] < middle[2]
    assert right[2] > middle[2] and right[3] > middle[3]
    assert (left[2] + left[3]) / 2 < 60
    assert (right[2] + right[3]) / 2 > 100


@pytest.mark.parametrize(
    ("ahead", "left"),
    [
        (-1.0, 0.0),  # behind the car
        (-0.4, 0.3),  # behind, beside the rear wheel
        (1.0, 1.5),  # ahead, but well past the left edge of the view
        (1.0, -1.5),  # and past the right edge
        (0.3, 0.7),  # beside the car, off to the left
    ],
)
def test_a_box_out_of_view_changes_nothing(
    camera: Camera, reinvent: Track, ahead: float, left: float
) -> None:
    pose = start_pose(reinvent)
    plain = frame(camera, pose)
    assert np.array_equal(frame(camera, pose, solids(ahead_of(pose, ahead, left))), plain)


def test_a_nearer_box_hides_a_farther_one_behind_it(camera: Camera, reinvent: Track) -> None:
    pose = start_pose(reinvent)
    near, far = ahead_of(pose, 1.0), ahead_of(pose, 2.0)
    near_tone, far_tone = scene.BOX_SIDE, 150
    only_near = frame(camera, pose, solids(near, sides=[near_tone]))
    # Whichever order they are listed in, the far box is wholly behind the near one.
    for places, tones in (
        ((near, far), [near_tone, far_tone]),
        ((far, near), [far_tone, near_tone]),
    ):
        both = frame(camera, pose, solids(*places, sides=tones))
        assert np.array_equal(both, only_near)
    # Moved aside, the far box shows, and the near one still hides its inner part.
    aside = ahead_of(pose, 2.0, 0.3)
    both = frame(camera, pose, solids(near, aside, sides=[near_tone, far_tone]))
    alone = frame(camera, pose, solids(aside, sides=[far_tone]))
    assert np.any(both == far_tone)
    assert np.count_nonzero(both == far_tone) < np.count_nonzero(alone == far_tone)
    assert np.array_equal(both == near_tone, only_near == near_tone)


def test_a_bot_car_looks_darker_than_a_box_and_than_the_road(
    camera: Camera, reinvent: Track
) -> None:
    pose = start_pose(reinvent)
    plain = frame(camera, pose)
    place = ahead_of(pose, 1.0)
    box = frame(camera, pose, solids(place))
    car = frame(camera, pose, solids(place, size=BOT_CAR, side=scene.BOT_CAR_SIDE))
    box_pixels, car_pixels = box[box != plain], car[car != plain]
    assert len(car_pixels) > 500
    assert np.all(car_pixels == scene.BOT_CAR_SIDE)
    assert car_pixels.max() < box_pixels.min()
    road = plain[80:, 60:100]  # the road just ahead
    assert np.median(road) - 4 * scene.ROAD_GRAIN > scene.BOT_CAR_SIDE
    # A car body is smaller than a box: it covers less of the frame.
    assert len(car_pixels) < len(box_pixels)


def test_without_solids_every_frame_is_unchanged(camera: Camera, reinvent: Track) -> None:
    rng = np.random.default_rng(5)
    picks = rng.integers(0, len(reinvent.center), 6)
    x, y = reinvent.center[picks, 0], reinvent.center[picks, 1]
    yaw = rng.uniform(-math.pi, math.pi, 6)
    plain = camera.render(x, y, yaw)
    assert np.array_equal(camera.render(x, y, yaw, solids=None), plain)
    assert np.array_equal(camera.render(x, y, yaw, None), plain)
    # Cars that carry no objects see the same.
    empty = Solids(
        x=np.zeros((6, 0)),
        y=np.zeros((6, 0)),
        heading=np.zeros((6, 0)),
        length=np.ones(0),
        width=np.ones(0),
        height=np.ones(0),
        side_tone=np.zeros(0, dtype=np.uint8),
        top_tone=np.zeros(0, dtype=np.uint8),
    )
    assert np.array_equal(camera.render(x, y, yaw, solids=empty), plain)


def test_each_car_sees_its_own_objects_and_a_batch_equals_one_car_at_a_time(
    camera: Camera, reinvent: Track
) -> None:
    rng = np.random.default_rng(11)
    n = 5
    picks = rng.integers(0, len(reinvent.center) - 1, n)
    poses = []
    for i in picks:  # on the centre line, heading for the next waypoint
        (x0, y0), (x1, y1) = reinvent.center[i], reinvent.center[i + 1]
        poses.append((float(x0), float(y0), math.atan2(y1 - y0, x1 - x0)))
    places = [
        [ahead_of(p, 0.8, 0.15), ahead_of(p, 1.6, -0.2, 0.5), ahead_of(p, -1.0)] for p in poses
    ]
    x, y, heading = (np.array([[q[i] for q in row] for row in places]) for i in range(3))
    batch = Solids(
        x=x,
        y=y,
        heading=heading,
        length=np.array([BOX[0], BOT_CAR[0], BOX[0]]),
        width=np.array([BOX[1], BOT_CAR[1], BOX[1]]),
        height=np.array([BOX[2], BOT_CAR[2], BOX[2]]),
        side_tone=np.array([scene.BOX_SIDE, scene.BOT_CAR_SIDE, scene.BOX_SIDE], np.uint8),
        top_tone=np.array([scene.BOX_TOP, scene.BOT_CAR_TOP, scene.BOX_TOP], np.uint8),
    )
    px, py, pyaw = (np.array([p[i] for p in poses]) for i in range(3))
    frames = camera.render(px, py, pyaw, solids=batch)
    for i, pose in enumerate(poses):
        own = Solids(
            x=x[i : i + 1],
            y=y[i : i + 1],
            heading=heading[i : i + 1],
            length=batch.length,
            width=batch.width,
            height=batch.height,
            side_tone=batch.side_tone,
            top_tone=batch.top_tone,
        )
        assert np.array_equal(frames[i], frame(camera, pose, own))
        assert np.any(frames[i] == scene.BOX_SIDE)
        assert np.any(frames[i] == scene.BOT_CAR_SIDE)
    # Written into a reused array, even one that is not contiguous, the same frames.
    out = np.zeros((n, 120, 320), dtype=np.uint8)[:, :, ::2]
    assert camera.render(px, py, pyaw, solids=batch, out=out) is out
    assert np.array_equal(out, frames)


def test_one_cars_one_object_draws_as_it_does_in_a_batch(camera: Camera, reinvent: Track) -> None:
    """A two-car race's rival goes through a plain-float path (one car, one object); it
    must draw what the batched path draws, to the bit: near and far, ahead, beside and
    behind the lens, seen from above its top (a low box) and from below it (a bot car),
    and with the lens inside it."""
    rng = np.random.default_rng(46)
    start = start_pose(reinvent)
    drawn = 0
    for case in range(400):
        pose = ahead_of(start, rng.uniform(-1.0, 3.0), rng.uniform(-0.4, 0.4))
        pose = (pose[0], pose[1], pose[2] + rng.normal(0.0, 0.3))
        reach = 0.0 if case % 50 == 0 else rng.uniform(-0.5, 2.5)  # now and then: inside
        place = ahead_of(pose, reach, rng.normal(0.0, 0.4), rng.uniform(-math.pi, math.pi))
        size = (BOX, BOT_CAR, (0.3, 0.3, 0.05))[case % 3]  # the last seen from above
        lone = solids(place, size=size)
        # A second car with an object of its own takes the batched path for both.
        other = ahead_of(start, 1.0)
        pair = Solids(
            x=np.array([[place[0]], [other[0] + 0.5]]),
            y=np.array([[place[1]], [other[1]]]),
            heading=np.array([[place[2]], [other[2]]]),
            length=lone.length,
            width=lone.width,
            height=lone.height,
            side_tone=lone.side_tone,
            top_tone=lone.top_tone,
        )
        poses = [pose, other]
        batch = camera.render(*(np.array([p[i] for p in poses]) for i in range(3)), solids=pair)
        alone = frame(camera, pose, lone)
        assert np.array_equal(alone, batch[0]), f"case {case}"
        drawn += int(not np.array_equal(alone, frame(camera, pose)))
    assert drawn > 150  # most cases put the object in view


def test_a_box_passed_close_by_fills_the_side_of_the_view_without_garbage(
    camera: Camera, reinvent: Track
) -> None:
    """A box beside the car, reaching from behind the lens (4.5 cm) to ahead of it: only
    the part in front of the lens shows, at the left edge of the frame, in one piece."""
    pose = start_pose(reinvent)
    plain = frame(camera, pose)
    seen = frame(camera, pose, solids(ahead_of(pose, 0.3, 0.25)))
    changed = seen != plain
    assert np.all(seen[changed] == scene.BOX_SIDE)
    assert changed[:, :10].mean() > 0.9  # the left edge is box, top to bottom
    assert not changed[:, 80:].any()  # nothing on the right half
    for row in changed:  # each row: box from the left edge, then the scene
        assert not np.any(np.diff(row.astype(int)) > 0)


def test_nosed_into_a_box_the_camera_sees_only_box(camera: Camera, reinvent: Track) -> None:
    pose = start_pose(reinvent)
    inside = frame(camera, pose, solids(ahead_of(pose, 0.2)))  # the lens is in the box
    assert np.all(inside == scene.BOX_SIDE)
    touching = frame(camera, pose, solids(ahead_of(pose, 0.375)))  # its face 1 cm ahead
    assert np.mean(touching == scene.BOX_SIDE) > 0.95


def test_a_camera_higher_than_a_box_sees_its_lighter_top_above_its_sides(
    reinvent: Track,
) -> None:
    camera = Camera(reinvent, CameraSpec(mount_height=0.5, pitch_deg=30.0))
    pose = start_pose(reinvent)
    seen = frame(camera, pose, solids(ahead_of(pose, 1.2, 0.0, 0.6)))
    top, side = seen == scene.BOX_TOP, seen == scene.BOX_SIDE
    assert top.sum() > 100 and side.sum() > 100
    assert scene.BOX_TOP > scene.BOX_SIDE
    for column in np.nonzero(top.any(axis=0) & side.any(axis=0))[0]:
        # In each column the lid is seen beyond the near sides, so higher up the frame.
        assert np.nonzero(top[:, column])[0].mean() < np.nonzero(side[:, column])[0].mean()


def test_boxes_are_where_geometry_puts_them(camera: Camera, reinvent: Track) -> None:
    """Against rays cast through every pixel's centre: a box turned across the road, one
    beside the car partly behind the lens and a bot car partly behind the first box, each
    pixel showing the nearest."""
    pose = start_pose(reinvent)
    places = [ahead_of(pose, 1.3, 0.1, 0.7), ahead_of(pose, 0.3, -0.25, 0.2)]
    places.append(ahead_of(pose, 2.2, 0.55, -0.3))
    objects = Solids(
        x=np.array([[p[0] for p in places]]),
        y=np.array([[p[1] for p in places]]),
        heading=np.array([[p[2] for p in places]]),
        length=np.array([BOX[0], BOX[0], BOT_CAR[0]]),
        width=np.array([BOX[1], BOX[1], BOT_CAR[1]]),
        height=np.array([BOX[2], BOX[2], BOT_CAR[2]]),
        side_tone=np.array([100, 110, 40], dtype=np.uint8),
        top_tone=np.array([120, 130, 50], dtype=np.uint8),
    )
    expected = np.where((hit := cast_rays(camera, pose, objects)) >= 0, hit, frame(camera, pose))
    seen = frame(camera, pose, objects)
    assert np.count_nonzero(seen != expected) <= 2  # a pixel centre on an edge may go either way
    assert all(np.any(seen == tone) for tone in (100, 110, 40))


def cast_rays(camera: Camera, pose: Pose, objects: Solids) -> np.ndarray:
    """Per pixel, the side tone of the nearest object its centre's ray meets, or -1."""
    spec = camera.spec
    height, width = camera.shape
    focal = (width / 2) / math.tan(math.radians(spec.fov_deg) / 2)
    pitch = math.radians(spec.pitch_deg)
    down = (np.arange(height)[:, None] + 0.5 - height / 2) / focal
    right = (np.arange(width)[None, :] + 0.5 - width / 2) / focal
    ahead = math.cos(pitch) - down * math.sin(pitch) + 0 * right
    left = -right + 0 * down
    up = -(math.sin(pitch) + down * math.cos(pitch)) + 0 * right
    x, y, yaw = pose
    c, s = math.cos(yaw), math.sin(yaw)
    origin = (x + spec.mount_forward * c, y + spec.mount_forward * s, spec.mount_height)
    direction = (ahead * c - left * s, ahead * s + left * c, up)
    nearest = np.full((height, width), np.inf)
    tone = np.full((height, width), -1)
    for j in range(objects.x.shape[1]):
        h = objects.heading[0, j]
        axes = ((math.cos(h), math.sin(h)), (-math.sin(h), math.cos(h)))
        rel = (origin[0] - objects.x[0, j], origin[1] - objects.y[0, j])
        slabs = [
            (rel[0] * a + rel[1] * b, direction[0] * a + direction[1] * b, half)
            for (a, b), half in zip(
                axes, (objects.length[j] / 2, objects.width[j] / 2), strict=True
            )
        ]
        low, high = np.full((height, width), -np.inf), np.full((height, width), np.inf)
        for start, step, half in slabs:
            with np.errstate(divide="ignore", invalid="ignore"):
                t0, t1 = (-half - start) / step, (half - start) / step
            low = np.maximum(low, np.minimum(t0, t1))
            high = np.minimum(high, np.maximum(t0, t1))
        with np.errstate(divide="ignore"):
            t0 = (0.0 - origin[2]) / direction[2]
            t1 = (objects.height[j] - origin[2]) / direction[2]
        low = np.maximum(low, np.minimum(t0, t1))
        high = np.minimum(high, np.maximum(t0, t1))
        hit = (high >= np.maximum(low, 0.0)) & (low < nearest)
        nearest = np.where(hit, low, nearest)
        tone = np.where(hit, int(objects.side_tone[j]), tone)
    return tone


def test_solids_are_checked(camera: Camera, reinvent: Track) -> None:
    good = solids(ahead_of(start_pose(reinvent), 1.0))
    fields = {name: getattr(good, name) for name in good.__dataclass_fields__}
    with pytest.raises(ValueError, match="2-D"):
        Solids(**{**fields, "x": np.zeros(1)})
    with pytest.raises(ValueError, match="one per object"):
        Solids(**{**fields, "height": np.ones(2)})
    with pytest.raises(ValueError, match="NaN"):
        Solids(**{**fields, "y": np.array([[np.nan]])})
    with pytest.raises(ValueError, match="positive"):
        Solids(**{**fields, "width": np.zeros(1)})
    with pytest.raises(ValueError, match="grey levels"):
        Solids(**{**fields, "side_tone": np.array([300])})
    as_lists = Solids(**{**fields, "x": [[fields["x"][0, 0]]], "side_tone": [96]})
    assert as_lists.x.dtype == np.float64 and as_lists.side_tone.dtype == np.uint8
    with pytest.raises(ValueError, match="1 car, not 2"):
        camera.render([0.0, 1.0], [0.0, 1.0], [0.0, 0.0], solids=good)


def test_solids_moved_elsewhere_draw_as_solids_built_there(camera: Camera, reinvent: Track) -> None:
    pose = start_pose(reinvent)
    here = solids(ahead_of(pose, 1.2, 0.1, 0.3), size=(0.3235, 0.1961, 0.2))
    there = ahead_of(pose, 0.9, -0.15, -0.4)
    frame(camera, pose, here)  # its drawing worked out and kept, then moved
    moved = here.placed_at([[there[0]]], [[there[1]]], [[there[2]]])
    built = solids(there, size=(0.3235, 0.1961, 0.2))
    assert np.array_equal(frame(camera, pose, moved), frame(camera, pose, built))
    assert not np.array_equal(frame(camera, pose, moved), frame(camera, pose, here))
    with pytest.raises(ValueError, match="NaN"):
        here.placed_at([[np.nan]], [[0.0]], [[0.0]])
    with pytest.raises(ValueError, match="shape"):
        here.placed_at([0.0, 1.0], [0.0, 1.0], [0.0, 0.0])


def test_sees_none_only_when_the_frame_would_not_show_the_object(
    camera: Camera, reinvent: Track
) -> None:
    """The cheap test a head-to-head car's frame takes before building its rival: when it
    says no object can be seen, the frame with the object is the frame without it, to the
    bit. Tried all round the car, near and far, low and high."""
    rng = np.random.default_rng(5)
    pose = start_pose(reinvent)
    length, width, height = BOT_CAR
    radius = math.sqrt(length**2 + width**2 + height**2) / 2
    said_none = drawn = 0
    for _ in range(400):
        bearing, distance = rng.uniform(-math.pi, math.pi), rng.uniform(0.0, 4.0)
        place = ahead_of(pose, distance * math.cos(bearing), distance * math.sin(bearing))
        none = camera.sees_none(
            [pose[0]],
            [pose[1]],
            [pose[2]],
            objects=[(place[0], place[1])],
            radius=radius,
            middle_height=height / 2,
        )
        with_it = frame(camera, pose, solids(place, size=BOT_CAR))
        if none:
            said_none += 1
            assert np.array_equal(with_it, frame(camera, pose))
        else:
            drawn += 1
    # Behind and beside the car most of the time; in view the rest.
    assert said_none > 100 and drawn > 50
    # An object straight ahead is never ruled out, nor one across the lens.
    for place in (ahead_of(pose, 1.0), ahead_of(pose, 0.1)):
        spot = [(place[0], place[1])]
        assert not camera.sees_none(
            [pose[0]], [pose[1]], [pose[2]], objects=spot, radius=radius, middle_height=0.08
        )
