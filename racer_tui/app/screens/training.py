"""The Training section: train models in the background and watch them learn.

One training runs at a time (the machine has two cores); more requests wait in a queue.
Each run is the training child (`python -m sim.training.worker`) in its own session, with
its JSON event lines going to `training-log.jsonl` in the model folder rather than to a
pipe: the app tails that file, so the child does not depend on the app. Quitting the app
can therefore leave a training running, and the next app session finds it again
(`training-state.json` names its pid) and keeps drawing and can stop it. Stop is SIGTERM:
the child saves a checkpoint and writes its last event; training the model again resumes
from that checkpoint.

Every figure on the view comes from the training's own files, read by the same functions
live and after a restart (`load_figures`, `read_new_rows`): its TrainingMetrics.json,
followed as the trainer appends it; its run history (the stream's updates and system
readings); its state file's last word, read again when the run ends. The charts pick the
figures up at 2 Hz.
Everything that reads files runs in thread workers; the log tail is an async worker that
reads a few kilobytes at a time, so keys stay responsive while the child trains flat out.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
import os
import signal
import tempfile
import time
from dataclasses import dataclass, field
from datetime import datetime
from functools import partial
from pathlib import Path
from typing import Any, ClassVar

import psutil
from rich.text import Text
from textual import on, work
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal, Vertical
from textual.message import Message
from textual.widgets import Button, DataTable, Label, Static

from racer_tui.app.screens.base import RacerModal, RacerScreen, error_message
from racer_tui.app.screens.evaluation import EvaluationScreen
from racer_tui.app.screens.train_dialog import TrainAnswer, TrainDialog
from racer_tui.app.widgets.agent_view import AgentView, Observation, observe_at
from racer_tui.app.widgets.footer import RacerFooter
from racer_tui.app.widgets.model_detail import status_text
from racer_tui.app.widgets.section_header import SectionHeader
from racer_tui.app.widgets.table_fill import Col, FittedTable, fill_table
from racer_tui.app.widgets.training_charts import MetricsMark, TrainingCharts, TrainingFigures
from racer_tui.app.words import said_in_app
from racer_tui.text.clocks import elapsed_text as clock
from sim.deepracer.files import (
    DeepRacerFileError,
    TrainingEpisode,
    last_sim_trace_row,
    training_metrics_rows_after,
)
from sim.foundation.remedies import fix_named
from sim.garage.folder import (
    MAX_MINUTES,
    MIN_MINUTES,
    ModelError,
    ModelFolder,
    list_models,
    open_model,
)
from sim.physics.objects.field import ObjectField
from sim.physics.objects.reading import race_settings
from sim.physics.objects.seen import read_seen
from sim.physics.objects.settings import RaceType
from sim.physics.objects.world import object_field
from sim.physics.simulation import LOOK_AHEAD
from sim.tracks.track import Track
from sim.training import events
from sim.training.config import training_env_config
from sim.training.launcher import (
    STOP_TIMEOUT,
    budget_grace,
    failure_from_stderr,
    overran,
    worker_command,
)
from sim.training.opponents import check_opponents, opponent_spec
from sim.training.run_history import read_history

WORKER_MODULE = "sim.training.worker"
TAIL_SECONDS = 0.25  # how often the log is read while a run is live
TICK_SECONDS = 2.0  # run status, adopted runs and the agent's-eye view
READ_CHUNK = 256_000
METRICS_SECONDS = 1.0  # how often a live run's TrainingMetrics.json is read for new rows
COLUMNS = (Col("model", keep=1, shrink_to=10, collapses=False, cuts_middle=True), Col("state"))
NARROW = 110  # below this width the agent's-eye view takes the charts' place on `v`
TINY = 70  # below this width the model list narrows


@dataclass(frozen=True)
class TrainingRequest:
    model: str
    minutes: float
    opponents: tuple[str, ...] = ()  # cars on the track with it (`racer-tui train --opponent`)


@dataclass
class LiveRun:
    """The training on screen. `process` is None when an earlier session started it."""

    model: str
    pid: int
    minutes: float | None
    process: asyncio.subprocess.Process | None = None
    stopping: bool = False
    started: float = field(default_factory=time.monotonic)
    stop_asked: float | None = None  # when the app stopped it for running past its budget


def running_worker_pid(folder: ModelFolder) -> int | None:
    """The pid of a training of `folder` that is running now (started by any session or
    the CLI), checked to really be a training worker: a stale pid may have been reused."""
    if not folder.is_training():
        return None
    state = folder.training_state() or {}
    pid = state.get("pid")
    if not isinstance(pid, int):
        return None
    try:
        command = psutil.Process(pid).cmdline()
    except psutil.Error:
        return None
    return pid if any(WORKER_MODULE in part for part in command) else None


def load_figures(folder: ModelFolder) -> TrainingFigures:
    """The model's training so far, every run: its TrainingMetrics, its run history and
    how its last run ended (empty before the first run). What the view shows after a
    restart, and at the end of a run it watched live."""
    figures = TrainingFigures.from_metrics(None, read_history(folder.training_history))
    figures.take_rows(*read_new_rows(folder, figures.metrics_mark))
    figures.ended, figures.ended_at = last_ending(folder)
    figures.ended_before = figures.ended is not None
    return figures


NewRows = tuple[tuple[TrainingEpisode, ...], MetricsMark, bool]


def read_new_rows(folder: ModelFolder, mark: MetricsMark) -> NewRows:
    """The TrainingMetrics rows written since `mark`, where to continue from, and whether
    the file was replaced whole since (read again from its first row). Unreadable
    metrics give no rows: the episode charts go on from the next readable row."""
    path = folder.training_metrics_file
    try:
        inode = path.stat().st_ino
    except FileNotFoundError:
        return (), MetricsMark(), mark.inode is not None
    except OSError:
        return (), mark, False
    fresh = inode != mark.inode
    offset = 0 if fresh else mark.offset
    if offset is None:  # a layout read whole once, not replaced since
        return (), mark, False
    try:
        rows, next_offset = training_metrics_rows_after(path, offset)
    except DeepRacerFileError:
        return (), MetricsMark(inode, None), fresh
    return rows, MetricsMark(inode, next_offset), fresh


def last_ending(folder: ModelFolder) -> tuple[events.Ended | None, float | None]:
    """How the model's last run ended and when (wall time), from the trainer's state file:
    what the run line says after a restart, and at the end of a run watched live. None
    while a run is going or before any."""
    state = folder.training_state()
    if state is None or folder.is_training():
        return None, None
    at, since = _wall(state.get("updated_at")), _wall(state.get("started_at"))
    # The file's elapsed_seconds counts every run of the model (it resumes); this run's
    # own time is from its start to its last word.
    elapsed = at - since if at is not None and since is not None and at >= since else 0.0
    kind, message = str(state["state"]), str(state.get("message") or "")
    problem, fix = str(state.get("problem") or ""), fix_named(state.get("fix"))
    if kind == "running":  # its process is gone without a last word
        kind, message = "failed", NO_LAST_WORD
        problem, fix = "", None
    return (
        events.Ended(
            elapsed=elapsed,
            kind=kind,
            message=message,
            total_steps=int(_number(state.get("steps"))),
            episodes=int(_number(state.get("episodes"))),
            best_progress=_number(state.get("best_progress")),
            best_lap=_number(state.get("best_lap")) or None,
            problem=problem if fix is not None else "",
            fix=fix.name if fix is not None else "",
        ),
        at,
    )


NO_LAST_WORD = "the training process ended without writing how"


def _wall(value: object) -> float | None:
    try:
        return datetime.fromisoformat(str(value)).timestamp()
    except ValueError:
        return None


def _number(value: object) -> float:
    return float(value) if isinstance(value, int | float) and not isinstance(value, bool) else 0.0


def latest_observation(folder: ModelFolder) -> Observation | None:
    """What the model saw at the last traced step of its latest traced training iteration."""
    files = [
        path
        for path in folder.training_trace_dir.glob("*-iteration.csv")
        if path.name.split("-")[0].isdigit()
    ]
    if not files:
        return None
    latest = max(files, key=lambda p: int(p.name.split("-")[0]))
    row = last_sim_trace_row(latest)
    if row is None:
        return None
    caption = f"iteration {latest.name.split('-')[0]}, episode {row.episode} step {row.steps}"
    sensors = folder.metadata().sensors
    # The trace's X, Y is DeepRacer's point ahead of the car; the view is from the car.
    yaw = math.radians(row.yaw)
    x, y = row.x - LOOK_AHEAD * math.cos(yaw), row.y - LOOK_AHEAD * math.sin(yaw)
    track = folder.track()
    objects, caption = _objects_seen(folder, track, caption, (row.episode, row.steps))
    return observe_at(track, sensors, (x, y, row.yaw), caption, objects)


def _objects_seen(
    folder: ModelFolder, track: Track, caption: str, at: tuple[int, int]
) -> tuple[ObjectField | None, str]:
    """The model's boxes or bots where they stood at the trace row `at` (episode, step):
    boxes that are not shuffled stand in the same places every episode; shuffled boxes and
    bot cars are where the trainer saw them at its last traced row (`sim.physics.objects.seen`).
    When that is not this row, the caption says they are left out rather than drawing
    them elsewhere."""

    try:
        race = race_settings(folder.training_params())
    except (DeepRacerFileError, ModelError):
        return None, caption
    if race.race_type is RaceType.TIME_TRIAL:
        return None, caption
    if race.race_type is RaceType.OBJECT_AVOIDANCE and not race.obstacles.randomize:
        return object_field(track, race, 1), caption
    seen = read_seen(folder.path)
    if seen is not None and (seen.episode, seen.steps) == at:
        return seen.field(track), caption
    what = "bot cars" if race.race_type is RaceType.HEAD_TO_BOT else "shuffled boxes"
    return None, f"{caption} · its {what} are not shown"


def _pid_alive(pid: int) -> bool:
    try:
        return psutil.Process(pid).status() != psutil.STATUS_ZOMBIE
    except psutil.Error:
        return False


# --- messages from the workers --------------------------------------------------------------


@dataclass
class TrainingModelsRead(Message):
    rows: list[tuple[str, str, int | None]]  # (name, status, pid of a training running elsewhere)
    select: str | None


@dataclass
class FiguresLoaded(Message):
    name: str
    figures: TrainingFigures
    replaces: TrainingFigures | None = None


@dataclass
class ObservationMade(Message):
    name: str
    observation: Observation | None


class LeaveWhileTraining(RacerModal[str | None]):
    """Quit with a training running: "stop" it, "keep" it running, or None to stay."""

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("s", "answer('stop')", "Stop it"),
        Binding("k", "answer('keep')", "Keep running"),
        Binding("escape", "answer(None)", "Stay"),
    ]

    def __init__(self, model: str) -> None:
        super().__init__()
        self.model = model

    def compose(self) -> ComposeResult:
        with Vertical(classes="dialog"):
            yield Label(Text(f"Quit? {self.model} is still training"), classes="dialog-title")
            yield Static(
                Text(
                    "Stop it now (it saves a checkpoint, and training again resumes from it), "
                    "or keep it running in the background: the next time you open racer-tui, "
                    "the Training section shows it again and can stop it."
                ),
                classes="dialog-body",
            )
            # Three buttons fit 60 columns only this short and close together.
            with Horizontal(classes="dialog-buttons -three"):
                yield Button("Stop it (s)", id="stop", variant="error")
                yield Button("Keep running (k)", id="keep", variant="primary")
                yield Button("Stay (esc)", id="stay")

    def action_answer(self, answer: str | None) -> None:
        self.dismiss(answer)

    @on(Button.Pressed)
    def _pressed(self, event: Button.Pressed) -> None:
        self.dismiss(event.button.id if event.button.id in ("stop", "keep") else None)


# The workers that follow a training for as long as it runs (its process's events, or an
# outside run's log): long-lived by design, unlike the app's other workers.
RUN_GROUP = "training-run"


class TrainingScreen(RacerScreen[None]):
    """Models on the left with their training state; the highlighted one's charts."""

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("t", "train", "Train", tooltip="Train the highlighted model (queued if busy)"),
        Binding("s", "stop", "Stop", tooltip="Stop the training (it saves a checkpoint)"),
        Binding("e", "evaluate", "Evaluate", tooltip="Time-trial trials of the trained policy"),
        Binding(
            "v",
            "toggle_eye",
            "Agent's view",
            tooltip="What the car sees, in the charts' place (a narrow terminal)",
        ),
        Binding("ctrl+r", "reload", "Reload", tooltip="Read the model folders again", show=False),
    ]
    DEFAULT_CSS = """
    TrainingScreen #training-body { height: 1fr; }
    TrainingScreen #training-models { width: 26; height: 1fr; }
    TrainingScreen #training-side { width: 34; height: 1fr; padding: 0 1; }
    TrainingScreen #agent-title { text-style: bold; color: $accent; }
    TrainingScreen.-narrow #training-side { display: none; }
    TrainingScreen.-tiny #training-models { width: 24; }
    TrainingScreen.-narrow.-eye #training-side { display: block; width: 1fr; }
    TrainingScreen.-narrow.-eye #training-charts { display: none; }
    """
    # Extra worker options (tests use a tiny budget); the child's own defaults otherwise.
    worker_options: ClassVar[tuple[str, ...]] = ()

    def __init__(self) -> None:
        super().__init__()
        self.rows: list[tuple[str, str, int | None]] = []
        self.ready_for_keys = False  # the app holds keys typed before the list lands
        self.queue: list[TrainingRequest] = []
        self.live: LiveRun | None = None
        self.figures: dict[str, TrainingFigures] = {}
        self.watched: str | None = None
        self.handled_keys = 0  # for the responsiveness test

    def compose(self) -> ComposeResult:
        yield SectionHeader("training")
        with Horizontal(id="training-body"):
            yield FittedTable(id="training-models", cursor_type="row", zebra_stripes=True)
            yield TrainingCharts(id="training-charts")
            with Vertical(id="training-side"):
                yield Static("Agent's-eye view", id="agent-title")
                yield AgentView(id="agent-view")
        yield RacerFooter()

    def on_mount(self) -> None:
        self.reload()
        self.set_interval(TICK_SECONDS, self._tick)

    def on_resize(self) -> None:
        self.set_class(self.size.width < TINY, "-tiny")  # the charts need the room
        narrow = self.size.width < NARROW
        if narrow != self.has_class("-narrow"):
            self.set_class(narrow, "-narrow")
            self.refresh_bindings()  # v is for a terminal too narrow for both

    @property
    def eye_shown(self) -> bool:
        """The agent's-eye view is on screen (beside the charts, or in their place)."""
        return not self.has_class("-narrow") or self.has_class("-eye")

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        if action == "toggle_eye":
            return self.has_class("-narrow")
        return True

    def action_toggle_eye(self) -> None:
        """The agent's-eye view in the charts' place, or the charts back."""
        self.toggle_class("-eye")
        if self.eye_shown and self.watched is not None:
            self._observe(self.watched)

    # --- the model list --------------------------------------------------------------------

    def reload(self, select: str | None = None) -> None:
        self._read_models(select or self.watched)

    @work(thread=True, exclusive=True, group="training-list", exit_on_error=False)
    def _read_models(self, select: str | None) -> None:
        rows = [
            (folder.name, str(folder.status()), running_worker_pid(folder))
            for folder in list_models()
        ]
        self.post_message(TrainingModelsRead(rows, select))

    def on_training_models_read(self, message: TrainingModelsRead) -> None:
        self.rows = message.rows
        self.ready_for_keys = True
        if self.live is None:
            elsewhere = next(((n, pid) for n, _, pid in self.rows if pid is not None), None)
            if elsewhere is not None:
                self._adopt(*elsewhere)
        self._fill_table(message.select)

    def _state_of(self, name: str, status: str) -> Text:
        if self.live is not None and self.live.model == name:
            return Text("stopping…" if self.live.stopping else "training", style="bold yellow")
        for place, request in enumerate(self.queue, start=1):
            if request.model == name:
                return Text(f"queued {place}", style="yellow")
        return status_text(status)

    def _fill_table(self, select: str | None = None) -> None:
        table = self.query_one("#training-models", DataTable)
        select = select or self.highlighted_name
        cells = [(Text(name), self._state_of(name, status)) for name, status, _ in self.rows]
        names = [name for name, _, _ in self.rows]
        fill_table(table, COLUMNS, cells, keys=names)
        if not names:
            self.query_one(AgentView).show_message("No models yet: create one in the garage (1).")
            return
        index = names.index(select) if select in names else 0
        table.move_cursor(row=index)
        self.watch_model(names[index])
        self._show_context()

    @property
    def highlighted_name(self) -> str | None:
        table = self.query_one("#training-models", DataTable)
        if not self.rows or not 0 <= table.cursor_row < len(self.rows):
            return None
        return self.rows[table.cursor_row][0]

    @on(DataTable.RowHighlighted, "#training-models")
    def _highlighted(self, event: DataTable.RowHighlighted) -> None:
        if 0 <= event.cursor_row < len(self.rows):
            self.watch_model(self.rows[event.cursor_row][0])

    def watch_model(self, name: str) -> None:
        """Show `name`'s charts: its live figures, or its history read from its files."""
        if name == self.watched:
            return
        self.watched = name
        known = self.figures.get(name)
        self.query_one(TrainingCharts).show(known or TrainingFigures(), name)
        if not self._live_run_of(name):
            # Read again each time: a run of it may have ended (or been made from the
            # command line) since its figures were last read.
            self._load_figures(name)
        self._observe(name)

    def _live_run_of(self, name: str) -> bool:
        return self.live is not None and self.live.model == name

    @work(thread=True, group="training-history", exit_on_error=False)
    def _load_figures(self, name: str, replaces: TrainingFigures | None = None) -> None:
        try:
            figures = load_figures(open_model(name))
        except ModelError:
            return  # the model is gone: the list says so on its next read
        self.post_message(FiguresLoaded(name, figures, replaces))

    def on_figures_loaded(self, message: FiguresLoaded) -> None:
        current = self.figures.get(message.name)
        figures = message.figures
        if message.replaces is not None:
            if current is not message.replaces:
                return  # a newer run of it is on screen
            ended = figures.ended
            if current.ended is not None and (ended is None or ended.message == NO_LAST_WORD):
                # The state file has no last word of this run: what the app saw of its end
                # (its process's exit, its error output) is all there is.
                figures.ended, figures.ended_at = current.ended, current.ended_at
            figures.ended_before = False
            self.figures[message.name] = figures
        elif self._live_run_of(message.name) and current is not None:
            figures = current  # a run started meanwhile: the truth now
        else:
            self.figures[message.name] = figures
        if message.name == self.watched:
            self.query_one(TrainingCharts).show(figures, message.name)

    @work(thread=True, exclusive=True, group="training-eye", exit_on_error=False)
    def _observe(self, name: str) -> None:
        self.post_message(ObservationMade(name, latest_observation(open_model(name))))

    def on_observation_made(self, message: ObservationMade) -> None:
        if message.name != self.watched:
            return
        view = self.query_one(AgentView)
        if message.observation is None:
            view.show_message("Train this model to see what it sees.")
        else:
            view.show(message.observation)

    def _tick(self) -> None:
        self._show_context()
        self._enforce_budget()
        live = self.live
        if live is None:
            # A training started outside the app (`racer-tui train`, the host's usual case
            # on a league night) is picked up within a tick, without a key press.
            self._read_models(None)
        if live is not None and live.model == self.watched and self.eye_shown:
            self._observe(live.model)

    def _enforce_budget(self) -> None:
        """A child that runs well past its time budget (hung where its own clock cannot
        stop it) is stopped by the app, and killed if it does not stop."""
        live = self.live
        if live is None or live.pid <= 0 or not live.minutes:
            return
        now = time.monotonic()
        budget = live.minutes * 60.0
        if live.stop_asked is None and now - live.started > budget + budget_grace(budget):
            live.stop_asked = now
            self.stop_training()
            self.notify(
                f"{live.model} ran well past its {live.minutes:g}-minute budget; stopping it "
                "(its last checkpoint is kept).",
                severity="warning",
                markup=False,
            )
        elif live.stop_asked is not None and now - live.stop_asked > STOP_TIMEOUT:
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.kill(live.pid, signal.SIGKILL)

    def _show_context(self) -> None:
        live = self.live
        header = self.query_one(SectionHeader)
        if live is None:
            waiting = f"{len(self.queue)} queued" if self.queue else ""
            header.set_context(waiting)
            return
        figures = self.figures.get(live.model)
        elapsed = clock(figures.elapsed) if figures else "0:00"
        limit = f" of {clock(live.minutes * 60)}" if live.minutes else ""
        queued = f" · {len(self.queue)} queued" if self.queue else ""
        header.set_context(f"{live.model}: {elapsed}{limit}{queued}")

    # --- training ----------------------------------------------------------------------------

    def action_train(self) -> None:
        self.handled_keys += 1
        name = self.highlighted_name
        if name is None:
            self.notify("There is no model to train; create one in the garage.", severity="warning")
            return
        self.ask_to_train(name)

    def ask_to_train(self, name: str) -> None:
        """Ask for the time budget, then train `name` (or queue it)."""
        if self._busy_with(name):
            self.notify(f"{name} is already training or queued.", severity="warning")
            return
        try:
            folder = open_model(name)
            problem = folder.car_archive_problem("train")
            if problem is not None:
                raise ModelError(problem)
            minutes = folder.last_budget_minutes() or folder.training_params().max_minutes
        except ModelError as error:
            self.notify(error_message(error), severity="error", markup=False)
            return
        dialog = TrainDialog(
            name,
            minutes,
            minutes_problem=_minutes_problem,
            opponents_problem=partial(_opponents_problem, folder),
        )
        self.app.push_screen(dialog, partial(self._budget_given, name))

    def _budget_given(self, name: str, answer: TrainAnswer | None) -> None:
        if answer is not None:
            self.request_training(name, answer.minutes, answer.opponents)

    def _busy_with(self, name: str) -> bool:
        live = self.live is not None and self.live.model == name
        return live or any(request.model == name for request in self.queue)

    def request_training(self, name: str, minutes: float, opponents: tuple[str, ...] = ()) -> None:
        """Train `name` now, or after the trainings already queued (among `opponents`)."""
        if self._busy_with(name):
            return
        cars = tuple(opponent_spec(car) for car in opponents)
        self.queue.append(TrainingRequest(name, minutes, cars))
        if self.live is not None:
            self.notify(f"{name} is queued; it trains when {self.live.model} is done.")
        self._start_next()
        self._fill_table(name)

    def _start_next(self) -> None:
        if self.live is not None or not self.queue:
            return
        request = self.queue.pop(0)
        # Claimed now, before the worker runs, so a second request cannot start a second run.
        self.live = LiveRun(request.model, pid=0, minutes=request.minutes)
        self._run(request)

    @work(group=RUN_GROUP, exit_on_error=False)
    async def _run(self, request: TrainingRequest) -> None:
        live = self.live
        assert live is not None
        cancelled = False  # the app is closing: leave the child alone, start nothing new
        try:
            folder = open_model(request.model)
            figures = await asyncio.to_thread(load_figures, folder)
            figures.starting()  # until its first event: not the last run's ending
            self.figures[request.model] = figures
            if request.model == self.watched:
                self.query_one(TrainingCharts).show(figures, request.model)
            if folder.is_training() or folder.training_locked():
                # Started elsewhere a moment ago (the command line): its log is not ours to
                # empty; the next tick follows that run here instead.
                self.notify(
                    f"{request.model} is already training in another process; it is shown "
                    "here as it runs.",
                    severity="warning",
                    markup=False,
                )
                return
            log = folder.training_log
            log.write_bytes(b"")  # a new run, a new log
            stderr = tempfile.TemporaryFile()  # noqa: SIM115 - closed when the run ends
            options = self._options()
            for car in request.opponents:
                options += ["--opponent", car]
            command = worker_command(request.model, request.minutes, options)
            with stderr:
                with log.open("ab") as out:
                    process = await asyncio.create_subprocess_exec(
                        *command,
                        stdin=asyncio.subprocess.DEVNULL,
                        stdout=out,
                        stderr=stderr,
                        start_new_session=True,
                        env={**os.environ, "PYTHONUNBUFFERED": "1", "OMP_NUM_THREADS": "1"},
                    )
                live.process, live.pid = process, process.pid
                self._fill_table()
                ended = await self._follow(request.model, log, 0, process.wait)
                if ended is None:
                    stderr.seek(0)
                    tail = stderr.read()[-2000:].decode("utf-8", "replace")
                    self._ended_silently(request.model, process.returncode, tail)
                else:
                    # The last event is written: let the child exit before the next starts.
                    with contextlib.suppress(TimeoutError):
                        await asyncio.wait_for(process.wait(), 30.0)
        except asyncio.CancelledError:
            cancelled = True
            raise
        finally:
            if not cancelled:
                self._run_over()

    def _options(self) -> list[str]:
        # The child must outlive the app when the racer chooses to keep it running, so it
        # does not watch this process (its stdout is a file, not a pipe, for the same reason).
        return [*self.worker_options, "--parent-pid", "0"]

    def _adopt(self, name: str, pid: int) -> None:
        """Follow a training that an earlier session (or the CLI) started."""
        self.live = LiveRun(name, pid=pid, minutes=None)
        self._follow_adopted(name, pid)

    @work(group=RUN_GROUP, exit_on_error=False)
    async def _follow_adopted(self, name: str, pid: int) -> None:
        cancelled = False
        try:
            folder = open_model(name)
            figures = await asyncio.to_thread(load_figures, folder)
            self.figures[name] = figures
            if name == self.watched:
                self.query_one(TrainingCharts).show(figures, name)
            log = folder.training_log
            if not log.is_file():
                # Started without a log (by `racer-tui train`): its metrics file as it grows,
                # then the whole of its files once it is over.
                while _pid_alive(pid):
                    await asyncio.sleep(METRICS_SECONDS)
                    await self.read_metrics(name)
                self._load_figures(name, self.figures.get(name))
                return
            start = log.stat().st_size

            async def exited() -> int | None:
                while _pid_alive(pid):
                    await asyncio.sleep(1.0)
                return None

            if await self._follow(name, log, start, exited) is None:
                # Gone without its last event (killed, crashed): said as it is, never left
                # looking like a run that is still going.
                self._ended_silently(name, None, "")
        except asyncio.CancelledError:
            cancelled = True
            raise
        finally:
            if not cancelled:
                self._run_over()

    async def _follow(
        self, name: str, log: Path, history_end: int, wait: Any
    ) -> events.Ended | None:
        """Apply the log's events until the last one, or until the child is gone and the
        log drained. Lines before `history_end` were written before this session looked:
        their episodes, updates and system readings are already in the TrainingMetrics and
        the run history, so only the rest of them is used."""
        waiter = asyncio.ensure_future(wait())
        offset, pending = 0, b""
        next_metrics = 0.0
        try:
            with log.open("rb") as handle:
                while True:
                    if time.monotonic() >= next_metrics:
                        await self.read_metrics(name)
                        next_metrics = time.monotonic() + METRICS_SECONDS
                    chunk = handle.read(READ_CHUNK)
                    if chunk:
                        lines = (pending + chunk).split(b"\n")
                        pending = lines.pop()
                        for line in lines:
                            offset += len(line) + 1
                            ended = self._line(name, line, replay=offset <= history_end)
                            if ended is not None:
                                return ended
                        continue
                    if waiter.done():
                        return None
                    await asyncio.sleep(TAIL_SECONDS)
        finally:
            waiter.cancel()

    async def read_metrics(self, name: str) -> None:
        """Fold the rows the trainer appended to `name`'s TrainingMetrics.json since the
        last look (read in a thread, folded here, where the charts read the figures)."""
        figures = self.figures.get(name)
        if figures is None:
            return
        try:
            folder = open_model(name)
        except ModelError:
            return
        new = await asyncio.to_thread(read_new_rows, folder, figures.metrics_mark)
        if self.figures.get(name) is figures:  # not replaced meanwhile
            figures.take_rows(*new)

    def _ended_silently(self, name: str, returncode: int | None, stderr_tail: str) -> None:
        """A run whose process ended without writing its last event (`returncode` None: not
        this app's child, so its exit status is unknown)."""
        figures = self.figures.get(name)
        if figures is not None and figures.started is not None and figures.ended is not None:
            return  # this run's end is already known
        elapsed = figures.elapsed if figures is not None and figures.started else 0.0
        self.apply_event(name, failure_from_stderr(returncode, stderr_tail, elapsed=elapsed))

    def _line(self, name: str, line: bytes, *, replay: bool) -> events.Ended | None:
        try:
            event = events.decode(line.strip())
        except events.EventError:
            return None  # a stray line is skipped, never fatal
        if replay and isinstance(event, events.Episode | events.Update | events.System):
            # Already read from the model's metrics and run history; its time still says
            # how far the run has got (an adopted run is not at 0:00).
            self.figures.setdefault(name, TrainingFigures()).heard_at(event.elapsed)
            return None
        self.apply_event(name, event)
        return event if isinstance(event, events.Ended) else None

    def apply_event(self, name: str, event: events.Event) -> None:
        """Fold one event into `name`'s figures (the charts redraw on their calm tick).
        Tests inject events here without a process, as the log tail does."""
        live = self.live
        if (
            isinstance(event, events.Ended)
            and live is not None
            and live.model == name
            and live.stop_asked is not None
            and live.minutes
        ):
            # The app stopped it for running past its budget: said so, as the CLI says it,
            # not as the child saw it ("stopped on request").
            event = overran(event, live.minutes * 60.0)
        figures = self.figures.setdefault(name, TrainingFigures())
        figures.fold(event)
        if isinstance(event, events.Ended):
            figures.ended_at = time.time()
        if isinstance(event, events.Started) and live is not None and live.model == name:
            live.minutes = event.max_minutes
        if isinstance(event, events.Ended):
            # Its figures as its files have them now that it is over: the state file's
            # clock and ending, the metrics' last rows. What a restart shows, shown now.
            self._load_figures(name, figures)
            said = said_in_app(event.message, event.problem, event.remedy)
            self.notify(
                f"Training of {name} {event.kind}: {said.rstrip('.')}.",
                severity="error" if event.kind == "failed" else "information",
                timeout=10,
                markup=False,
            )

    def _run_over(self) -> None:
        finished = self.live.model if self.live is not None else None
        self.live = None
        if finished is not None and finished == self.watched:
            self._observe(finished)
        self._start_next()
        self.reload(select=self.watched)

    # --- stop ----------------------------------------------------------------------------------

    def action_stop(self) -> None:
        self.handled_keys += 1
        name = self.highlighted_name
        for request in self.queue:
            if request.model == name:
                self.queue.remove(request)
                self.notify(f"{name} is no longer queued.")
                self._fill_table()
                return
        if self.live is None:
            self.notify("Nothing is training.", severity="warning")
            return
        self.stop_training()
        self.notify(f"Stopping {self.live.model}: it saves a checkpoint first.")

    def stop_training(self) -> None:
        """SIGTERM to the running child: it checkpoints and writes its last event."""
        live = self.live
        if live is None or live.pid <= 0:
            return
        live.stopping = True
        with contextlib.suppress(ProcessLookupError, PermissionError):
            if live.process is not None:
                if live.process.returncode is None:
                    live.process.send_signal(signal.SIGTERM)
            else:
                os.kill(live.pid, signal.SIGTERM)
        self._fill_table()

    @property
    def training_here(self) -> str | None:
        """The model of a training that is running now, if any (to ask before quitting)."""
        return self.live.model if self.live is not None and self.live.pid > 0 else None

    # --- evaluate ------------------------------------------------------------------------------

    def action_evaluate(self) -> None:
        name = self.highlighted_name
        if name is None:
            self.notify("There is no model to evaluate.", severity="warning")
            return
        self.app.push_screen(EvaluationScreen(name))

    def action_reload(self) -> None:
        self.reload()


def _opponents_problem(folder: ModelFolder, opponents: tuple[str, ...]) -> str | None:
    """What keeps `folder` from training among `opponents`, said as the command line does."""
    try:
        check_opponents(training_env_config(folder), opponents)
    except ModelError as error:
        said = error_message(error).removeprefix("--opponent: ")
        return said[:1].upper() + said[1:]
    return None


def _minutes_problem(text: str) -> str | None:
    try:
        minutes = float(text)
    except ValueError:
        return "Give the time budget as a number of minutes, for example 10."
    if not MIN_MINUTES <= minutes <= MAX_MINUTES:
        return f"The time budget must be from {MIN_MINUTES:g} to {MAX_MINUTES:g} minutes."
    return None
