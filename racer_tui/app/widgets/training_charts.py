"""The training dashboard: what a racer watches while a model trains.

`TrainingFigures` folds a training's own files into plain lists and counters: the rows of
its TrainingMetrics.json (every car's episodes and the evaluations between iterations, read
as the trainer appends them), its run history (updates and system readings, the same
events the child streams) and its state file's last word. Live and after a restart the same
rows go through the same fold, so a figure shown while the model trains is the figure shown
the next day. The child's `episode` events (one car's sample of what the metrics file
holds) and `evaluation` events (rows of it again) are not folded. It knows nothing of Textual, so
tests can check it directly. `TrainingCharts` draws one model's figures: six `LineChart`s
(each repaints at its own calm rate) and a few lines of counters, refreshed at 2 Hz however
fast the events arrive.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import ClassVar

from rich.console import Group, RenderableType
from rich.progress_bar import ProgressBar
from rich.table import Table
from rich.text import Text
from textual.app import ComposeResult
from textual.containers import Grid, Vertical
from textual.widgets import Static

from racer_tui.app.jobs import Job, JobState, sentence
from racer_tui.app.widgets.chart import MAX_POINTS, LineChart
from racer_tui.app.widgets.job_line import local_clock
from racer_tui.app.words import said_in_app
from racer_tui.text.clocks import elapsed_text as clock
from sim.deepracer.files import TrainingEpisode, TrainingMetrics
from sim.foundation.plural import counted
from sim.training import events

MEAN_WINDOW = 20  # episodes in the running means, like the DeepRacer console's
COMPLETION_WINDOW = 50  # episodes in the lap completion rate
STATUS_REFRESH_HZ = 2.0
LAP_COMPLETE = "Lap complete"


@dataclass(frozen=True)
class EvaluationFigures:
    """The latest evaluation between iterations, from its TrainingMetrics rows."""

    trials: int
    laps: int
    mean_progress: float
    best_lap: float | None


@dataclass(frozen=True)
class MetricsMark:
    """How far a TrainingMetrics file has been read: its inode (a file replaced whole is
    read again from the start) and the byte offset to continue from (None: a layout with
    no place to continue from, read whole once)."""

    inode: int | None = None
    offset: int | None = 0


@dataclass
class TrainingFigures:
    """One model's training figures: its metrics rows, run history and ending."""

    rewards: list[float] = field(default_factory=list)
    progress: list[float] = field(default_factory=list)
    lap_times: list[float] = field(default_factory=list)
    entropy: list[float] = field(default_factory=list)
    steps_per_second: list[float] = field(default_factory=list)
    cpu: list[float] = field(default_factory=list)
    statuses: Counter[str] = field(default_factory=Counter)
    completed: list[bool] = field(default_factory=list)  # per episode: lap complete?
    started: events.Started | None = None
    update: events.Update | None = None
    evaluation: EvaluationFigures | None = None
    system: events.System | None = None
    ended: events.Ended | None = None
    ended_at: float | None = None  # wall time of the end, when known
    ended_before: bool = False  # `ended` is the last run before this session's (its file)
    is_starting: bool = False  # a run was started and has not said so yet
    elapsed: float = 0.0
    version: int = 0  # bumped by every change, so views redraw only when needed
    metrics_mark: MetricsMark = field(default_factory=MetricsMark)
    _evaluation_rows: list[TrainingEpisode] = field(default_factory=list)
    _evaluating: bool = False  # the last row read was an evaluation's

    @classmethod
    def from_metrics(
        cls,
        metrics: TrainingMetrics | None,
        history: Sequence[events.Update | events.System] = (),
    ) -> TrainingFigures:
        """A model's training so far, every run of it: episodes from its TrainingMetrics,
        entropy, steps per second and CPU from its run history (`sim.training.run_history`;
        DeepRacer's file does not keep those)."""
        figures = cls()
        for event in history:
            figures.fold(event)
        figures.fold_rows(metrics.episodes if metrics is not None else ())
        figures.version += 1
        return figures

    def fold_rows(self, rows: Sequence[TrainingEpisode]) -> None:
        """Add TrainingMetrics rows, in the file's order: training episodes of every car,
        and the evaluations between iterations (each a run of rows back to back)."""
        for row in rows:
            if row.phase == "evaluation":
                self._evaluation_row(row)
                continue
            self._evaluating = False
            if row.phase != "training":
                continue
            lap = (
                row.elapsed_time_in_milliseconds / 1000.0
                if row.episode_status == LAP_COMPLETE
                else None
            )
            self._episode(row.reward_score, row.completion_percentage, lap, row.episode_status)
        if rows:
            self.version += 1

    def _evaluation_row(self, row: TrainingEpisode) -> None:
        group = self._evaluation_rows
        # simapp's evaluation rows follow each other from the clock: one that does not start
        # where the last ended begins the next evaluation.
        if not (self._evaluating and group and row.start_time == group[-1].metric_time):
            group = self._evaluation_rows = []
        group.append(row)
        self._evaluating = True
        laps = [
            r.elapsed_time_in_milliseconds / 1000.0
            for r in group
            if r.episode_status == LAP_COMPLETE
        ]
        self.evaluation = EvaluationFigures(
            trials=len(group),
            laps=len(laps),
            mean_progress=sum(r.completion_percentage for r in group) / len(group),
            best_lap=min(laps) if laps else None,
        )

    def take_rows(self, rows: Sequence[TrainingEpisode], mark: MetricsMark, fresh: bool) -> None:
        """New rows read from the metrics file up to `mark`; `fresh`: the file was replaced
        whole, and `rows` are all of it."""
        if fresh:
            self.clear_rows()
        self.fold_rows(rows)
        self.metrics_mark = mark

    def clear_rows(self) -> None:
        """Forget what came from the metrics file (it was replaced whole: read it again)."""
        self.rewards, self.progress, self.lap_times = [], [], []
        self.completed, self.statuses = [], Counter()
        self.evaluation, self._evaluation_rows, self._evaluating = None, [], False
        self.metrics_mark = MetricsMark()
        self.version += 1

    def starting(self) -> None:
        """A new run is on its way: the last one's ending is no longer the news, and its
        clock and budget are not the new run's (they come with its `started` event)."""
        self.ended, self.ended_at, self.ended_before = None, None, False
        self.started, self.elapsed = None, 0.0
        self.is_starting = True
        self.version += 1

    def heard_at(self, elapsed: float) -> None:
        """The run was last heard of `elapsed` seconds in (an event whose figures are
        already counted)."""
        if elapsed > self.elapsed:
            self.elapsed = elapsed
            self.version += 1

    def fold(self, event: events.Event) -> None:
        """Fold one event of the child's stream. Episodes and evaluations are not taken
        from it (one car's sample): they come from the metrics file (`fold_rows`)."""
        self.elapsed = max(self.elapsed, event.elapsed)
        if isinstance(event, events.Started):
            # A new run's clock starts again (the history holds the earlier runs' times).
            self.started, self.ended, self.elapsed = event, None, event.elapsed
            self.ended_at, self.ended_before, self.is_starting = None, False, False
        elif isinstance(event, events.Update):
            self.update = event
            _append(self.entropy, event.entropy)
            _append(self.steps_per_second, event.steps_per_second)
        elif isinstance(event, events.System):
            self.system = event
            _append(self.cpu, event.cpu_percent)
        elif isinstance(event, events.Ended):
            self.ended, self.ended_before, self.is_starting = event, False, False
        self.version += 1

    def _episode(self, reward: float, progress: float, lap: float | None, status: str) -> None:
        _append(self.rewards, reward)
        _append(self.progress, progress)
        _append(self.completed, lap is not None)
        if lap is not None:
            _append(self.lap_times, lap)
        self.statuses[status] += 1

    @property
    def episodes(self) -> int:
        return sum(self.statuses.values())

    @property
    def completion_rate(self) -> float | None:
        """Percent of the last COMPLETION_WINDOW episodes that completed the lap."""
        recent = self.completed[-COMPLETION_WINDOW:]
        return 100.0 * sum(recent) / len(recent) if recent else None


