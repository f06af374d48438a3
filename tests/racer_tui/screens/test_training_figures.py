"""Issue 42, points 4 and 5: every figure on the Training view comes from the training's
own files, so what a racer reads while the model trains is what the view says after a
restart. The run is written as the trainer writes it (its metrics writer, its run history,
its state file's keys) while its stream's events go through the screen as the log tail
applies them; then a new app opens the same folder."""

from __future__ import annotations

import json
import os
from datetime import UTC, datetime, timedelta

import pytest

from racer_tui.app.application import create_app
from racer_tui.app.screens.training import TrainingScreen
from racer_tui.app.widgets.chart import LineChart
from racer_tui.app.widgets.training_charts import (
    TrainingCharts,
    TrainingFigures,
    empty_reason,
)
from sim.deepracer.files import TrainingEpisode, TrainingMetrics, append_training_metrics
from sim.garage.folder import ModelFolder
from sim.garage.options import new_model
from sim.training import events
from sim.training.run_history import RunHistory
from tests.racer_tui.screens.tui_helpers import painted, settle, wait_for

CARS = 4
PER_ITERATION = 20
ITERATIONS = 6
STARTED = datetime(2026, 11, 28, 20, 0, tzinfo=UTC)


class FakeTrainer:
    """Writes a training's files in the trainer's order (rows, then the stream's events)
    and hands each event to the screen. Car 0, the one the stream reports, mostly goes
    off track while the other cars mostly complete their laps: a figure computed from the
    stream's sample would be far from the file's."""

    def __init__(self, folder: ModelFolder, screen: TrainingScreen) -> None:
        self.folder, self.screen = folder, screen
        self.history = RunHistory(folder.training_history)
        self.episode = 0
        self.clock_ms = 0
        self.steps = 0

    def state(self, kind: str, message: str, seconds: float) -> None:
        document = {
            "state": kind,
            "pid": os.getpid() if kind == "running" else 999_999_999,
            "started_at": STARTED.isoformat(),
            "updated_at": (STARTED + timedelta(seconds=seconds)).isoformat(),
            "elapsed_seconds": seconds,
            "steps": self.steps,
            "episodes": self.episode,
            "best_progress": 100.0,
            "best_lap": 10.39,
            "message": message,
            "problem": "",
            "fix": "",
        }
        self.folder.training_state_file.write_text(json.dumps(document))

    def emit(self, event: events.Event) -> None:
        self.history.record(event)
        self.screen.apply_event(self.folder.name, event)

    def iteration(self, number: int) -> None:
        rows: list[TrainingEpisode] = []
        for trial in range(1, PER_ITERATION + 1):
            self.episode += 1
            car = self.episode % CARS
            lap = car != 0 and trial % 7 != 0
            ms = 10_400 if lap else 3_000
            self.clock_ms += ms
            status = "Lap complete" if lap else "Off track"
            progress = 100.0 if lap else 30.0
            rows.append(
                TrainingEpisode(
                    float(trial), self.clock_ms, self.clock_ms - ms, ms, self.episode, trial,
                    "training", progress, status,
                )
            )  # fmt: skip
            if car == 0:  # the stream reports one car
                self.emit(
                    events.Episode(
                        number * 10.0, self.episode, 0, float(trial), progress,
                        ms / 1000 if lap else None, status, ms // 66,
                    )
                )  # fmt: skip
        self.steps += 3000
        self.emit(
            events.Update(
                number * 10.0, number, self.steps, self.episode, 1.5 - number / 100, 0.0,
                0.4, 0.0, 0.1, 5000.0, PER_ITERATION, 10.0, 80.0, 15, 10.4,
            )
        )  # fmt: skip
        if number % 2 == 0:  # an evaluation between iterations, five laps
            start = self.clock_ms
            for _ in range(5):
                rows.append(
                    TrainingEpisode(
                        0, start + 10_390, start, 10_390, self.episode, PER_ITERATION,
                        "evaluation", 100, "Lap complete",
                    )
                )  # fmt: skip
                start += 10_390
            self.emit(
                events.Evaluation(
                    number * 10.0 + 1, number, self.steps, 5, 5, 100.0, 10.39,
                    (10.39,) * 5, ("Lap complete",) * 5, True,
                )
            )  # fmt: skip
        append_training_metrics(self.folder.training_metrics_file, rows, TrainingMetrics(()))
        self.emit(events.System(number * 10.0 + 2, 97.0, 420.0))


