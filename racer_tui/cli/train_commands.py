"""`racer-tui train` and `racer-tui evaluate`.

`train` starts the training child process and draws its JSON event stream as a rich
progress bar with live figures (or passes the events through with `--json`), keeping the
events in the model's training log as the app does, so an open app follows the run. Ctrl+C asks
the child to stop: it saves a checkpoint and the command prints how the run ended; a
second Ctrl+C kills it (the folder stays consistent; the work since the last checkpoint
is lost). `evaluate` runs DeepRacer-style trials and prints the console's table.
Neither imports torch in this process: the child trains, and evaluation loads the
policy only when it runs.
"""

from __future__ import annotations

import argparse
import math
import signal
import sys
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from types import FrameType
from typing import Any

from rich.console import Console, Group
from rich.live import Live
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table
from rich.text import Text

from racer_tui.cli.output import print_json, print_table
from sim.foundation.remedies import RemedyError
from sim.garage.folder import ModelError, open_model
from sim.reward.limit import DEFAULT_SECONDS as DEFAULT_REWARD_SECONDS
from sim.reward.sandbox import DEFAULT_MEMORY_MB, check_memory_mb
from sim.tracks.catalog import resolve_track
from sim.training import events
from sim.training.algorithms import check_trainable
from sim.training.config import training_env_config
from sim.training.evaluation import DEFAULT_TRIALS, MAX_TRIALS, EvaluationReport, evaluate_model
from sim.training.launcher import TrainingProcess
from sim.training.opponents import check_opponents, opponent_spec

NAMES = ("train", "evaluate")


class TrainingFailedError(RemedyError):
    """The training child ended with `failed`; the message is its sentence."""


