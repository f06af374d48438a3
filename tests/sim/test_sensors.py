"""The camera and lidar: what a car sees, checked against geometry worked out by hand and
against DeepRacer's own camera."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import shapely
from shapely.geometry import LineString, MultiLineString

from sim.sensors import camera_scene as scene
from sim.sensors.batched import (
    DEEPRACER_CAMERA,
    PHYSICAL_CAR_CAMERA,
    Camera,
    CameraSpec,
    Lidar,
    LidarSpec,
    SectorLidar,
    SectorLidarSpec,
    camera_space,
    channels_last,
    lidar_space,
    sector_lidar_space,
    sectors,
)
from sim.sensors.raster import TrackRaster
from sim.tracks.track import Track, load_track

CENTRE_RADIUS, INNER_RADIUS, OUTER_RADIUS = 2.0, 1.62, 2.38
HALF_WIDTH = 0.38


def ring_array(points: int = 120) -> np.ndarray:
    """A circular track run counter-clockwise: centre r=2, borders at 1.62 and 2.38."""
    theta = np.linspace(0.0, 2.0 * math.pi, points + 1)
    unit = np.stack([np.cos(theta), np.sin(theta)], axis=1)
    array = np.hstack([unit * CENTRE_RADIUS, unit * INNER_RADIUS, unit * OUTER_RADIUS])
    array[-1] = array[0]
    return array


def stadium_array(straight: float = 6.0, radius: float = 1.5, step: float = 0.1) -> np.ndarray:
    """A long rounded rectangle run counter-clockwise; its bottom straight lies on y=-radius."""
    points: list[tuple[float, float]] = []
    normals: list[tuple[float, float]] = []
    along = np.arange(0.0, straight, step)
    for x in along:  # bottom straight, driving +x
        points.append((-straight / 2 + x, -radius))
        normals.append((0.0, -1.0))
    arc = np.linspace(-math.pi / 2, math.pi / 2, int(math.pi * radius / step), endpoint=False)
    for a in arc:
        points.append((straight / 2 + radius * math.cos(a), radius * math.sin(a)))
        normals.append((math.cos(a), math.sin(a)))
    for x in along:  # top straight, driving -x
        points.append((straight / 2 - x, radius))
        normals.append((0.0, 1.0))
    for a in arc + math.pi:
        points.append((-straight / 2 + radius * math.cos(a), radius * math.sin(a)))
        normals.append((math.cos(a), math.sin(a)))
    centre, normal = np.array(points), np.array(normals)
    array = np.hstack([centre, centre - normal * HALF_WIDTH, centre + normal * HALF_WIDTH])
    return np.vstack([array, array[:1]])


def ray_circle(origin: tuple[float, float], heading: float, radius: float) -> float:
    """Distance along a ray to where it first meets a circle about the origin (inf if never)."""
    ox, oy = origin
    dx, dy = math.cos(heading), math.sin(heading)
    b = ox * dx + oy * dy
    c = ox * ox + oy * oy - radius * radius
    disc = b * b - c
    if disc < 0:
        return math.inf
    roots = [t for t in (-b - math.sqrt(disc), -b + math.sqrt(disc)) if t > 0]
    return min(roots, default=math.inf)


def ray_index(lidar: Lidar, degrees: float) -> int:
    """The ray pointing `degrees` counter-clockwise from the car's heading."""
    offset = np.mod(np.degrees(lidar.angles) - degrees + 180.0, 360.0) - 180.0
    return int(np.argmin(np.abs(offset)))


def exact_scan(track: Track, x: float, y: float, yaw: float, lidar: Lidar) -> np.ndarray:
    """What the lidar should read, from shapely's ray-border intersections."""
    borders = MultiLineString([track.inner, track.outer])
    spec = lidar.spec
    readings = []
    for angle in lidar.angles:
        end = (
            x + spec.max_range * math.cos(yaw + angle),
            y + spec.max_range * math.sin(yaw + angle),
        )
        hits = shapely.get_coordinates(LineString([(x, y), end]).intersection(borders))
        nearest = np.min(np.hypot(hits[:, 0] - x, hits[:, 1] - y)) if len(hits) else spec.max_range
        readings.append(min(max(float(nearest), spec.min_range), spec.max_range))
    return np.array(readings)