def words(text: str) -> str:
    return " ".join(text.split())


def shown(screen: TrainingScreen) -> tuple[str, dict[str, list[float]]]:
    """The counters and run line as painted, and every chart's values."""
    charts = screen.query_one(TrainingCharts)
    charts.redraw_now()
    values = {chart.id or "": list(chart.values) for chart in charts.query(LineChart)}
    return painted(charts.query_one("#figures")), values


async def test_figures_shown_live_are_the_figures_shown_after_a_restart() -> None:
    folder = new_model("ada")
    app = create_app(start="training")
    async with app.run_test(size=(120, 40)) as pilot:
        await settle(pilot)
        screen = app.screen
        assert isinstance(screen, TrainingScreen)
        trainer = FakeTrainer(folder, screen)
        trainer.state("running", "training", 1.0)
        trainer.emit(events.Started(0.0, "ada", "hairpin", ("FRONT_FACING_CAMERA",), CARS,
                                    "scratch", 0, 5.0, os.getpid()))  # fmt: skip
        for number in range(1, ITERATIONS + 1):
            trainer.iteration(number)
            await screen.read_metrics("ada")
        live_text, _ = shown(screen)
        # The file's figures while it runs, not the reported car's (0% laps, 30 episodes).
        assert "120 episodes" in " ".join(live_text.split())
        assert "laps 64% of last 50" in live_text
        assert "eval 5/5 laps, progress 100%" in live_text
        assert "Lap complete 78 · Off track 42" in live_text
        watched = screen.figures["ada"]
        # The run ends: the child's clock says 5:02, its state file 5:04 (start-up counts).
        trainer.state("finished", "the time limit was reached", 304.0)
        screen.apply_event(
            "ada", events.Ended(302.0, "finished", "the time limit was reached",
                                trainer.steps, trainer.episode, 100.0, 10.39),
        )  # fmt: skip
        await wait_for(pilot, lambda: screen.figures["ada"] is not watched)
        live_text, live_charts = shown(screen)
        assert "after 5:04" in live_text
    assert live_charts["chart-reward"]  # drawn from the file, every car's episodes

    again = create_app(start="training")
    async with again.run_test(size=(120, 40)) as pilot:
        await settle(pilot)
        restarted = again.screen
        assert isinstance(restarted, TrainingScreen)
        figures = restarted.figures
        await wait_for(pilot, lambda: "ada" in figures and figures["ada"].episodes == 120)
        restart_text, restart_charts = shown(restarted)
    # "finished at" and "last run finished at": the same end, the same clock and figures.
    assert words(restart_text.replace("last run ", "")) == words(live_text)
    assert restart_charts == live_charts


def test_metrics_rows_are_read_once_as_the_file_grows(tmp_path: object) -> None:
    """The live reader continues where it stopped, so a three-hour log is never read
    again whole; a file replaced whole is read again from its first row."""
    from racer_tui.app.screens.training import read_new_rows

    folder = new_model("ada")
    figures = TrainingFigures()
    row = TrainingEpisode(1.0, 1000, 0, 1000, 1, 1, "training", 50.0, "Off track")
    for count in range(1, 4):
        append_training_metrics(folder.training_metrics_file, [row], TrainingMetrics(()))
        figures.take_rows(*read_new_rows(folder, figures.metrics_mark))
        assert figures.episodes == count
    figures.take_rows(*read_new_rows(folder, figures.metrics_mark))
    assert figures.episodes == 3  # nothing new: nothing counted twice
    replaced = folder.training_metrics_file.with_suffix(".new")
    replaced.write_text(json.dumps({"metrics": [vars(row)], "version": 2.0}))
    replaced.replace(folder.training_metrics_file)
    figures.take_rows(*read_new_rows(folder, figures.metrics_mark))
    assert figures.episodes == 1


