"""The reward map: what a reward function pays in every cell of a track, before training."""

from __future__ import annotations

import json
import struct
import zlib
from pathlib import Path

import numpy as np
import pytest

from racer_tui.cli.main import main
from sim.coach.reward_line import load_template
from sim.reward.function import load_reward_source
from sim.reward.map import (
    BORDER_COLOUR,
    CENTRE_COLOUR,
    START_COLOUR,
    MapOptions,
    RewardMap,
    compute_map,
    png_bytes,
)
from sim.tracks.catalog import resolve_track

HAIRPIN = resolve_track("hairpin-circuit")
COARSE = MapOptions(spacing=0.2)


def values_of(reward_map: RewardMap) -> np.ndarray:
    return np.array(
        [[np.nan if v is None else v for v in row] for row in reward_map.values], dtype=float
    )


def test_follow_center_line_pays_its_bands_across_the_road() -> None:
    reward_map = compute_map(load_template("follow_center_line"), HAIRPIN, COARSE)
    values = values_of(reward_map)
    assert set(np.unique(values[~np.isnan(values)])) == {0.001, 0.1, 0.5, 1.0}
    # Every band is there, the road's middle pays most, off the road almost nothing.
    assert np.nanmax(values) == 1.0 and np.nanmin(values) == 0.001
    assert reward_map.failed == [] and reward_map.first_failure is None


def test_each_cell_faces_along_the_track_or_a_fixed_heading() -> None:
    heading = load_reward_source(
        "def reward_function(params):\n    return params['heading']\n", "h"
    )
    fixed = values_of(compute_map(heading, HAIRPIN, MapOptions(spacing=0.2, heading=90.0)))
    assert np.allclose(fixed[~np.isnan(fixed)], 90.0)
    along = values_of(compute_map(heading, HAIRPIN, COARSE))
    assert len(np.unique(np.round(along[~np.isnan(along)]))) > 20  # the road turns


def test_progress_and_steps_are_those_of_a_car_that_drove_there() -> None:
    source = (
        "def reward_function(params):\n"
        "    assert params['steps'] >= 1 and params['speed'] == 3.0\n"
        "    return params['progress']\n"
    )
    reward = load_reward_source(source, "progress.py")
    values = values_of(compute_map(reward, HAIRPIN, MapOptions(spacing=0.2, speed=3.0)))
    shown = values[~np.isnan(values)]
    assert shown.min() >= 0.0 and shown.max() <= 100.0
    assert shown.max() - shown.min() > 90.0  # all the way round


def test_cells_where_the_function_fails_are_marked_and_the_first_is_said() -> None:
    source = (
        "def reward_function(params):\n"
        "    if params['x'] > 4.0:\n"
        "        raise ValueError('east of x=4')\n"
        "    return 1.0\n"
    )
    reward_map = compute_map(load_reward_source(source, "half.py"), HAIRPIN, COARSE)
    assert reward_map.failed and len(reward_map.shown) > 0
    assert reward_map.first_failure is not None
    assert (
        "half.py line 3" in reward_map.first_failure and "first at x=" in reward_map.first_failure
    )


def test_the_png_is_the_grid_at_four_pixels_a_cell() -> None:
    reward_map = compute_map(load_template("stay_inside_borders"), HAIRPIN, COARSE)
    data = png_bytes(reward_map, scale=4)
    assert data.startswith(b"\x89PNG\r\n\x1a\n")
    width, height = struct.unpack(">II", data[16:24])
    assert (width, height) == (4 * len(reward_map.values[0]), 4 * len(reward_map.values))


def decoded(png: bytes) -> np.ndarray:
    """The RGB pixels of one of png_bytes's images (one IDAT, filter 0 on every line)."""
    width, height = struct.unpack(">II", png[16:24])
    start = png.index(b"IDAT") + 4
    length = struct.unpack(">I", png[start - 8 : start - 4])[0]
    raw = zlib.decompress(png[start : start + length])
    lines = np.frombuffer(raw, dtype=np.uint8).reshape(height, 1 + 3 * width)
    assert not lines[:, 0].any()
    return lines[:, 1:].reshape(height, width, 3)


def test_the_png_draws_the_road_its_centre_line_and_its_start_line() -> None:
    reward_map = compute_map(load_template("follow_center_line"), HAIRPIN, COARSE)
    plain = decoded(png_bytes(reward_map))
    drawn = decoded(png_bytes(reward_map, track=HAIRPIN))
    for rgb in (CENTRE_COLOUR, BORDER_COLOUR, START_COLOUR):
        assert not np.all(plain == rgb, axis=2).any()
        assert np.all(drawn == rgb, axis=2).sum() > 3
    # The start line crosses the road at the track's first row.
    row, column = np.argwhere(np.all(drawn == START_COLOUR, axis=2)).mean(axis=0)
    x0, y0 = HAIRPIN.center[0]
    spacing, (ox, oy) = COARSE.spacing, reward_map.origin
    assert abs(column / 4 - ((x0 - ox) / spacing + 0.5)) < 2
    assert abs(row / 4 - (len(reward_map.values) - 0.5 - (y0 - oy) / spacing)) < 2