def _append(values: list[float] | list[bool], value: float | bool) -> None:
    values.append(value)  # type: ignore[arg-type]
    if len(values) > MAX_POINTS * 2:
        del values[:-MAX_POINTS]


def _number(value: float | None, fmt: str, unit: str = "") -> str:
    if value is None or not math.isfinite(value):
        return "-"
    return format(value, fmt) + unit


# How a run's ending reads, for each way it can end (events.ENDINGS).
_ENDED_STATES = {
    "finished": JobState.DONE,
    "stopped": JobState.STOPPED,
    "failed": JobState.FAILED,
}
TRAIN_AGAIN = "Press t to train again."


def training_job(figures: TrainingFigures, model: str = "") -> Job:
    """The run as the app's one status model for long jobs (`racer_tui.app.jobs`): running
    with its clock against its budget (`done` and `total` in seconds), or how and when it
    ended, a failure with its reason and the key that starts another run."""
    what = f"Training {model}".strip()
    ended, started = figures.ended, figures.started
    if ended is not None:
        state = _ENDED_STATES.get(ended.kind, JobState.FAILED)
        failed = state is JobState.FAILED
        return Job(
            what,
            state,
            at=figures.ended_at or 0.0,
            done=ended.elapsed,
            outcome=said_in_app(ended.message, ended.problem, ended.remedy) if failed else "",
            fix=TRAIN_AGAIN if failed else "",
        )
    if started is None:
        return Job(what, JobState.RUNNING if figures.is_starting else JobState.IDLE)
    budget = started.max_minutes * 60.0
    return Job(what, JobState.RUNNING, done=figures.elapsed, total=budget if budget > 0 else None)


