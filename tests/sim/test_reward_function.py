"""Reward functions: the templates pay what the console's templates of the same names pay, and
every way a racer's file can fail says where."""

from __future__ import annotations

import ast
import itertools
import math
import pickle
import textwrap
from pathlib import Path

import numpy as np
import pytest

from sim.coach.reward_line import load_template, template_source
from sim.reward.errors import RewardFunctionError
from sim.reward.function import RewardFunction, load_reward_function, load_reward_source
from sim.reward.sample_params import PARAM_KEYS, TRACK_WIDTH, sample_params
from sim.reward.template_files import TEMPLATES

LANE = TRACK_WIDTH / 4


def write_reward(tmp_path: Path, code: str, name: str = "my_reward.py") -> Path:
    path = tmp_path / name
    path.write_text(textwrap.dedent(code).lstrip("\n"), encoding="utf-8")
    return path


def load_error(path: Path) -> RewardFunctionError:
    with pytest.raises(RewardFunctionError) as caught:
        load_reward_function(path)
    return caught.value


def call_error(path: Path) -> RewardFunctionError:
    reward = load_reward_function(path)
    with pytest.raises(RewardFunctionError) as caught:
        reward(sample_params())
    return caught.value


def assert_one_sentence(error: RewardFunctionError, path: Path, line: int | None) -> str:
    message = str(error)
    assert "\n" not in message
    assert message.endswith(".")
    assert error.path == path
    assert error.line == line
    where = f"{path} line {line}:" if line is not None else f"{path}:"
    assert message.startswith(where), message
    return message


# --- sample params ---------------------------------------------------------------------------
def test_sample_params_have_every_deepracer_key_with_its_type() -> None:
    params = sample_params()
    assert tuple(params) == PARAM_KEYS
    assert len(set(PARAM_KEYS)) == len(PARAM_KEYS) == 27
    bools = ("all_wheels_on_track", "is_left_of_center", "is_reversed", "is_offtrack")
    for key in (*bools, "is_crashed", "object_in_camera"):
        assert type(params[key]) is bool, key
    floats = ("x", "y", "heading", "distance_from_center", "track_width", "track_length")
    for key in (*floats, "progress", "speed", "steering_angle", "projection_distance", "sim_time"):
        assert type(params[key]) is float, key
    assert type(params["steps"]) is int
    waypoints = params["waypoints"]
    assert isinstance(waypoints, list)
    assert all(type(p) is tuple and len(p) == 2 for p in waypoints)
    assert waypoints[0] == waypoints[-1]
    for key in ("closest_waypoints", "closest_objects"):
        pair = params[key]
        assert isinstance(pair, list)
        assert len(pair) == 2
        assert all(type(i) is int for i in pair)


def test_sample_params_are_consistent_for_a_car_on_the_straight() -> None:
    params = sample_params()
    waypoints = params["waypoints"]
    closest = params["closest_waypoints"]
    x, y, progress = params["x"], params["y"], params["progress"]
    assert isinstance(waypoints, list)
    assert isinstance(closest, list)
    assert isinstance(x, float)
    assert isinstance(y, float)
    assert isinstance(progress, float)
    before, after = closest
    assert after == before + 1
    assert waypoints[before][0] <= x <= waypoints[after][0]
    assert params["distance_from_center"] == abs(y)
    assert params["is_left_of_center"] is False
    assert 0.0 < progress < 100.0
    length = sum(math.dist(a, b) for a, b in itertools.pairwise(waypoints))
    assert params["track_length"] == pytest.approx(length)
    assert progress == pytest.approx(100.0 * x / length)


def test_sample_params_without_objects_use_deepracer_defaults() -> None:
    params = sample_params(objects=())
    assert params["closest_objects"] == [0, 0]
    for key in ("objects_location", "objects_left_of_center", "objects_speed"):
        assert params[key] == []
    assert params["objects_distance_from_center"] == []
    assert params["object_in_camera"] is False


def test_sample_params_measure_objects_like_deepracer() -> None:
    params = sample_params(objects=[(1.0, -LANE), (3.0, LANE), (5.0, -LANE)])
    assert params["closest_objects"] == [0, 1]  # behind the car at x=2.1, then ahead of it
    assert params["objects_left_of_center"] == [False, True, False]
    assert params["objects_distance"] == [1.0, 3.0, 5.0]
    assert params["objects_distance_from_center"] == pytest.approx([LANE] * 3)
    assert params["object_in_camera"] is True