def test_the_command_draws_writes_json_and_png_and_refuses_bad_input(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert (
        main(["reward", "map", "follow_center_line", "--track", "hairpin-circuit", "--json"]) == 0
    )
    grid = json.loads(capsys.readouterr().out)
    assert grid["track"] == "hairpin-circuit" and grid["max"] == 1.0 and grid["heading"] == "track"
    assert len(grid["values"]) == grid["rows"] and len(grid["values"][0]) == grid["columns"]
    image = tmp_path / "map.png"
    assert (
        main(["reward", "map", "prevent_zigzag", "--track", "hairpin-circuit", "--png", str(image)])
        == 0
    )
    assert image.read_bytes().startswith(b"\x89PNG")
    assert main(["reward", "map", "follow_center_line", "--track", "hairpin-circuit"]) == 0
    drawn = capsys.readouterr().out
    assert "▀" in drawn and "high: 0.001 to 1 on hairpin-circuit" in drawn
    assert main(["reward", "map", "follow_center_line", "--heading", "north"]) == 2
    assert "--heading must be 'track' or fixed:DEGREES" in capsys.readouterr().err
    # A track file of one's own is mapped from that file, not from the catalogue's name.
    mine = tmp_path / "my-hairpin.npy"
    np.save(mine, HAIRPIN.points)
    assert main(["reward", "map", "follow_center_line", "--track", str(mine), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["track"] == "my-hairpin"
    hangs = tmp_path / "hangs.py"
    hangs.write_text("def reward_function(params):\n    while True:\n        pass\n")
    assert main(["reward", "map", str(hangs), "--track", "hairpin-circuit"]) == 2
    assert "line 2: reward_function did not return within 1 s" in capsys.readouterr().err


def test_the_terminal_map_draws_the_road_its_centre_line_and_its_start_over_the_colours() -> None:
    from rich.console import Console

    from racer_tui.text.reward_map import map_text

    reward_map = compute_map(load_template("follow_center_line"), HAIRPIN, COARSE)
    bare = map_text(reward_map, 200, legend=False)
    assert set(bare.plain) <= {"▀", "\n"}
    drawn = map_text(reward_map, 200, legend=False, track=HAIRPIN)
    lines = drawn.plain.splitlines()
    assert len(lines) == len(bare.plain.splitlines())

    def cell(x: float, y: float) -> tuple[int, int]:
        """The text line and column of the map cell holding (x, y); 200 columns: no thinning."""
        column = round((x - reward_map.origin[0]) / COARSE.spacing)
        row = len(reward_map.values) - 1 - round((y - reward_map.origin[1]) / COARSE.spacing)
        return row // 2, column

    # A point far from the start where the road runs up the screen: its centre and its
    # edges are in cells of their own (where it runs across, a text line holds two rows).
    heading = np.diff(HAIRPIN.center, axis=0)
    upright = [
        i
        for i in range(len(heading) // 4, 3 * len(heading) // 4)
        if abs(heading[i, 1]) > 3 * abs(heading[i, 0])
    ]
    middle = upright[len(upright) // 2]
    line, column = cell(*HAIRPIN.center[middle])
    assert lines[line][column] == "·"
    line, column = cell(*HAIRPIN.inner[middle])
    assert lines[line][column] == "•"
    line, column = cell(*HAIRPIN.center[0])
    assert lines[line][column] == "■"
    # The colour stays behind the dot: the centre cell is on the top band, not black.
    offset = sum(len(text) + 1 for text in lines[:line]) + column
    style = drawn.get_style_at_offset(Console(), offset)
    assert style.bgcolor is not None and style.bgcolor.get_truecolor() != (0, 0, 0)
    legend = map_text(reward_map, 200, track=HAIRPIN).plain.splitlines()[-1]
    assert "• road edges" in legend and "· centre line" in legend and "■ start" in legend


def test_the_command_maps_a_garage_models_own_function_on_its_track_at_its_top_speed(
    capsys: pytest.CaptureFixture[str],
) -> None:
    model = ["model", "new", "quick", "--track", "hairpin-circuit", "--max-speed", "3"]
    assert main([*model, "--reward", "prevent_zigzag"]) == 0
    capsys.readouterr()
    assert main(["reward", "map", "--model", "quick", "--spacing", "0.3", "--json"]) == 0
    grid = json.loads(capsys.readouterr().out)
    assert (grid["track"], grid["speed"]) == ("hairpin-circuit", 3.0)
    zigzag = ["reward", "map", "prevent_zigzag", "--track", "hairpin-circuit", "--speed", "3"]
    assert main([*zigzag, "--spacing", "0.3", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["values"] == grid["values"]
    # Given, the speed and track win over the model's.
    given = ["--speed", "1", "--track", "reinvent_base", "--spacing", "0.5", "--json"]
    assert main(["reward", "map", "--model", "quick", *given]) == 0
    grid = json.loads(capsys.readouterr().out)
    assert (grid["track"], grid["speed"]) == ("reinvent_base", 1.0)
    assert main(["reward", "map"]) == 2
    assert "or --model NAME for a garage model's own function" in capsys.readouterr().err