BAR_WIDTH = 48  # below this the run's clock reads as words: the bar would cut its figures


def run_line(figures: TrainingFigures, model: str = "", width: int = 0) -> RenderableType:
    """Whose figures these are, and where the run is: its clock against the time budget
    (DeepRacer's stop condition, so the time left is exact), or how it ended."""
    job = training_job(figures, model)
    name = Text.assemble((model, "bold"), ": ") if model else Text()
    if job.state is JobState.IDLE:
        return name + Text("not training now", style="dim")
    if job.state is not JobState.RUNNING:  # this session's run, or the last one before it
        assert figures.ended is not None
        last = "last run " if figures.ended_before else ""
        when = f" at {local_clock(job.at)}" if job.at else ""
        took = f" after {clock(job.done)}" if job.done > 0 or not last else ""
        ending = name + Text(f"{last}{figures.ended.kind}{when}{took}", style="dim")
        if job.state is JobState.FAILED:  # why, and what to do: not only in a toast
            ending += Text(f": {sentence(job.outcome)} {job.fix}".rstrip(), style="red")
        return ending
    if figures.started is None:
        return name + Text("starting…", style="dim")
    if job.total is None:
        return name + Text(f"training {clock(job.done)}")
    if 0 < width < BAR_WIDTH:  # wraps whole words instead of cutting a time
        left = clock(job.total - job.done)
        return name + Text(f"training {clock(job.done)} of {clock(job.total)}, {left} left")
    line = Table.grid(expand=True)
    line.add_column(no_wrap=True)
    line.add_column(ratio=1)
    line.add_column(no_wrap=True)
    line.add_row(
        name + Text(f"training {clock(job.done)} of {clock(job.total)} "),
        ProgressBar(total=job.total, completed=min(job.done, job.total)),
        Text(f" {clock(job.total - job.done)} left"),
    )
    return line


def figures_lines(figures: TrainingFigures, model: str = "", width: int = 0) -> Group:
    """The model and its run's clock, then the counters above the charts: run,
    evaluation, process, and how episodes ended."""
    return Group(run_line(figures, model, width), counters(figures))


def counters(figures: TrainingFigures) -> Text:
    update, system, evaluation = figures.update, figures.system, figures.evaluation
    text = Text()
    # Every car's episodes, as the metrics file has them (the trainer's own count runs a
    # write ahead of the file: the larger of the two).
    every = max(figures.episodes, update.episodes if update is not None else 0)
    number, noun = counted(every, "episode").split(" ", 1)
    text.append(number)
    text.append(f" {noun}  ", style="dim")
    text.append(_number(update.total_steps if update else None, ",.0f"))
    text.append(" steps  ", style="dim")
    text.append("laps ", style="dim")
    text.append(_number(figures.completion_rate, ".0f", "%"))
    text.append(f" of last {COMPLETION_WINDOW}", style="dim")
    text.append("\neval ", style="dim")
    text.append(
        # Progress, said as such: "5/5 laps 6%" read as a lap rate (the host walk).
        f"{evaluation.laps}/{evaluation.trials} laps, progress {evaluation.mean_progress:.0f}%"
        if evaluation
        else "-"
    )
    if figures.ended is None:
        text.append("  CPU ", style="dim")
        text.append(_number(system.cpu_percent if system else None, ".0f", "%"))
        text.append("  mem ", style="dim")
        text.append(_number(system.rss_mb if system else None, ",.0f", " MB"))
    else:
        # The process is gone: its last sample read as a live figure (the host walk).
        text.append("  process ended", style="dim")
    if figures.started is not None and figures.started.opponents:  # on the track with it
        text.append("\nagainst ", style="dim")
        text.append(", ".join(figures.started.opponents))
    text.append("\nended ", style="dim")
    if figures.statuses:
        parts = [f"{status} {count:,}" for status, count in figures.statuses.most_common()]
        text.append(" · ".join(parts))
    else:
        text.append("-", style="dim")
    return text