def register(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    train = commands.add_parser("train", help="train a model (PPO) with live figures")
    train.add_argument("name", help="model name or folder")
    train.add_argument(
        "--minutes", type=float, help="time limit (default: the model's training_params.yaml)"
    )
    train.add_argument(
        "--reward-seconds",
        type=float,
        default=DEFAULT_REWARD_SECONDS,
        help="time limit on each call of the reward function "
        f"(default {DEFAULT_REWARD_SECONDS:g} s)",
    )
    train.add_argument(
        "--reward-memory-mb",
        type=float,
        default=DEFAULT_MEMORY_MB,
        help="memory the reward function may use in each training process "
        f"(default {DEFAULT_MEMORY_MB} MB)",
    )
    train.add_argument(
        "--processes",
        type=int,
        help="processes stepping the cars, each with a fleet of its own, and threads of the "
        "learning step (default: the cores less one, left for the app, at most 8)",
    )
    train.add_argument(
        "--opponent",
        action="append",
        default=[],
        metavar="CAR",
        help="train among other racers' cars: a garage model, a .racer-bundle file or "
        "reference, on the track with every training car (repeat for up to 5); instead of "
        "a head-to-bot model's bot cars",
    )
    train.add_argument("--json", action="store_true", help="stream the JSON events instead")

    evaluate = commands.add_parser("evaluate", help="time-trial evaluation, one lap per trial")
    evaluate.add_argument("name", help="model name or folder")
    evaluate.add_argument("--track", help="track name or .npy file (default: the model's)")
    evaluate.add_argument(
        "--trials", type=int, default=DEFAULT_TRIALS, help=f"default {DEFAULT_TRIALS}"
    )
    evaluate.add_argument("--json", action="store_true", help="print JSON")


def run(args: argparse.Namespace) -> int:
    if args.command == "train":
        return _train(args)
    return _evaluate(args)


# --- train -----------------------------------------------------------------------------------


@dataclass
class Figures:
    """What the live view shows, folded from the event stream."""

    model: str = ""
    track: str = ""
    minutes: float = 0.0
    elapsed: float = 0.0
    started: events.Started | None = None
    update: events.Update | None = None
    evaluation: events.Evaluation | None = None
    system: events.System | None = None
    best_lap: float | None = None
    best_progress: float = 0.0
    last_episode: events.Episode | None = None
    notes: list[str] = field(default_factory=list)

    def fold(self, event: events.Event) -> None:
        self.elapsed = max(self.elapsed, event.elapsed)
        if isinstance(event, events.Started):
            self.started = event
            self.model, self.track, self.minutes = event.model, event.track, event.max_minutes
        elif isinstance(event, events.Update):
            self.update = event
        elif isinstance(event, events.Evaluation):
            self.evaluation = event
            self.best_progress = max(self.best_progress, event.mean_progress)
            if event.best_lap is not None and (
                self.best_lap is None or event.best_lap < self.best_lap
            ):
                self.best_lap = event.best_lap
        elif isinstance(event, events.System):
            self.system = event
        elif isinstance(event, events.Episode):
            self.last_episode = event


def _figures_table(figures: Figures) -> Table:
    table = Table.grid(padding=(0, 2))
    for _ in range(4):
        table.add_column()
    update, evaluation, system = figures.update, figures.evaluation, figures.system

    def number(value: float | None, fmt: str) -> str:
        return "-" if value is None or not math.isfinite(value) else format(value, fmt)

    rows = [
        (
            "steps",
            number(update.total_steps if update else None, ",.0f"),
            "steps/s",
            number(update.steps_per_second if update else None, ",.0f"),
        ),
        (
            "episodes",
            number(update.episodes if update else None, ",.0f"),
            "iteration",
            number(update.iteration if update else None, ".0f"),
        ),
        (
            "mean reward",
            number(update.mean_reward if update else None, ".2f"),
            "mean progress",
            number(update.mean_progress if update else None, ".1f") + " %",
        ),
        (
            "entropy",
            number(update.entropy if update else None, ".3f"),
            "approx KL",
            number(update.approx_kl if update else None, ".4f"),
        ),
        (
            "policy loss",
            number(update.policy_loss if update else None, ".4f"),
            "value loss",
            number(update.value_loss if update else None, ".4f"),
        ),
        (
            "evaluation",
            f"{evaluation.laps}/{evaluation.trials} laps, {evaluation.mean_progress:.1f} %"
            if evaluation
            else "-",
            "best lap",
            number(figures.best_lap, ".3f") + " s",
        ),
        (
            "CPU",
            number(system.cpu_percent if system else None, ".0f") + " %",
            "memory",
            number(system.rss_mb if system else None, ".0f") + " MB",
        ),
        ("cars", _fleet(figures.started), *_against(figures.started)),
    ]
    for label, value, label2, value2 in rows:
        table.add_row(
            Text(label, style="dim"), Text(value), Text(label2, style="dim"), Text(value2)
        )
    return table


def _fleet(started: events.Started | None) -> str:
    if started is None:
        return "-"
    processes = started.processes
    return f"{started.cars} in {processes} process{'' if processes == 1 else 'es'}"


def _against(started: events.Started | None) -> tuple[str, str]:
    """The opponents on the track with every training car, when there are any."""
    if started is None or not started.opponents:
        return "", ""
    return "against", ", ".join(started.opponents)


class _Interrupts:
    """Ctrl+C while training: first SIGTERM to the child (it checkpoints), then SIGKILL."""

    def __init__(self, process: Any) -> None:
        self.process = process
        self.count = 0
        self.previous: Any = None

    def __enter__(self) -> _Interrupts:
        self.previous = signal.signal(signal.SIGINT, self._handle)
        return self

    def __exit__(self, *exc: object) -> None:
        signal.signal(signal.SIGINT, self.previous)

    def _handle(self, signum: int, frame: FrameType | None) -> None:
        del signum, frame
        self.count += 1
        if self.count == 1:
            self.process.stop()
        else:
            self.process.kill()


def _train(args: argparse.Namespace) -> int:

    if args.minutes is not None and not (math.isfinite(args.minutes) and args.minutes > 0):
        raise ModelError(f"--minutes must be more than 0, not {args.minutes:g}.")
    seconds = args.reward_seconds
    if not (math.isfinite(seconds) and seconds > 0):
        raise ModelError(f"--reward-seconds must be more than 0, not {seconds:g}.")
    try:
        memory_mb = check_memory_mb(args.reward_memory_mb)
    except ValueError as error:
        raise ModelError(f"--reward-memory-mb: {error}.") from None
    if args.processes is not None and args.processes < 1:
        raise ModelError(f"--processes must be 1 or more, not {args.processes}.")
    folder = open_model(args.name)
    problem = folder.car_archive_problem("train")
    if problem is not None:
        raise ModelError(problem)
    check_trainable(folder.metadata())  # before a child process starts
    if args.opponent:  # what the child would refuse, said before it starts
        check_opponents(training_env_config(folder), args.opponent)
    if folder.is_training() or folder.training_locked():
        raise ModelError(
            f"model {folder.name!r} is already training in another process; stop that one first."
        )
    log = folder.training_log
    log.write_bytes(b"")  # a new run, a new log, as the app starts one
    minutes = args.minutes if args.minutes is not None else folder.training_params().max_minutes
    # The child dies with this command (a killed command leaves no training running at
    # full CPU), and this command stops it if it ever runs well past its budget.
    extra = ["--die-with-parent", "--reward-seconds", repr(float(seconds))]
    extra += ["--reward-memory-mb", str(memory_mb)]
    if args.processes is not None:
        extra += ["--processes", str(args.processes)]
    for opponent in args.opponent:
        extra += ["--opponent", opponent_spec(opponent)]
    process = TrainingProcess.start(
        str(folder.path), args.minutes, extra, budget_seconds=minutes * 60.0
    )
    with _Interrupts(process) as interrupts:
        show = _stream_json if args.json else _show_live
        ended = show(_logged(process.events(), log), folder.name, interrupts)
    if ended.kind == "failed":
        raise TrainingFailedError(ended.message)
    return 0


def _logged(stream: Iterator[events.Event], log: Path) -> Iterator[events.Event]:
    """The run's events, each also appended to the model's training log as it comes: the
    app follows a run started here from that log, with all its figures."""
    with log.open("ab") as out:
        for event in stream:
            out.write((events.encode(event) + "\n").encode("utf-8"))
            out.flush()
            yield event


def _stream_json(
    stream: Iterator[events.Event], name: str, interrupts: _Interrupts
) -> events.Ended:
    del name, interrupts
    ended: events.Ended | None = None
    for event in stream:
        sys.stdout.write(events.encode(event) + "\n")
        sys.stdout.flush()
        if isinstance(event, events.Ended):
            ended = event
    assert ended is not None  # the launcher always ends with an Ended event
    return ended


def _show_live(stream: Iterator[events.Event], name: str, interrupts: _Interrupts) -> events.Ended:
    console = Console(stderr=False)
    if not console.is_terminal:  # piped: a live view draws only its last frame, at the end
        return _show_lines(console, stream, name)
    figures = Figures(model=name)
    progress = Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        TextColumn("{task.percentage:>3.0f}%"),
        TimeElapsedColumn(),
        console=console,
    )
    task = progress.add_task(f"training {name}", total=1.0)
    ended: events.Ended | None = None
    with Live(
        Group(progress, _figures_table(figures)), console=console, refresh_per_second=4
    ) as live:
        for event in stream:
            figures.fold(event)
            if isinstance(event, events.Ended):
                ended = event
                continue
            total = max(figures.minutes * 60.0, 1e-9)
            description = (
                f"stopping {name} (saving a checkpoint)" if interrupts.count else f"training {name}"
            )
            progress.update(
                task, completed=min(figures.elapsed / total, 1.0), description=description
            )
            live.update(Group(progress, _figures_table(figures)))
    assert ended is not None
    _print_ending(console, ended)
    return ended