@pytest.fixture(scope="module")
def ring() -> Track:
    return Track.from_array(ring_array(), "ring")


@pytest.fixture(scope="module")
def stadium() -> Track:
    return Track.from_array(stadium_array(), "stadium")


@pytest.fixture(scope="module")
def lidar(ring: Track) -> Lidar:
    return Lidar(ring)


@pytest.fixture(scope="module")
def camera(ring: Track) -> Camera:
    return Camera(ring)


# A car on the ring's centre line at (2, 0), pointing along the track (counter-clockwise).
ON_CENTRE = (CENTRE_RADIUS, 0.0, math.pi / 2)


# --- lidar ----------------------------------------------------------------------------------


def test_lidar_sees_both_borders_square_to_the_car(lidar: Lidar) -> None:
    scan = lidar.scan(*ON_CENTRE)
    assert scan.shape == (1, 64)
    assert scan.dtype == np.float32
    # Right of the car is outward, to the outer border; left is inward, to the inner one.
    assert scan[0, ray_index(lidar, -90)] == pytest.approx(HALF_WIDTH, abs=0.005)
    assert scan[0, ray_index(lidar, 90)] == pytest.approx(HALF_WIDTH, abs=0.005)


def test_lidar_forward_ray_meets_the_outer_border_at_the_chord(lidar: Lidar) -> None:
    chord = math.sqrt(OUTER_RADIUS**2 - CENTRE_RADIUS**2)  # 1.290 m
    scan = lidar.scan(*ON_CENTRE)
    assert scan[0, ray_index(lidar, 0)] == pytest.approx(chord, abs=0.005)
    assert scan[0, ray_index(lidar, 180)] == pytest.approx(chord, abs=0.005)


def test_lidar_oblique_rays_match_ray_circle_geometry(lidar: Lidar) -> None:
    x, y, yaw = ON_CENTRE
    scan = lidar.scan(x, y, yaw)[0]
    for degrees in (45.0, -45.0, 135.0, -22.5):
        heading = yaw + math.radians(degrees)
        expected = min(
            ray_circle((x, y), heading, INNER_RADIUS),
            ray_circle((x, y), heading, OUTER_RADIUS),
            lidar.spec.max_range,
        )
        assert scan[ray_index(lidar, degrees)] == pytest.approx(expected, abs=0.005), degrees


def test_lidar_reads_max_range_when_a_ray_meets_nothing(ring: Track) -> None:
    lidar = Lidar(ring)
    # Off the track, outside the ring, facing away from it: nothing ahead, the ring behind.
    scan = lidar.scan(3.0, 0.0, 0.0)[0]
    assert scan[ray_index(lidar, 0)] == pytest.approx(lidar.spec.max_range)
    assert scan[ray_index(lidar, 180)] == pytest.approx(3.0 - OUTER_RADIUS, abs=0.005)
    # A shorter lidar on the centre line cannot reach the border 1.29 m ahead.
    short = Lidar(ring, LidarSpec(max_range=1.0))
    assert short.scan(*ON_CENTRE)[0, ray_index(short, 0)] == pytest.approx(1.0)


def test_lidar_never_reads_under_min_range(lidar: Lidar) -> None:
    # 5 mm from the outer border: the reading is clipped up to min_range.
    scan = lidar.scan(OUTER_RADIUS - 0.005, 0.0, math.pi / 2)[0]
    assert scan[ray_index(lidar, -90)] == pytest.approx(lidar.spec.min_range)
    assert scan.min() >= lidar.spec.min_range
    assert scan.max() <= lidar.spec.max_range


