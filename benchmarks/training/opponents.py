"""Does training among a rival's model make a model beat it? Issue 46's check of training
against an opponent (`racer-tui train MODEL --opponent CAR`).

    python -m benchmarks.training.opponents [--seeds 10] [--first-seed 1] [--minutes 3]
                                            [--laps 3] [--track reinvent_base] [--json]
                                            [--keep FOLDER] [--reward racing_line]

For each seed S, two fresh models of one spec (vector state and sector lidar, 10 actions
from the racing line, one reward: `--reward`, a template or a file), each trained for the
same minutes on one core with training seed S:
- "alone-S" trains alone on the track: the rival's published model;
- "among-S" trains with alone-S on the track as its opponent, as a racer preparing for a
  bracket against it would.
Trainings run two at a time on a machine with two cores or more. Then among-S and alone-S
race head-to-head (N laps, the head-to-head preset's penalties) twice, each car on pole
once. The figure is how many of those races among-S finishes ahead of alone-S, per seed and
in all. The issue's target, printed beside it: ahead more often than not over the seeds.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any

from benchmarks.training.runs import (
    Trained,
    bench_home,
    print_result,
    train_model,
    train_side_by_side,
)
from sim.foundation.remedies import RemedyError

SENSORS = ("vector", "sector_lidar")
TARGET = "among-S ahead of alone-S in more than half of the races"


@dataclass
class Seed:
    seed: int
    alone: Trained = field(default_factory=Trained)
    among: Trained = field(default_factory=Trained)
    # Per race: (the car on pole, the winner), as "alone" or "among".
    races: list[tuple[str, str]] = field(default_factory=list)

    @property
    def alone_name(self) -> str:
        return f"alone-{self.seed}"

    @property
    def among_name(self) -> str:
        return f"among-{self.seed}"

    @property
    def among_ahead(self) -> int:
        return sum(winner == "among" for _pole, winner in self.races)


def _train_alone(item: Seed, minutes: float) -> None:
    item.alone = train_model(item.alone_name, minutes, _options(item.seed))


def _train_among(item: Seed, minutes: float) -> None:
    extra = [*_options(item.seed), "--opponent", item.alone_name]
    item.among = train_model(item.among_name, minutes, extra)


def _options(seed: int) -> list[str]:
    return ["--processes", "1", "--seed", str(seed)]


def _race(item: Seed, track_name: str, laps: int) -> None:
    from sim.race.head_to_head import Entry, run_head_to_head
    from sim.race.rules import HEAD_TO_HEAD_RULES
    from sim.tracks.catalog import resolve_track
    from sim.training.drivers import resolve_driver

    track = resolve_track(track_name)
    rules = replace(HEAD_TO_HEAD_RULES, lap_count=laps)
    cars = {
        "alone": resolve_driver(item.alone_name, track),
        "among": resolve_driver(item.among_name, track),
    }
    for grid in (("alone", "among"), ("among", "alone")):
        entries = [Entry(name, cars[name]) for name in grid]
        result = run_head_to_head(track, rules, entries, seed=item.seed)
        item.races.append((grid[0], grid[result.winner.car]))


def new_pairs(seeds: Sequence[int], track_name: str, reward: str) -> list[Seed]:
    """alone-S and among-S, fresh, for each seed (a reward or track the garage cannot take
    raises its RemedyError here, before any training)."""
    from sim.garage.options import new_model

    items = [Seed(seed) for seed in seeds]
    for item in items:
        for name in (item.alone_name, item.among_name):
            new_model(
                name,
                track=track_name,
                sensors=SENSORS,
                actions_from_line=10,
                reward=reward,
            )
    return items


def run(
    items: Sequence[Seed], minutes: float, track_name: str, laps: int, reward: str
) -> dict[str, Any]:
    # The rivals first: each among-S trains against its finished alone-S.
    parallel = train_side_by_side(items, lambda item: _train_alone(item, minutes))
    train_side_by_side(items, lambda item: _train_among(item, minutes))
    for item in items:
        _race(item, track_name, laps)
    races = sum(len(item.races) for item in items)
    ahead = sum(item.among_ahead for item in items)
    return {
        "track": track_name,
        "minutes": minutes,
        "laps": laps,
        "reward": reward,
        "side_by_side": parallel,
        "seeds": [
            {
                "seed": item.seed,
                "alone_steps": item.alone.steps,
                "among_steps": item.among.steps,
                "ended": [item.alone.ended, item.among.ended],
                "races": [{"pole": pole, "winner": winner} for pole, winner in item.races],
                "among_ahead": item.among_ahead,
            }
            for item in items
        ],
        "among_ahead": ahead,
        "races": races,
        "target": TARGET,
        "met": ahead * 2 > races,
    }


def _print(result: dict[str, Any]) -> None:
    from rich.console import Console
    from rich.table import Table

    table = Table(
        title=f"{result['minutes']:g} minutes of training each on {result['track']}, "
        f"races of {result['laps']} laps"
    )
    for column in ("seed", "alone steps", "among steps", "pole alone", "pole among"):
        table.add_column(column, justify="right")
    for row in result["seeds"]:
        winners = {race["pole"]: race["winner"] for race in row["races"]}
        table.add_row(
            str(row["seed"]),
            f"{row['alone_steps']:,}",
            f"{row['among_steps']:,}",
            f"{winners.get('alone', '-')} won",
            f"{winners.get('among', '-')} won",
        )
    console = Console()
    console.print(table)
    console.print(
        f"among-S ahead in {result['among_ahead']} of {result['races']} races; "
        f"target: {result['target']} ({'met' if result['met'] else 'not met'})"
    )


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument(
        "--first-seed", type=int, default=1, help="seeds run from it on (more evidence: 11)"
    )
    parser.add_argument("--minutes", type=float, default=3.0)
    parser.add_argument("--laps", type=int, default=3)
    parser.add_argument("--track", default="reinvent_base")
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--keep", help="keep the models in this data folder")
    parser.add_argument(
        "--reward", default="racing_line", help="both models' reward: a template or a file"
    )
    args = parser.parse_args(argv)
    with bench_home(args.keep):
        seeds = range(args.first_seed, args.first_seed + args.seeds)
        try:
            items = new_pairs(seeds, args.track, args.reward)
        except RemedyError as error:  # a reward or track it cannot take: said in a sentence
            parser.error(str(error))
        result = run(items, args.minutes, args.track, args.laps, args.reward)
    print_result(result, args.json, _print)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