def test_sample_params_are_fresh_each_time() -> None:
    first = sample_params()
    first["x"] = 99.0
    waypoints = first["waypoints"]
    assert isinstance(waypoints, list)
    waypoints.append((1.0, 1.0))
    second = sample_params()
    assert second["x"] == 2.1
    assert second["waypoints"] == sample_params()["waypoints"]
    assert second["waypoints"] != waypoints


def test_sample_objects_off_the_straight_are_refused() -> None:
    with pytest.raises(ValueError, match="first straight"):
        sample_params(objects=[(9.0, 0.0)])


# --- templates -------------------------------------------------------------------------------
@pytest.mark.parametrize("name", sorted(TEMPLATES))
def test_each_template_returns_a_float_in_range(name: str) -> None:
    reward = load_template(name)
    value = reward(sample_params())
    assert type(value) is float
    assert 0.0 < value <= 1e5
    assert reward.name == TEMPLATES[name]
    assert "def reward_function(params):" in reward.source


@pytest.mark.parametrize("name", sorted(TEMPLATES))
def test_each_template_runs_in_a_time_trial_without_objects(name: str) -> None:
    value = load_template(name)(sample_params(objects=()))
    assert type(value) is float
    assert 0.0 < value <= 1e5


def road(**changes: object) -> dict[str, object]:
    """Sample params on a 1 m wide road (easy band edges), with `changes`."""
    return {**sample_params(objects=()), "track_width": 1.0, **changes}


@pytest.mark.parametrize(
    ("from_centre", "pays"),
    [(0.0, 1.0), (0.10, 1.0), (0.11, 0.5), (0.25, 0.5), (0.26, 0.1), (0.50, 0.1), (0.51, 0.001)],
)
def test_follow_center_line_pays_by_band(from_centre: float, pays: float) -> None:
    # The console's template: bands end at 10%, 25% and 50% of the width, edges included.
    assert load_template("follow_center_line")(road(distance_from_center=from_centre)) == pays


@pytest.mark.parametrize(
    ("from_centre", "wheels_on", "pays"),
    [(0.0, True, 1.0), (0.44, True, 1.0), (0.46, True, 0.001), (0.1, False, 0.001)],
)
def test_stay_inside_borders_pays_the_road_but_not_its_last_5_cm(
    from_centre: float, wheels_on: bool, pays: float
) -> None:
    params = road(distance_from_center=from_centre, all_wheels_on_track=wheels_on)
    assert load_template("stay_inside_borders")(params) == pays


@pytest.mark.parametrize(
    ("from_centre", "steering", "pays"),
    [(0.0, 15.0, 1.0), (0.0, -15.0, 1.0), (0.0, 15.5, 0.8), (0.0, -30.0, 0.8), (0.2, 20.0, 0.4)],
)
def test_prevent_zigzag_cuts_a_fifth_for_steering_past_15_degrees(
    from_centre: float, steering: float, pays: float
) -> None:
    params = road(distance_from_center=from_centre, steering_angle=steering)
    assert load_template("prevent_zigzag")(params) == pytest.approx(pays)


@pytest.mark.parametrize(
    ("gap", "car_across", "box_across", "pays"),
    [
        (0.9, 0.1, 0.19, 5.001),  # 0.001 + the road (1.0) + 4 x full clearance
        (0.8, 0.1, 0.19, 5.001),
        (0.6, 0.1, 0.19, 3.001),  # half clearance
        (0.4, 0.1, 0.19, 1.801),  # a fifth
        (0.2, 0.1, 0.19, 1.005),  # about to hit it
        (0.2, 0.25, -0.19, 5.001),  # well clear of a box in the other lane: it costs nothing
        # Just over the centre line from a box in the other lane is still in its way: the
        # box's crash zone reaches 0.2 m to its side and the car is 0.2 m wide.
        (0.2, 0.05, -0.19, 1.005),
    ],
)
def test_object_avoidance_pays_for_clearance_from_an_object_in_the_cars_way(
    gap: float, car_across: float, box_across: float, pays: float
) -> None:
    params = road(
        x=1.0,
        y=2.0,
        objects_location=[(9.0, 9.0), (1.0 + gap, 2.0)],
        closest_objects=[0, 1],
        objects_left_of_center=[True, box_across > 0],
        objects_distance_from_center=[0.0, abs(box_across)],
        is_left_of_center=car_across > 0,
        distance_from_center=abs(car_across),
    )
    assert load_template("object_avoidance")(params) == pytest.approx(pays)
    off_the_road = {**params, "all_wheels_on_track": False}
    assert load_template("object_avoidance")(off_the_road) == pytest.approx(pays - 0.999)