def test_lidar_ray_order_is_counter_clockwise_centred_on_the_heading() -> None:
    full = LidarSpec().angles_deg
    assert full[0] == pytest.approx(-180.0)
    assert full[32] == pytest.approx(0.0)
    assert np.all(np.diff(full) > 0)
    fan = LidarSpec(rays=5, fov_deg=120.0).angles_deg
    assert fan.tolist() == pytest.approx([-60.0, -30.0, 0.0, 30.0, 60.0])


def test_lidar_matches_exact_geometry_anywhere_on_the_ring(ring: Track, lidar: Lidar) -> None:
    rng = np.random.default_rng(7)
    angle = rng.uniform(0.0, 2.0 * math.pi, 12)
    radius = rng.uniform(INNER_RADIUS - 0.2, OUTER_RADIUS + 0.2, 12)  # some cars off track
    x, y = radius * np.cos(angle), radius * np.sin(angle)
    yaw = rng.uniform(-math.pi, math.pi, 12)
    scans = lidar.scan(x, y, yaw)
    for i in range(12):
        expected = exact_scan(ring, x[i], y[i], yaw[i], lidar)
        np.testing.assert_allclose(scans[i], expected, atol=0.02)


def test_lidar_matches_exact_geometry_on_a_real_deepracer_track(deepracer_dir: Path) -> None:
    track = load_track(deepracer_dir / "tracks" / "reinvent_base.npy")
    lidar = Lidar(track)
    rng = np.random.default_rng(11)
    s = rng.uniform(0.0, track.length, 16)
    centre, tangent = track.centerline.point_at(s), track.centerline.direction_at(s)
    offset = rng.uniform(-0.5, 0.5, 16) * track.width
    xy = centre + np.stack([-tangent[:, 1], tangent[:, 0]], axis=1) * offset[:, None]
    yaw = np.arctan2(tangent[:, 1], tangent[:, 0]) + rng.normal(0.0, 0.5, 16)
    scans = lidar.scan(xy[:, 0], xy[:, 1], yaw)
    for i in range(16):
        expected = exact_scan(track, xy[i, 0], xy[i, 1], yaw[i], lidar)
        np.testing.assert_allclose(scans[i], expected, atol=0.02)


def test_lidar_batch_equals_one_car_at_a_time(lidar: Lidar) -> None:
    rng = np.random.default_rng(3)
    angle = rng.uniform(0.0, 2.0 * math.pi, 6)
    radius = rng.uniform(INNER_RADIUS, OUTER_RADIUS, 6)
    x, y, yaw = radius * np.cos(angle), radius * np.sin(angle), rng.uniform(-3, 3, 6)
    batch = lidar.scan(x, y, yaw)
    singles = np.vstack([lidar.scan(x[i], y[i], yaw[i]) for i in range(6)])
    np.testing.assert_array_equal(batch, singles)


def test_sector_lidar_flags_the_side_where_a_border_is_close(ring: Track) -> None:
    # 8 cm from the outer border, on the car's right; the inner border is 0.68 m to the left.
    pose = (2.30, 0.0, math.pi / 2)
    flags = SectorLidar(ring).scan(*pose)
    assert flags.shape == (1, 8)
    assert flags.dtype == np.float32
    # Sectors run counter-clockwise from straight behind: 1-3 cover the right-hand side.
    assert flags[0, [1, 2, 3]].tolist() == [1.0, 1.0, 1.0]
    assert flags[0, [5, 6]].tolist() == [0.0, 0.0]
    assert set(flags.ravel().tolist()) <= {0.0, 1.0}
    scan = Lidar(ring).scan(*pose)
    np.testing.assert_array_equal(sectors(scan), flags)


def test_sectors_need_a_scan_that_splits_evenly() -> None:
    with pytest.raises(ValueError, match="sectors"):
        sectors(np.ones((1, 60), dtype=np.float32))
    with pytest.raises(ValueError, match="sectors"):
        SectorLidarSpec(sectors=7)