def _show_lines(console: Console, stream: Iterator[events.Event], name: str) -> events.Ended:
    """One line per policy update, each flushed as it is printed, for a program reading
    the output as the run goes (`racer-tui train ada | tee train.txt`)."""
    figures = Figures(model=name)
    ended: events.Ended | None = None
    for event in stream:
        figures.fold(event)
        if isinstance(event, events.Ended):
            ended = event
        elif isinstance(event, events.Update):
            print(
                f"{name} {figures.elapsed:.0f} s of {figures.minutes * 60:.0f} s: iteration "
                f"{event.iteration}, {event.total_steps:,} steps, {event.episodes:,} episodes, "
                f"mean progress {event.mean_progress:.1f} %, best evaluation "
                f"{figures.best_progress:.1f} %",
                flush=True,
            )
    assert ended is not None
    _print_ending(console, ended)
    return ended


def _print_ending(console: Console, ended: events.Ended) -> None:
    if ended.kind == "failed":
        return  # the CLI prints the failure as one sentence on stderr
    lap = "-" if ended.best_lap is None else f"{ended.best_lap:.3f} s"
    line = Text(
        f"{ended.kind}: {ended.message}. {ended.total_steps:,} steps, {ended.episodes:,} "
        f"episodes, best evaluation progress {ended.best_progress:.1f} %, best mean lap {lap}."
    )
    console.print(line)