def test_object_avoidance_without_objects_pays_the_road_and_full_clearance() -> None:
    assert load_template("object_avoidance")(road()) == pytest.approx(5.001)


@pytest.mark.parametrize("name", sorted(TEMPLATES))
def test_templates_read_only_standard_params_keys(name: str) -> None:
    tree = ast.parse(template_source(name))
    keys = {
        node.slice.value
        for node in ast.walk(tree)
        if isinstance(node, ast.Subscript)
        and isinstance(node.value, ast.Name)
        and node.value.id == "params"
        and isinstance(node.slice, ast.Constant)
    }
    assert keys
    assert keys <= set(PARAM_KEYS)


def test_templates_pay_what_the_console_templates_pay_on_the_sample() -> None:
    params = sample_params()  # 5 cm from the centre of a 0.76 m road, steering straight
    assert load_template("follow_center_line")(params) == 1.0
    assert load_template("stay_inside_borders")(params) == 1.0
    assert load_template("prevent_zigzag")(params) == 1.0
    assert load_template("prevent_zigzag")({**params, "steering_angle": -20.0}) == 0.8
    assert load_template("object_avoidance")(params) == pytest.approx(5.001)


def test_object_avoidance_pays_less_with_objects_ahead_in_the_cars_lane() -> None:
    reward = load_template("object_avoidance")
    nothing_near = reward(sample_params())
    far_ahead = reward(sample_params(objects=[(5.5, -LANE), (5.9, -LANE)]))
    close_ahead = reward(sample_params(objects=[(2.7, -LANE), (4.5, -LANE)]))
    assert close_ahead < nothing_near
    assert close_ahead < far_ahead
    assert far_ahead == nothing_near


def test_unknown_template_lists_the_names() -> None:
    with pytest.raises(RewardFunctionError) as caught:
        load_template("go_fast")
    message = str(caught.value)
    assert "go_fast" in message
    for name in TEMPLATES:
        assert name in message


# --- loading failures ------------------------------------------------------------------------
def test_missing_file(tmp_path: Path) -> None:
    path = tmp_path / "nowhere.py"
    message = assert_one_sentence(load_error(path), path, None)
    assert "no such file" in message


def test_folder_instead_of_file(tmp_path: Path) -> None:
    message = assert_one_sentence(load_error(tmp_path), tmp_path, None)
    assert "folder" in message


def test_not_utf8_names_the_line(tmp_path: Path) -> None:
    path = tmp_path / "latin1.py"
    path.write_bytes(b"def reward_function(params):\n    # caf\xe9\n    return 1.0\n")
    message = assert_one_sentence(load_error(path), path, 2)
    assert "UTF-8" in message


def test_byte_order_mark_is_accepted(tmp_path: Path) -> None:
    path = tmp_path / "bom.py"
    path.write_bytes(b"\xef\xbb\xbfdef reward_function(params):\n    return 1.0\n")
    assert load_reward_function(path)(sample_params()) == 1.0


def test_syntax_error_names_its_line(tmp_path: Path) -> None:
    path = write_reward(
        tmp_path,
        """
        def reward_function(params):
            reward = 1.0
            if reward > 0
                reward = 2.0
            return reward
        """,
    )
    message = assert_one_sentence(load_error(path), path, 3)
    assert "syntax error" in message


def test_indentation_error_names_its_line(tmp_path: Path) -> None:
    path = tmp_path / "indent.py"
    path.write_text("def reward_function(params):\nreturn 1.0\n", encoding="utf-8")
    message = assert_one_sentence(load_error(path), path, 2)
    assert "IndentationError" in message


def test_exception_at_import_names_the_line_in_the_file(tmp_path: Path) -> None:
    path = write_reward(
        tmp_path,
        """
        import math

        SCALE = 1 / 0

        def reward_function(params):
            return 1.0
        """,
    )
    message = assert_one_sentence(load_error(path), path, 3)
    assert "ZeroDivisionError: division by zero" in message