def test_lidar_space_holds_its_scans(lidar: Lidar) -> None:
    space = lidar_space(lidar.spec)
    assert space.shape == (64,)
    assert space.dtype == np.float32
    assert float(space.high.max()) == pytest.approx(2.0)
    assert space.contains(lidar.scan(*ON_CENTRE)[0])
    assert sector_lidar_space().shape == (8,)


# --- camera ---------------------------------------------------------------------------------

DARK_ROAD = scene.ROAD + 4 * scene.ROAD_GRAIN  # road grain stays below this
BRIGHT_BAND = scene.BORDER - 4 * scene.BORDER_GRAIN  # and band grain above this
WALL_TONES = {scene.WALL_LOW_X, scene.WALL_HIGH_X, scene.WALL_LOW_Y, scene.WALL_HIGH_Y}
DR_DEMO = "car-model/dr-demo-1.png"
# Where dr-demo-1.png was taken, found by a search over poses (every 5 cm along the centre
# line, 7 offsets across the road, 17 headings, then refined) for the best correlation:
# re:Invent 2018's top straight, driving -x towards the left-hand hairpin, a little right
# of the centre line; the wall ahead is the one the sun lights, the darker one on the right
# the high-y.
DR_DEMO_POSE = (2.855, 4.598, math.radians(-177.8))


def grassy(pixels: np.ndarray) -> np.ndarray:
    return np.asarray(np.abs(pixels.astype(int) - scene.GRASS) <= 4 * scene.GRASS_GRAIN)


def start_pose(track: Track) -> tuple[float, float, float]:
    """The first waypoint, heading for the second: where DeepRacer starts a car."""
    (x0, y0), (x1, y1) = track.center[0], track.center[1]
    return float(x0), float(y0), math.atan2(y1 - y0, x1 - x0)


@pytest.fixture
def reinvent(deepracer_dir: Path) -> Track:
    return load_track(deepracer_dir / "tracks" / "reinvent_base.npy")


def test_the_default_camera_is_deepracers_simulated_camera() -> None:
    spec = CameraSpec()
    assert spec == DEEPRACER_CAMERA
    assert (spec.width, spec.height) == (160, 120)
    assert math.radians(spec.fov_deg) == pytest.approx(1.13)  # about 65 degrees
    # The URDF's 0.2618 rad, less the 1.39 degrees the chassis tips nose-up on its wheels.
    assert math.radians(spec.pitch_deg) == pytest.approx(0.2618 - 0.02434, abs=1e-4)
    assert spec.mount_height == pytest.approx(0.1328, abs=0.0005)
    assert spec.mount_forward == pytest.approx(0.1418, abs=0.0005)
    # The physical car's wide lens stays available by name, never by default.
    assert PHYSICAL_CAR_CAMERA.fov_deg == pytest.approx(120.0)
    assert spec != PHYSICAL_CAR_CAMERA


def test_camera_frames_are_greyscale_images_of_the_spec_size(ring: Track) -> None:
    for width, height in ((160, 120), (80, 60), (40, 30), (41, 31)):
        frames = Camera(ring, CameraSpec(width=width, height=height)).render(*ON_CENTRE)
        assert frames.shape == (1, height, width)
        assert frames.dtype == np.uint8


def test_camera_horizon_sits_where_the_pitch_puts_it(camera: Camera) -> None:
    # Focal length 80 / tan(1.13 / 2) = 126.2 px; 13.6 degrees up from the image centre
    # is 30.5 px above row 60: rows 0-28 look above the horizon, row 29 is the first below.
    assert camera.horizon_row == 29
    frame = camera.render(*ON_CENTRE)[0]
    # Above the horizon only walls and the background over them; never ground.
    above = frame[: camera.horizon_row]
    assert set(np.unique(above).tolist()) <= {*WALL_TONES, scene.BACKGROUND}


def test_camera_sees_road_in_the_lower_middle(camera: Camera) -> None:
    frame = camera.render(*ON_CENTRE)[0]
    lower_middle = frame[100:, 50:110]
    dashes = lower_middle == scene.CENTRE
    assert np.all(lower_middle[~dashes] <= DARK_ROAD)
    assert np.mean(~dashes) > 0.7


