"""`racer-tui tracks list` and `tracks import`: the catalogs only, no simulator, so they
answer at once."""

from __future__ import annotations

from pathlib import Path

from rich.table import Table
from rich.text import Text

from racer_tui.cli.output import print_json, print_table
from sim.tracks.catalog import TrackInfo, import_track

_GROUPS = (
    ("built-in", "Built-in: racer-tui's designs"),
    ("official", "Official: AWS DeepRacer's tracks"),
    ("imported", "Imported: your tracks"),
)

_DIRECTIONS = {"counter-clockwise": "ccw", "clockwise": "cw", "straight": "-"}


def filtered(infos: list[TrackInfo], search: str | None, kinds: set[str]) -> list[TrackInfo]:
    needle = (search or "").casefold()
    return [
        info
        for info in infos
        if (not kinds or info.kind in kinds)
        and (needle in info.name.casefold() or needle in info.console_name.casefold())
    ]


def list_tracks_table(infos: list[TrackInfo], as_json: bool) -> int:
    if as_json:
        print_json(
            [
                {
                    "name": info.name,
                    "console_name": info.console_name,
                    "kind": info.kind,
                    "builtin": info.builtin,
                    "length_m": info.length_m,
                    "width_m": info.width_m,
                    "direction": info.direction,
                    "release_date": info.release_date,
                    "lappable": info.lappable,
                    "description": info.description,
                }
                for info in infos
            ]
        )
        return 0
    if not infos:
        print("No track matches; `racer-tui tracks list` shows them all.")
        return 0
    # One table per kind, one line per track, so 132 tracks read well at 80 columns.
    for kind, heading in _GROUPS:
        group = [info for info in infos if info.kind == kind]
        if group:
            print_table(_kind_table(f"{heading} ({len(group)})", group, kind))
    print("Give a track by its name or console name, e.g. --track reinvent_base.")
    return 0


def _kind_table(title: str, infos: list[TrackInfo], kind: str) -> Table:
    table = Table(
        title=title, title_justify="left", box=None, pad_edge=False, header_style="bold underline"
    )
    table.add_column("name", no_wrap=True, min_width=max(len(info.name) for info in infos))
    # What the console calls it; racer-tui's and your own tracks are not in the console,
    # and the column says what it holds for them: their description.
    second = "console name" if kind == "official" else "description"
    table.add_column(second, no_wrap=True, overflow="ellipsis", max_width=22)
    table.add_column("len m", justify="right", no_wrap=True)
    table.add_column("wide", justify="right", no_wrap=True)
    table.add_column("dir", no_wrap=True)
    table.add_column("released", no_wrap=True)  # the month: the day is in --json
    for info in infos:
        # Names and descriptions are user data: Text() keeps them plain, never markup.
        table.add_row(
            Text(info.name),
            Text(_console_or_description(info)),
            f"{info.length_m:.2f}",
            f"{info.width_m:.2f}",
            _DIRECTIONS.get(info.direction, info.direction),
            info.release_date[:7] or "-",
        )
    return table


def _console_or_description(info: TrackInfo) -> str:
    if info.kind == "official":
        return info.console_name or "(not in the console)"
    return info.description or "-"


def import_track_file(file: Path, name: str | None, reverse: bool, description: str) -> int:
    info = import_track(file, name, reverse=reverse, description=description)
    title = (
        f"Imported {info.name}"
        if info.kind == "imported"
        else f"{info.title} is already here as {_a(info.kind)} track; nothing was copied"
    )
    print_table(one_track_table(title, info.length_m, info.width_m, info.direction))
    return 0


def _a(kind: str) -> str:
    return f"an {kind}" if kind[0] in "aeiou" else f"a {kind}"


def one_track_table(title: str, length: float, width: float, direction: str) -> Table:
    table = Table(title=Text(title))
    table.add_column("length")
    table.add_column("width")
    table.add_column("direction")
    table.add_row(f"{length:.2f} m", f"{width:.3f} m", direction)
    return table