def test_missing_module_at_import(tmp_path: Path) -> None:
    path = write_reward(
        tmp_path,
        """
        import math
        import tensorflow_of_dreams

        def reward_function(params):
            return 1.0
        """,
    )
    message = assert_one_sentence(load_error(path), path, 2)
    assert "ModuleNotFoundError" in message
    assert "tensorflow_of_dreams" in message


def test_missing_reward_function(tmp_path: Path) -> None:
    path = write_reward(
        tmp_path,
        """
        def reward(params):
            return 1.0
        """,
    )
    message = assert_one_sentence(load_error(path), path, None)
    assert "must define `def reward_function(params):`" in message


def test_reward_function_that_is_not_callable(tmp_path: Path) -> None:
    path = write_reward(tmp_path, "reward_function = 1.0\n")
    message = assert_one_sentence(load_error(path), path, None)
    assert "float, not a function" in message


def test_reward_function_with_wrong_arguments(tmp_path: Path) -> None:
    path = write_reward(
        tmp_path,
        """
        import math

        def reward_function(params, speed):
            return 1.0
        """,
    )
    message = assert_one_sentence(load_error(path), path, 3)
    assert "exactly one argument" in message


# --- run-time failures -----------------------------------------------------------------------
def test_raise_names_the_line_type_and_message(tmp_path: Path) -> None:
    path = write_reward(
        tmp_path,
        """
        def reward_function(params):
            speed = params["speed"]
            reward = speed / 0
            return reward
        """,
    )
    message = assert_one_sentence(call_error(path), path, 3)
    assert "reward_function raised ZeroDivisionError: float division by zero" in message


def test_raise_in_a_helper_names_the_deepest_line_in_the_file(tmp_path: Path) -> None:
    path = write_reward(
        tmp_path,
        """
        import math

        def lateral(params):
            return math.sqrt(-params["distance_from_center"])

        def reward_function(params):
            return lateral(params)
        """,
    )
    message = assert_one_sentence(call_error(path), path, 4)
    assert "ValueError: math domain error" in message


def test_misspelt_key_names_the_key(tmp_path: Path) -> None:
    path = write_reward(
        tmp_path,
        """
        def reward_function(params):
            return abs(params["steering"])
        """,
    )
    message = assert_one_sentence(call_error(path), path, 2)
    assert "KeyError: 'steering'" in message


def test_long_exception_messages_stay_one_short_line(tmp_path: Path) -> None:
    path = write_reward(
        tmp_path,
        """
        def reward_function(params):
            raise RuntimeError("bad\\n" * 500)
        """,
    )
    message = assert_one_sentence(call_error(path), path, 2)
    assert len(message) < 400


def test_sys_exit_is_reported_not_obeyed(tmp_path: Path) -> None:
    path = write_reward(
        tmp_path,
        """
        import sys

        def reward_function(params):
            sys.exit(3)
        """,
    )
    assert_one_sentence(call_error(path), path, 4)


@pytest.mark.parametrize(
    ("returned", "expected"),
    [
        ("None", "returned None instead of a number"),
        ("'fast'", "returned 'fast' (a str) instead of a number"),
        ("True", "returned True (a bool) instead of a number"),
        ("[1.0]", "(a list) instead of a number"),
        ("float('nan')", "returned NaN"),
        ("float('inf')", "returned inf"),
        ("-math.inf", "returned -inf"),
        ("1e6", "returned 1000000.0, outside DeepRacer's allowed range -100000..100000"),
        ("-250000", "returned -250000.0, outside"),
        ("np.float64(2e5)", "returned 200000.0, outside"),
        ("np.bool_(True)", "(a bool) instead of a number"),
    ],
)
def test_bad_rewards_name_the_return_line(tmp_path: Path, returned: str, expected: str) -> None:
    path = write_reward(
        tmp_path,
        f"""
        import math
        import numpy as np

        def reward_function(params):
            reward = 1.0
            if params["speed"] > 0:
                return {returned}
            return reward
        """,
    )
    message = assert_one_sentence(call_error(path), path, 7)
    assert expected in message


def test_falling_off_the_end_names_the_last_line_run(tmp_path: Path) -> None:
    path = write_reward(
        tmp_path,
        """
        def reward_function(params):
            reward = 1.0
            reward *= 0.5
        """,
    )
    message = assert_one_sentence(call_error(path), path, 3)
    assert "return float(reward)" in message