def test_camera_sees_border_bands_on_both_sides(stadium: Track, camera: Camera) -> None:
    for cam, pose in ((camera, ON_CENTRE), (Camera(stadium), (0.0, -1.5, 0.0))):
        frame = cam.render(*pose)[0]
        ground = frame[cam.horizon_row :]
        width = frame.shape[1]
        assert np.any(ground[:, : width // 2] >= BRIGHT_BAND)
        assert np.any(ground[:, width // 2 :] >= BRIGHT_BAND)
        # Past the white bands lies the green field.
        assert np.any(grassy(ground))


def test_camera_view_of_the_road_is_symmetric_on_a_straight(stadium: Track) -> None:
    camera = Camera(stadium)
    frame = camera.render(0.0, -1.5, 0.0)[0]  # middle of the bottom straight, on the line
    # The road and its bands, up to 1.2 m ahead (the walls and the field beyond are not
    # symmetric about this straight); the grain is not symmetric either, so compare what
    # each pixel shows: road, band, dash or field.
    near = frame[camera.horizon_row + 14 :].astype(int)
    kind = np.digitize(near, [DARK_ROAD + 1, scene.CENTRE - 1, scene.CENTRE + 1, BRIGHT_BAND])
    assert np.mean(kind == kind[:, ::-1]) > 0.97


def test_camera_image_changes_when_the_car_moves_or_turns(camera: Camera) -> None:
    x, y, yaw = ON_CENTRE
    still = camera.render(x, y, yaw)[0]
    moved = camera.render(x - 0.05, y + 0.1, yaw)[0]
    turned = camera.render(x, y, yaw + math.radians(10))[0]
    assert np.mean(still != moved) > 0.01
    assert np.mean(still != turned) > 0.05


def test_camera_scene_slides_right_when_the_car_turns_left(stadium: Track) -> None:
    camera = Camera(stadium)
    row = camera.horizon_row + 14  # a row where both bands are in view on a straight

    def band_columns(turn_deg: float) -> tuple[int, int]:
        frame = camera.render(0.0, -1.5, math.radians(turn_deg))[0]
        columns = np.flatnonzero(frame[row] >= BRIGHT_BAND)
        return int(columns.min()), int(columns.max())

    left_band, right_band = band_columns(0.0)
    turned_left, turned_right = band_columns(5.0), band_columns(-5.0)
    assert turned_left[0] > left_band and turned_left[1] > right_band
    assert turned_right[0] < left_band and turned_right[1] < right_band


def test_camera_batch_equals_one_car_at_a_time_and_is_deterministic(
    ring: Track, camera: Camera
) -> None:
    rng = np.random.default_rng(5)
    angle = rng.uniform(0.0, 2.0 * math.pi, 9)
    radius = rng.uniform(INNER_RADIUS, OUTER_RADIUS, 9)
    x, y, yaw = radius * np.cos(angle), radius * np.sin(angle), rng.uniform(-3, 3, 9)
    x[0], y[0] = 40.0, -3.0  # a car outside the walls too
    batch = camera.render(x, y, yaw)
    # One car, three cars and nine are rendered by different paths: all agree exactly.
    singles = np.concatenate([camera.render(x[i], y[i], yaw[i]) for i in range(9)])
    threes = np.concatenate(
        [camera.render(x[i : i + 3], y[i : i + 3], yaw[i : i + 3]) for i in (0, 3, 6)]
    )
    np.testing.assert_array_equal(batch, singles)
    np.testing.assert_array_equal(batch, threes)
    np.testing.assert_array_equal(Camera(ring).render(x, y, yaw), batch)
    out = np.zeros_like(batch)
    assert camera.render(x, y, yaw, out=out) is out
    np.testing.assert_array_equal(out, batch)


def test_camera_outside_the_walls_sees_only_wall(camera: Camera) -> None:
    frame = camera.render(500.0, -300.0, 1.0)[0]
    assert set(np.unique(frame).tolist()) <= WALL_TONES


def test_a_far_wall_shows_the_background_over_its_top_and_a_near_one_fills_the_view(
    stadium: Track,
) -> None:
    camera = Camera(stadium)
    # The stadium's field ends 5.8 m ahead: the wall's top is below the image's top edge.
    far = camera.render(0.0, -1.5, 0.0)[0]
    assert np.all(far[0, 60:100] == scene.BACKGROUND)
    assert np.all(np.isin(far[camera.horizon_row - 5 : camera.horizon_row], list(WALL_TONES)))
    # 1.3 m from the wall beside the straight: wall from the horizon up to the top edge.
    near = camera.render(0.0, -1.5, -math.pi / 2)[0]
    assert set(np.unique(near[: camera.horizon_row]).tolist()) <= WALL_TONES


def test_the_wall_in_the_sun_is_brighter_than_the_one_in_shade(stadium: Track) -> None:
    camera = Camera(stadium)
    towards_low_x = camera.render(0.0, -1.5, math.pi)[0]
    towards_high_x = camera.render(0.0, -1.5, 0.0)[0]
    middle = slice(camera.horizon_row - 3, camera.horizon_row), slice(70, 90)
    assert np.all(towards_low_x[middle] == scene.WALL_LOW_X)
    assert np.all(towards_high_x[middle] == scene.WALL_HIGH_X)
    assert scene.WALL_LOW_X > scene.WALL_HIGH_X


def test_camera_space_accepts_rendered_frames(camera: Camera) -> None:
    space = camera_space(camera.spec)
    assert space.shape == (120, 160, 1)
    assert space.dtype == np.uint8
    frames = channels_last(camera.render(*ON_CENTRE))
    assert frames.shape == (1, 120, 160, 1)
    assert space.contains(frames[0])


def test_sensors_refuse_poses_that_are_not_numbers(camera: Camera, lidar: Lidar) -> None:
    with pytest.raises(ValueError, match="finite"):
        camera.render([0.0], [float("nan")], [0.0])
    with pytest.raises(ValueError, match="same length"):
        lidar.scan([0.0, 1.0], [0.0], [0.0])
    with pytest.raises(ValueError, match="same length"):
        camera.render([[0.0]], [[0.0]], [[0.0]])


# --- DeepRacer's look on re:Invent 2018 -------------------------------------------------------


def test_at_the_start_of_reinvent_the_frame_looks_like_deepracers(reinvent: Track) -> None:
    camera = Camera(reinvent)
    frame = camera.render(*start_pose(reinvent))[0].astype(int)
    horizon = camera.horizon_row
    # Dark walls right above the horizon, at the row the pitch predicts.
    assert horizon == 29
    assert np.all(frame[horizon - 10 : horizon] <= max(WALL_TONES))
    # The road is darker than the white bands either side of it, 1-3 m ahead.
    rows = frame[horizon + 9 : horizon + 24]
    middle = rows[:, 40:120]
    road = middle[middle != scene.CENTRE]
    assert np.median(road) <= DARK_ROAD
    for side in (rows[:, :80], rows[:, 80:]):
        assert side.max() >= BRIGHT_BAND > np.median(road) + 100
    # Green beside the road: the infield on the left, the field to the wall on the right.
    assert np.mean(grassy(frame[horizon + 9 : horizon + 13, :30])) > 0.9
    assert np.mean(grassy(frame[horizon + 9 : horizon + 13, 135:])) > 0.9
    # The centre line's dashes in the lower middle: orange runs with road between them.
    centre_column = frame[60:, 78:82].min(axis=1) == scene.CENTRE
    runs = np.count_nonzero(np.diff(centre_column.astype(int)) == 1)
    assert runs >= 3
    assert 0.2 < np.mean(centre_column) < 0.8


def test_raster_paints_deepracers_bands_and_dashes(stadium: Track) -> None:
    raster = TrackRaster.for_track(stadium)
    texture = raster.texture.astype(int)
    res = raster.resolution
    col = int((0.0 - raster.origin[0]) / res)  # across the bottom straight at x = 0
    rows = ((np.array([-1.5 - HALF_WIDTH, -1.5 + HALF_WIDTH]) - raster.origin[1]) / res).astype(int)
    across = texture[rows[0] : rows[1] + 1, col]
    bands = np.flatnonzero(across >= BRIGHT_BAND)
    # 0.0762 m bands inside each border: about 8 cells on either edge of the road.
    assert 14 <= len(bands) <= 18
    assert bands.min() <= 1 and bands.max() >= len(across) - 2
    # Dashes 0.0508 m long with gaps as long, along the centre line (y = -1.5).
    line = texture[int((-1.5 - raster.origin[1]) / res), :]
    on = line == scene.CENTRE
    start, stop = (int((x - raster.origin[0]) / res) for x in (-2.5, 2.5))
    painted = on[start:stop]
    edges = np.flatnonzero(np.diff(painted.astype(int)))
    lengths = np.diff(edges)
    assert np.median(lengths) == pytest.approx(scene.DASH_LENGTH / res, abs=1)
    # 0.0254 m wide: two or three cells across.
    dash = start + int(np.flatnonzero(painted)[0]) + 2
    width = np.count_nonzero(texture[rows[0] : rows[1] + 1, dash] == scene.CENTRE)
    assert 2 <= width <= 3


def test_a_frame_like_dr_demo_correlates_with_it_better_than_the_wide_lens(
    reinvent: Track, deepracer_dir: Path
) -> None:
    image_module = pytest.importorskip("PIL.Image")
    # DeepRacer's pipeline: the 640x480 frame resized to 160x120 (PIL bilinear,
    # deepracer-simapp sensors_rollout.py) and greyed with 0.2989 R + 0.5870 G + 0.1140 B.
    with image_module.open(deepracer_dir / DR_DEMO) as image:
        small = image.convert("RGB").resize((160, 120), resample=image_module.BILINEAR)
    rgb = np.asarray(small, dtype=np.float64)
    grey = 0.2989 * rgb[..., 0] + 0.5870 * rgb[..., 1] + 0.1140 * rgb[..., 2]

    def likeness(spec: CameraSpec) -> float:
        frame = Camera(reinvent, spec).render(*DR_DEMO_POSE)[0]
        return float(np.corrcoef(grey.ravel(), frame.ravel().astype(np.float64))[0, 1])

    deepracer, wide = likeness(DEEPRACER_CAMERA), likeness(PHYSICAL_CAR_CAMERA)
    assert deepracer > 0.9
    assert deepracer > wide + 0.5


# --- raster ---------------------------------------------------------------------------------


def test_raster_is_built_once_per_track_content(ring: Track) -> None:
    same_content = Track.from_array(ring_array(), "another name")
    assert TrackRaster.for_track(same_content) is TrackRaster.for_track(ring)


def test_raster_road_and_border_distance_match_the_geometry(ring: Track) -> None:
    raster = TrackRaster.for_track(ring)
    rng = np.random.default_rng(2)
    rows = rng.integers(0, raster.height, 3000)
    cols = rng.integers(0, raster.width, 3000)
    centres = np.stack(
        [
            raster.origin[0] + (cols + 0.5) * raster.resolution,
            raster.origin[1] + (rows + 0.5) * raster.resolution,
        ],
        axis=1,
    )
    np.testing.assert_array_equal(raster.road[rows, cols], ring.on_road(centres))
    radius = np.hypot(centres[:, 0], centres[:, 1])
    true_distance = np.minimum(np.abs(radius - INNER_RADIUS), np.abs(radius - OUTER_RADIUS))
    np.testing.assert_allclose(raster.border_distance[rows, cols], true_distance, atol=0.008)
    assert raster.texture.dtype == np.uint8
    assert raster.border_distance.dtype == np.float32