def test_an_empty_chart_says_why_never_waiting_beside_data() -> None:
    figures = TrainingFigures()
    assert empty_reason(figures, "reward") == "no data yet: press t to train"
    figures.starting()
    assert empty_reason(figures, "reward") == "waiting for data…"
    figures.fold_rows([TrainingEpisode(1.0, 1000, 0, 1000, 1, 1, "training", 50.0, "Off track")])
    # Episodes have ended, none with a lap: the lap-time chart is not waiting, it has none.
    assert empty_reason(figures, "lap-time") == "no training lap yet"
    # An evaluation's greedy policy laps while exploring episodes do not: both are said.
    figures.fold_rows(
        [TrainingEpisode(2.0, 1000, 0, 11_390, 1, 1, "evaluation", 100.0, "Lap complete")]
    )
    assert empty_reason(figures, "lap-time") == "no training lap yet\nevaluation best 11.39 s"
    figures.fold(events.Ended(3.0, "failed", "the reward function raised", 9, 1, 50.0, None))
    assert "failed" in empty_reason(figures, "entropy")


@pytest.mark.parametrize("size", [(120, 40), (80, 24)])
async def test_a_failed_training_says_so_in_its_charts_place(size: tuple[int, int]) -> None:
    # At 80x24 the walk read "the training failed (see a": each chart says it whole.
    new_model("ada")
    app = create_app(start="training")
    async with app.run_test(size=size) as pilot:
        await settle(pilot)
        screen = app.screen
        assert isinstance(screen, TrainingScreen)
        screen.apply_event("ada", events.Ended(1.0, "failed", "the reward function raised",
                                               0, 0, 0.0, None))  # fmt: skip
        charts = screen.query_one(TrainingCharts)
        charts.redraw_now()
        await pilot.pause()
        text = painted(charts)
        assert "waiting for data" not in text
        assert text.count("training failed: see above") == 6


async def test_the_agents_eye_view_has_a_place_at_80x24() -> None:
    """Point 8: below wide sizes the view never appeared; `v` puts it in the charts'
    place, and back."""
    from racer_tui.app.widgets.agent_view import AgentView
    from racer_tui.app.widgets.footer import screen_keys

    new_model("ada")
    app = create_app(start="training")
    async with app.run_test(size=(80, 24)) as pilot:
        await settle(pilot)
        screen = app.screen
        assert isinstance(screen, TrainingScreen)
        view, charts = screen.query_one(AgentView), screen.query_one(TrainingCharts)
        assert not view.region.width and charts.region.width
        assert "Agent's view" in [key.description for key in screen_keys(screen)[0]]
        await pilot.press("v")
        await pilot.pause()
        assert view.region.width > 40 and not charts.region.width
        await pilot.press("v")
        await pilot.pause()
        assert not view.region.width and charts.region.width
    wide = create_app(start="training")
    async with wide.run_test(size=(200, 60)) as pilot:
        await settle(pilot)
        screen = wide.screen
        assert isinstance(screen, TrainingScreen)
        assert screen.query_one(AgentView).region.width  # beside the charts already
        assert "Agent's view" not in [key.description for key in screen_keys(screen)[0]]


def test_the_apps_worker_command_names_one_parent() -> None:
    """Point 13: the worker's command line said `--parent-pid` twice (a real PID, then 0)."""
    from sim.training.launcher import worker_command

    command = worker_command("ada", 5.0, TrainingScreen()._options())
    assert command.count("--parent-pid") == 1
    assert command[command.index("--parent-pid") + 1] == "0"
    assert worker_command("ada", 5.0).count("--parent-pid") == 1  # the command line's own


def test_a_narrow_run_line_says_its_clock_in_words_never_cut() -> None:
    from racer_tui.app.widgets.training_charts import run_line

    figures = TrainingFigures()
    figures.fold(events.Started(0.0, "ada", "hairpin", ("vector",), 8, "scratch", 0, 10.0, 1))
    figures.heard_at(60.0)
    line = run_line(figures, "hairpin-hero", width=40)
    assert str(line) == "hairpin-hero: training 1:00 of 10:00, 9:00 left"