def test_unreproducible_bad_reward_names_the_def_line(tmp_path: Path) -> None:
    path = write_reward(
        tmp_path,
        """
        calls = []

        def reward_function(params):
            calls.append(1)
            return None if len(calls) == 1 else 1.0
        """,
    )
    assert_one_sentence(call_error(path), path, 3)


@pytest.mark.parametrize(
    "returned",
    [
        "1",
        "0.5",
        "np.float64(0.5)",
        "np.float32(0.5)",
        "np.int64(1)",
        "np.array(0.5)",
        "1e5",
        "-1e5",
    ],
)
def test_numbers_of_any_kind_come_back_as_python_floats(tmp_path: Path, returned: str) -> None:
    path = write_reward(
        tmp_path,
        f"""
        import numpy as np

        def reward_function(params):
            return {returned}
        """,
    )
    value = load_reward_function(path)(sample_params())
    assert type(value) is float
    assert value == float(eval(returned, {"np": np}))


# --- isolation and imports -------------------------------------------------------------------
def test_mutating_params_does_not_change_the_callers_dict(tmp_path: Path) -> None:
    path = write_reward(
        tmp_path,
        """
        def reward_function(params):
            params["x"] = 1000.0
            params["bonus"] = True
            del params["speed"]
            params.pop("waypoints")
            return 1.0
        """,
    )
    params = sample_params()
    before = dict(params)
    reward = load_reward_function(path)
    assert reward(params) == 1.0
    assert params == before
    assert reward(params) == 1.0  # a second call still sees every key


def test_deepracer_libraries_import_in_a_reward_file(tmp_path: Path) -> None:
    path = write_reward(
        tmp_path,
        """
        import math
        import random

        import numpy as np
        import scipy.spatial
        from shapely.geometry import Point, Polygon

        def reward_function(params):
            x, y = params["x"], params["y"]
            road = Polygon([(0, -0.38), (6, -0.38), (6, 0.38), (0, 0.38)])
            inside = road.contains(Point(x, y))
            distance = scipy.spatial.distance.euclidean((x, y), (x, 0.0))
            noise = random.random() * 0.0
            return float(np.clip(math.exp(-distance) * inside + noise, 1e-3, 1.0))
        """,
    )
    value = load_reward_function(path)(sample_params())
    assert value == pytest.approx(math.exp(-0.05))


def test_each_loaded_file_has_its_own_globals(tmp_path: Path) -> None:
    code = """
        counter = [0]

        def reward_function(params):
            counter[0] += 1
            return float(counter[0])
        """
    first = load_reward_function(write_reward(tmp_path, code, "a.py"))
    second = load_reward_function(write_reward(tmp_path, code, "b.py"))
    assert [first(sample_params()) for _ in range(3)] == [1.0, 2.0, 3.0]
    assert second(sample_params()) == 1.0


def test_main_guard_in_the_file_does_not_run(tmp_path: Path) -> None:
    path = write_reward(
        tmp_path,
        """
        def reward_function(params):
            return 1.0

        if __name__ == "__main__":
            raise SystemExit("test code must not run on load")
        """,
    )
    assert load_reward_function(path)(sample_params()) == 1.0


# --- in-memory sources and pickling ----------------------------------------------------------
def test_source_errors_use_the_given_name() -> None:
    source = "def reward_function(params):\n    return params['nope']\n"
    reward = load_reward_source(source, "model-7/reward_function.py")
    with pytest.raises(RewardFunctionError) as caught:
        reward(sample_params())
    assert str(caught.value).startswith("model-7/reward_function.py line 2: ")
    with pytest.raises(RewardFunctionError) as syntax:
        load_reward_source("def reward_function(params):\n    return (\n", "draft.py")
    assert str(syntax.value).startswith("draft.py line 2: ")


def test_reward_function_pickles_as_its_source(tmp_path: Path) -> None:
    reward = load_template("prevent_zigzag")
    clone = pickle.loads(pickle.dumps(reward))
    assert isinstance(clone, RewardFunction)
    assert clone.source == reward.source
    assert clone(sample_params()) == reward(sample_params())


def test_error_pickles_with_its_attributes(tmp_path: Path) -> None:
    error = load_error(tmp_path / "gone.py")
    clone = pickle.loads(pickle.dumps(error))
    assert str(clone) == str(error)
    assert clone.path == error.path
    assert clone.line is None