# --- evaluate ----------------------------------------------------------------------------------


def _evaluate(args: argparse.Namespace) -> int:

    if not 1 <= args.trials <= MAX_TRIALS:
        raise ModelError(f"--trials must be between 1 and {MAX_TRIALS}, not {args.trials}.")
    folder = open_model(args.name)
    track = resolve_track(args.track) if args.track else None
    report = evaluate_model(folder, track=track, trials=args.trials)
    if args.json:
        print_json(_report_json(folder.name, report))
    else:
        print_table(_report_table(folder.name, report))
    return 0


def lap_clock(seconds: float) -> str:
    """DeepRacer console style: 00:00:16.468."""
    whole = int(seconds)
    return f"{whole // 3600:02d}:{whole // 60 % 60:02d}:{seconds % 60:06.3f}"


def _report_table(name: str, report: EvaluationReport) -> Table:
    table = Table(title=Text(f"Evaluation of {name} on {report.track}"))
    table.add_column("Trial", justify="right")
    table.add_column("Time")
    table.add_column("Trial results (% track completed)", justify="right")
    table.add_column("Status")
    for trial in report.trials:
        table.add_row(
            str(trial.trial),
            lap_clock(trial.seconds),
            f"{trial.progress:.0f}%",
            Text(trial.status),
        )
    best = "-" if report.best_lap is None else lap_clock(report.best_lap)
    where = "" if report.metrics_file is None else f"; written to {report.metrics_file.name}"
    off_tracks = sum(trial.off_tracks for trial in report.trials)
    penalty = sum(trial.penalty_seconds for trial in report.trials)
    # The console's off-track columns, in a line: the table already fills 80 columns.
    offs = f", {off_tracks} off-tracks (+{penalty:g} s)" if off_tracks else ""
    table.caption = f"{report.laps}/{len(report.trials)} laps{offs}, best lap {best}{where}"
    return table


def _report_json(name: str, report: EvaluationReport) -> dict[str, Any]:
    return {
        "model": name,
        "track": report.track,
        "laps": report.laps,
        "best_lap_seconds": report.best_lap,
        "mean_progress": round(report.mean_progress, 2),
        "metrics_file": None if report.metrics_file is None else str(report.metrics_file),
        "trials": [
            {
                "trial": trial.trial,
                "time_seconds": round(trial.seconds, 3),
                "completion_percentage": round(trial.progress, 2),
                "status": trial.status,
                "off_tracks": trial.off_tracks,
                "penalty_seconds": round(trial.penalty_seconds, 3),
            }
            for trial in report.trials
        ],
    }