def empty_reason(figures: TrainingFigures, chart_id: str) -> str:
    """What an empty chart says in its plot's place: why it has nothing to draw."""
    if figures.ended is not None and figures.ended.kind == "failed":
        return "training failed: see above"  # short: a chart at 60 columns is 28 wide
    if chart_id == "lap-time" and figures.episodes:
        # The chart is of training episodes, whose exploring policy may not finish a lap
        # while the evaluations' greedy one does: said, so the two never seem to disagree.
        evaluation = figures.evaluation
        if evaluation is not None and evaluation.best_lap is not None:
            return f"no training lap yet\nevaluation best {evaluation.best_lap:.2f} s"
        return "no training lap yet"
    if figures.ended is None and (figures.started is not None or figures.is_starting):
        return "waiting for data…"
    return "no data yet: press t to train"


class TrainingCharts(Vertical):
    """Counters and six charts of one model's `TrainingFigures`."""

    DEFAULT_CSS = """
    TrainingCharts { height: 1fr; }
    TrainingCharts > #figures { height: auto; max-height: 8; padding: 0 1; }
    TrainingCharts > Grid { grid-size: 2 3; grid-gutter: 0 1; height: 1fr; }
    TrainingCharts LineChart { min-height: 4; }
    """
    CHARTS: ClassVar[tuple[tuple[str, str, str, int | None], ...]] = (
        # (id, title, unit, running-mean window)
        ("reward", "reward", "", MEAN_WINDOW),
        ("progress", "progress", " %", MEAN_WINDOW),
        ("entropy", "entropy", "", None),
        ("lap-time", "lap time", " s", 10),
        ("steps", "steps/s", "", None),
        ("cpu", "CPU", " %", None),
    )

    def __init__(self, *, id: str | None = None) -> None:
        super().__init__(id=id)
        self.figures = TrainingFigures()
        self.model = ""  # whose figures: the counters name it
        self._shown_version = -1
        self._lengths: dict[str, int] = {}

    def compose(self) -> ComposeResult:
        yield Static(id="figures")
        with Grid():
            for chart_id, title, unit, window in self.CHARTS:
                yield LineChart(title, unit=unit, mean_window=window, id=f"chart-{chart_id}")

    def on_mount(self) -> None:
        self.set_interval(1.0 / STATUS_REFRESH_HZ, self.sync)
        self.sync()

    def on_resize(self) -> None:
        self._shown_version = -1  # the run line's wording follows the width
        self.sync()

    def show(self, figures: TrainingFigures, model: str) -> None:
        """Watch `model`'s figures (its charts are redrawn from the start)."""
        self.figures = figures
        self.model = model
        self._shown_version = -1
        self._lengths.clear()
        self.sync()

    def _series(self) -> dict[str, list[float]]:
        figures = self.figures
        return {
            "reward": figures.rewards,
            "progress": figures.progress,
            "entropy": figures.entropy,
            "lap-time": figures.lap_times,
            "steps": figures.steps_per_second,
            "cpu": figures.cpu,
        }

    def sync(self) -> None:
        """Hand new values to the charts (which repaint on their own calm tick) and
        rewrite the counters, when the figures changed since the last look."""
        if not self.is_mounted or self.figures.version == self._shown_version:
            return
        self._shown_version = self.figures.version
        for chart_id, values in self._series().items():
            chart = self.query_one(f"#chart-{chart_id}", LineChart)
            known = self._lengths.get(chart_id)
            if known is None or known > len(values):
                chart.replace(values)  # a new model, or the list was trimmed
            elif len(values) > known:
                chart.extend(values[known:])
            self._lengths[chart_id] = len(values)
            chart.say_when_empty(empty_reason(self.figures, chart_id))
        self.query_one("#figures", Static).update(
            figures_lines(self.figures, self.model, self.size.width)
        )

    def redraw_now(self) -> None:
        """Sync and repaint at once, off the calm tick (snapshots and tests)."""
        self.sync()
        for chart in self.query(LineChart):
            chart.repaint_if_changed()
