"""The Training section without a training process: events injected as the log tail
applies them (the memray pattern), history from TrainingMetrics.json, the queue, the question
when quitting, and adopting a training an earlier session left running."""

from __future__ import annotations

import contextlib
import json
import os
import re
import signal
import subprocess
import sys
import time
from collections.abc import AsyncIterator, Iterator
from datetime import UTC, datetime, timedelta
from typing import Any

import pytest
from rich.text import Text
from textual.pilot import Pilot

from racer_tui.app.application import create_app
from racer_tui.app.jobs import JobState
from racer_tui.app.screens.training import LeaveWhileTraining, LiveRun, TrainingScreen
from racer_tui.app.widgets.agent_view import Observation
from racer_tui.app.widgets.chart import LineChart
from racer_tui.app.widgets.training_charts import (
    TrainingCharts,
    TrainingFigures,
    run_line,
    training_job,
)
from sim.deepracer.files import (
    TrainingEpisode,
    TrainingMetrics,
    append_training_metrics,
    write_training_metrics,
)
from sim.garage.folder import open_model
from sim.garage.options import new_model
from sim.training import events
from sim.training.run_history import RunHistory
from tests.racer_tui.screens.tui_helpers import Notifications, painted, settle, wait_for


def sample_events() -> list[events.Event]:
    """A short run: three episodes (one lap), an update, a system reading, the end."""
    return [
        events.Started(0.0, "ada", "hairpin", ("vector",), 8, "scratch", 0, 5.0, 4242),
        events.Episode(0.5, 1, 0, 12.0, 40.0, None, "Off track", 90),
        events.Episode(0.9, 2, 0, 30.0, 100.0, 11.25, "Lap complete", 170),
        events.Episode(1.2, 3, 0, 8.0, 25.0, None, "Off track", 60),
        events.Update(
            1.5, 1, 2048, 3, 1.61, -0.01, 0.4, 0.002, 0.1, 5100.0, 3, 16.7, 55.0, 1, 11.25
        ),
        events.System(2.0, 97.0, 310.0),
        events.Ended(3.0, "finished", "the time limit was reached", 2048, 3, 55.0, None),
    ]


def sample_rows() -> list[TrainingEpisode]:
    """The episodes of `sample_events` as the trainer writes them to TrainingMetrics.json."""
    return [
        TrainingEpisode(12.0, 6000, 0, 6000, 1, 1, "training", 40.0, "Off track"),
        TrainingEpisode(30.0, 17250, 6000, 11250, 2, 2, "training", 100.0, "Lap complete"),
        TrainingEpisode(8.0, 21250, 17250, 4000, 3, 3, "training", 25.0, "Off track"),
    ]


def write_rows(folder: Any, rows: list[TrainingEpisode]) -> None:
    """Append rows with the trainer's own writer (its logbook's flush)."""
    append_training_metrics(folder.training_metrics_file, rows, TrainingMetrics(()))


def test_a_run_is_one_job_from_start_to_its_ending() -> None:
    """The run line reads the app's one status model for long jobs: idle, starting,
    running against its budget, then done, stopped or failed with the key that helps."""
    figures = TrainingFigures()
    assert training_job(figures, "ada").state is JobState.IDLE
    figures.starting()
    starting = training_job(figures, "ada")
    assert starting.state is JobState.RUNNING and starting.total is None
    run = sample_events()
    for event in run[:3]:
        figures.fold(event)
    running = training_job(figures, "ada")
    assert (running.state, running.done, running.total) == (JobState.RUNNING, 0.9, 300.0)
    assert running.what == "Training ada"
    for kind, state in (
        ("finished", JobState.DONE),
        ("stopped", JobState.STOPPED),
        ("failed", JobState.FAILED),
    ):
        figures.fold(events.Ended(4.0, kind, "reward_function raised ValueError", 9, 3, 40, None))
        job = training_job(figures, "ada")
        assert (job.state, job.done) == (state, 4.0)
        assert bool(job.fix) is (state is JobState.FAILED)  # only a failure needs a remedy
    line = run_line(figures, "ada")
    assert isinstance(line, Text) and "ada: failed" in line.plain
    assert "Reward_function raised ValueError. Press t to train again." in line.plain
    # The next run is starting: not the last run's clock against its budget.
    figures.starting()
    again = training_job(figures, "ada")
    assert (again.state, again.done, again.total) == (JobState.RUNNING, 0.0, None)
    assert "starting" in str(run_line(figures, "ada"))


def test_figures_fold_metrics_rows_updates_and_endings() -> None:
    figures = TrainingFigures()
    for event in sample_events():
        figures.fold(event)
    # The stream's episodes are one car's sample: the figures come from the metrics rows.
    assert figures.rewards == [] and figures.episodes == 0
    figures.fold_rows(sample_rows())
    assert figures.rewards == [12.0, 30.0, 8.0]
    assert figures.lap_times == [11.25]
    assert figures.statuses == {"Off track": 2, "Lap complete": 1}
    assert figures.completion_rate == pytest.approx(100 / 3)
    assert figures.entropy == [1.61] and figures.steps_per_second == [5100.0]
    assert figures.cpu == [97.0]
    assert figures.ended is not None and figures.ended.kind == "finished"


@contextlib.asynccontextmanager
async def training_section() -> AsyncIterator[tuple[Pilot[Any], TrainingScreen]]:
    """The app on its Training section at 100x30, settled."""
    app = create_app(start="training")
    async with app.run_test(size=(100, 30)) as pilot:
        await settle(pilot)
        screen = app.screen
        assert isinstance(screen, TrainingScreen)
        yield pilot, screen


@pytest.fixture
def sleeper() -> Iterator[subprocess.Popen[bytes]]:
    """A harmless process that looks like a training worker to the screen."""
    process = subprocess.Popen(
        [sys.executable, "-c", "import time; time.sleep(120)", "sim.training.worker"],
        start_new_session=True,
    )
    yield process
    if process.poll() is None:
        process.kill()
    process.wait()


async def test_injected_events_reach_the_charts_and_counters() -> None:
    new_model("ada")
    app = create_app(start="training")
    async with app.run_test(size=(120, 40)) as pilot:
        await settle(pilot)
        screen = app.screen
        assert isinstance(screen, TrainingScreen)
        notes = Notifications(app)
        folder = open_model("ada")
        write_rows(folder, sample_rows())
        history = RunHistory(folder.training_history)
        for event in sample_events():
            history.record(event)  # as the trainer does when it emits an update
            screen.apply_event("ada", event)
            await screen.read_metrics("ada")  # as the log tail does between its lines
        charts = screen.query_one(TrainingCharts)
        charts.redraw_now()
        await pilot.pause()
        assert charts.query_one("#chart-reward", LineChart).values == [12.0, 30.0, 8.0]
        assert charts.query_one("#chart-lap-time", LineChart).values == [11.25]
        assert charts.query_one("#chart-entropy", LineChart).values == [1.61]
        text = painted(charts)
        assert "Off track 2" in text and "Lap complete 1" in text
        assert "process ended" in text and "310 MB" not in text  # the run has finished
        assert "reward: 8.0" in text
        assert "finished" in notes.text()


async def test_the_run_clock_and_time_left_show_at_80x24() -> None:
    # The section header has no room for the run's clock at 80 columns: the dashboard
    # itself says how long the run has gone and how long it has left, then how it ended.
    folder = new_model("ada")
    # An earlier run's updates reach 600 s on its own clock; the new run starts again at 0.
    old = events.System(600.0, 90.0, 300.0)
    folder.training_history.write_text(events.encode(old) + "\n")
    app = create_app(start="training")
    async with app.run_test(size=(80, 24)) as pilot:
        await settle(pilot)
        screen = app.screen
        assert isinstance(screen, TrainingScreen)
        charts = screen.query_one(TrainingCharts)
        await wait_for(pilot, lambda: charts.figures.cpu == [90.0])
        assert "ada: not training now" in painted(charts)  # whose charts these are
        screen.apply_event("ada", sample_events()[0])  # a 5-minute budget
        screen.apply_event("ada", events.Episode(83.0, 1, 0, 12.0, 40.0, None, "Off track", 90))
        charts.redraw_now()
        await pilot.pause()
        text = painted(charts)
        assert "ada: training 1:23 of 5:00" in text and "3:37 left" in text
        screen.apply_event("ada", events.Ended(250.0, "stopped", "stopped by you", 9, 1, 40, None))
        charts.redraw_now()
        await pilot.pause()
        text = painted(charts)
        assert re.search(r"stopped at \d\d:\d\d after 4:10", text) and "left" not in text


async def test_after_a_restart_the_run_line_says_how_and_when_the_last_run_ended() -> None:
    folder = new_model("ada")
    ended = datetime(2026, 11, 20, 21, 5, tzinfo=UTC)
    state = {
        "state": "finished",
        "pid": 999_999_999,
        "started_at": (ended - timedelta(minutes=20)).isoformat(),
        "updated_at": ended.isoformat(),
        "elapsed_seconds": 3600.0,  # every run of the model: the last one was its third
        "steps": 90_000,
        "episodes": 1200,
        "message": "the time limit was reached",
    }
    folder.training_state_file.write_text(json.dumps(state))
    app = create_app(start="training")
    async with app.run_test(size=(80, 24)) as pilot:
        await settle(pilot)
        screen = app.screen
        assert isinstance(screen, TrainingScreen)
        charts = screen.query_one(TrainingCharts)
        charts.redraw_now()
        await pilot.pause()
        at = time.strftime("%H:%M", time.localtime(ended.timestamp()))
        assert f"ada: last run finished at {at} after 20:00" in painted(charts)
        assert "not training now" not in painted(charts)


async def test_charts_show_the_history_in_training_json() -> None:
    folder = new_model("ada")
    rows = [
        TrainingEpisode(float(i), i * 1000, 0, 5000, i, i, "training", 10.0 * i, "Off track")
        for i in range(1, 6)
    ]
    write_training_metrics(folder.training_metrics_file, TrainingMetrics(tuple(rows)))
    app = create_app(start="training")
    async with app.run_test(size=(120, 40)) as pilot:
        await settle(pilot)
        charts = app.screen.query_one(TrainingCharts)
        await wait_for(pilot, lambda: charts.figures.episodes == 5)
        charts.redraw_now()
        assert charts.query_one("#chart-progress", LineChart).values == [10, 20, 30, 40, 50]


async def test_entropy_steps_and_cpu_charts_show_every_run_after_a_restart() -> None:
    # Two earlier runs left their updates and system readings in the model's run history:
    # the charts continue across runs instead of starting again from nothing.
    folder = new_model("ada")
    runs = [
        events.Update(10.0, 1, 2048, 3, 1.7, 0.0, 0.4, 0.0, 0.1, 4000.0, 3, 10.0, 30.0, 0, None),
        events.System(11.0, 90.0, 300.0),
        events.Update(20.0, 2, 4096, 6, 1.6, 0.0, 0.4, 0.0, 0.1, 4100.0, 3, 11.0, 35.0, 0, None),
        events.Update(8.0, 3, 6144, 9, 1.5, 0.0, 0.4, 0.0, 0.1, 4200.0, 3, 12.0, 40.0, 0, None),
        events.System(9.0, 95.0, 310.0),
    ]
    folder.training_history.write_text("".join(events.encode(e) + "\n" for e in runs))
    app = create_app(start="training")
    async with app.run_test(size=(120, 40)) as pilot:
        await settle(pilot)
        charts = app.screen.query_one(TrainingCharts)
        await wait_for(pilot, lambda: len(charts.figures.entropy) == 3)
        charts.redraw_now()
        assert charts.query_one("#chart-entropy", LineChart).values == [1.7, 1.6, 1.5]
        assert charts.query_one("#chart-steps", LineChart).values == [4000, 4100, 4200]
        assert charts.query_one("#chart-cpu", LineChart).values == [90, 95]


async def test_a_second_request_waits_in_the_queue(monkeypatch: pytest.MonkeyPatch) -> None:
    new_model("ada")
    new_model("bob")
    app = create_app(start="training")
    async with app.run_test(size=(120, 40)) as pilot:
        await settle(pilot)
        screen = app.screen
        assert isinstance(screen, TrainingScreen)
        started: list[str] = []
        monkeypatch.setattr(screen, "_run", lambda request: started.append(request.model))
        screen.request_training("ada", 1.0)
        screen.request_training("bob", 1.0)
        assert started == ["ada"]
        assert [request.model for request in screen.queue] == ["bob"]
        screen.live = None
        screen._start_next()
        assert started == ["ada", "bob"]


async def test_quitting_while_training_can_keep_it_running(
    sleeper: subprocess.Popen[bytes],
) -> None:
    new_model("ada")
    async with training_section() as (pilot, screen):
        app = pilot.app
        screen.live = LiveRun("ada", pid=sleeper.pid, minutes=5)
        await pilot.press("q")
        assert isinstance(app.screen, LeaveWhileTraining)
        await pilot.press("k")
        await pilot.pause()
    assert sleeper.poll() is None  # still running after the app has gone


async def test_quitting_while_training_can_stop_it(sleeper: subprocess.Popen[bytes]) -> None:
    new_model("ada")
    async with training_section() as (pilot, screen):
        app = pilot.app
        screen.live = LiveRun("ada", pid=sleeper.pid, minutes=5)
        await pilot.press("q")
        await pilot.press("escape")  # stay: nothing happens
        assert app.is_running and sleeper.poll() is None
        await pilot.press("q", "s")
        await pilot.pause()
    assert sleeper.wait(10) == -signal.SIGTERM


async def test_a_training_left_running_is_shown_again_and_can_be_stopped(
    sleeper: subprocess.Popen[bytes],
) -> None:
    folder = new_model("ada")
    state = {"state": "running", "pid": sleeper.pid, "message": "training"}
    folder.training_state_file.write_text(json.dumps(state))
    app = create_app(start="training")
    async with app.run_test(size=(120, 40)) as pilot:
        # Not `settle`: the worker following the adopted run lasts as long as the run.
        screen = app.screen
        assert isinstance(screen, TrainingScreen)
        await wait_for(pilot, lambda: screen.live is not None and screen.rows != [])
        assert screen.live is not None and screen.live.pid == sleeper.pid
        assert "training" in painted(screen.query_one("#training-models"))
        await pilot.press("s")
        assert sleeper.wait(10) == -signal.SIGTERM
        await wait_for(pilot, lambda: screen.live is None, tries=200)
    assert not os.path.exists(f"/proc/{sleeper.pid}/status") or sleeper.poll() is not None


async def test_an_adopted_training_that_is_killed_says_so_instead_of_running_on(
    sleeper: subprocess.Popen[bytes],
) -> None:
    # A run the command line started, 75 s in; then it is killed (out of memory, kill -9)
    # and never writes its last event.
    folder = new_model("ada")
    state = {"state": "running", "pid": sleeper.pid, "message": "training"}
    folder.training_state_file.write_text(json.dumps(state))
    started = events.Started(0.0, "ada", "hairpin", ("vector",), 8, "scratch", 0, 5.0, 4242)
    episode = events.Episode(75.0, 1, 0, 12.0, 40.0, None, "Off track", 90)
    folder.training_log.write_text(events.encode(started) + "\n" + events.encode(episode) + "\n")
    app = create_app(start="training")
    async with app.run_test(size=(120, 40)) as pilot:
        notes = Notifications(app)
        screen = app.screen
        assert isinstance(screen, TrainingScreen)
        await wait_for(pilot, lambda: screen.live is not None and screen.rows != [])
        charts = screen.query_one(TrainingCharts)
        await wait_for(pilot, lambda: "left" in painted(charts))
        assert "training 1:15 of 5:00" in painted(charts)
        sleeper.kill()
        await wait_for(pilot, lambda: screen.live is None, tries=200)
        charts.redraw_now()
        await pilot.pause()
        shown = painted(charts)
        assert "left" not in shown
        assert re.search(r"failed at \d\d:\d\d after 1:15", shown)  # not 0:00
        # Why, and what to do, stay on the dashboard after the notification has gone.
        assert "ended without writing how" in " ".join(shown.split())
        assert "Press t to train again" in " ".join(shown.split())
        assert "ended without writing how" in notes.text("error")


def test_the_agents_eye_view_draws_camera_and_lidar() -> None:
    import numpy as np

    from racer_tui.app.widgets.agent_view import half_block_lines, observe_at, polar_lines

    track = new_model("ada").track()
    x, y = (float(v) for v in track.points[0, :2])
    toward = track.points[1, :2] - track.points[0, :2]
    yaw = float(np.degrees(np.arctan2(toward[1], toward[0])))
    camera = observe_at(track, ("vector",), (x, y, yaw), "start")
    assert camera.frame is not None and camera.frame.std() > 0  # road and borders differ
    lines = half_block_lines(camera.frame, 32, 12)
    assert 1 <= len(lines) <= 12 and all(line.cell_length <= 32 for line in lines)
    lidar = observe_at(track, ("lidar",), (x, y, yaw), "start")
    assert lidar.ranges is not None and lidar.angles_deg is not None
    from rich.style import Style

    polar = polar_lines(lidar.ranges, lidar.angles_deg, lidar.max_range, (30, 10), Style())
    text = "".join(line.text for line in polar)
    assert "▲" in text and any(0x2800 < ord(ch) <= 0x28FF for ch in text)  # hits drawn


async def test_the_agents_eye_views_caption_wraps_instead_of_being_cut() -> None:
    """A vector model's view says what the model sees; in a narrow pane it takes two lines
    rather than losing its end."""
    import numpy as np
    from textual.app import App, ComposeResult

    from racer_tui.app.widgets.agent_view import AgentView, observe_at

    track = new_model("ada").track()
    x, y = (float(v) for v in track.points[0, :2])
    observation = observe_at(track, ("vector",), (x, y, 0.0), "step 12 of episode 3")
    view = AgentView()

    class Pane(App[None]):
        def compose(self) -> ComposeResult:
            yield view

    async with Pane().run_test(size=(30, 16)) as pilot:
        view.show(observation)
        await pilot.pause()
        shown = " ".join(painted(view).split())
        assert "camera (the model sees the vector state) · step 12 of episode 3" in shown
        assert np.asarray(observation.frame).size > 0


def test_the_agents_eye_view_comes_from_the_newest_traced_step(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from dataclasses import replace

    from racer_tui.app.screens import training
    from sim.deepracer.files import SimTraceRow, sim_trace_text
    from sim.physics.simulation import LOOK_AHEAD

    folder = new_model("ada")
    folder.training_trace_dir.mkdir()
    # The trace's X, Y is DeepRacer's point ahead of the car, as simapp writes it.
    car_x, car_y, yaw = 3.0, 0.7, 90.0
    row = SimTraceRow(
        41, 7, car_x, car_y + LOOK_AHEAD, yaw, 0, 1, 0, 0, False, True, 3, 1, 17.7, 5.0, "prepare"
    )
    (folder.training_trace_dir / "3-iteration.csv").write_text(sim_trace_text([row]))
    newest = sim_trace_text([row, replace(row, steps=8, episode_status="in_progress")])
    (folder.training_trace_dir / "12-iteration.csv").write_text(newest)
    poses: list[tuple[float, float, float]] = []

    def observe(
        track: object,
        sensors: object,
        pose: tuple[float, float, float],
        caption: str,
        objects: object = None,
    ) -> str:
        poses.append(pose)
        assert objects is None  # a time trial's model: nothing on the track
        return caption

    monkeypatch.setattr(training, "observe_at", observe)
    assert training.latest_observation(folder) == "iteration 12, episode 41 step 8"
    ((x, y, heading),) = poses  # seen from the car itself, not from the point ahead
    assert (x, y, heading) == (pytest.approx(car_x), pytest.approx(car_y), yaw)


async def test_a_training_started_from_the_command_line_appears_without_a_key(
    sleeper: subprocess.Popen[bytes],
) -> None:
    folder = new_model("ada")
    app = create_app(start="training")
    async with app.run_test(size=(120, 40)) as pilot:
        await settle(pilot)
        screen = app.screen
        assert isinstance(screen, TrainingScreen)
        assert screen.live is None
        # What `racer-tui train ada` leaves while it runs: its state, its event log and
        # the model's run history (the trainer's updates and system readings).
        so_far = sample_events()[:-1]
        folder.training_log.write_text("".join(events.encode(e) + "\n" for e in so_far))
        kept = [e for e in so_far if isinstance(e, events.Update | events.System)]
        folder.training_history.write_text("".join(events.encode(e) + "\n" for e in kept))
        state = {"state": "running", "pid": sleeper.pid, "message": "training"}
        folder.training_state_file.write_text(json.dumps(state))
        await wait_for(pilot, lambda: screen.live is not None, tries=400)
        assert screen.live is not None and screen.live.pid == sleeper.pid
        await wait_for(pilot, lambda: "training" in painted(screen.query_one("#training-models")))
        # Its figures come from the log: entropy, steps/s and CPU, not only episodes.
        await wait_for(pilot, lambda: screen.figures["ada"].cpu == [97.0], tries=200)
        figures = screen.figures["ada"]
        assert figures.entropy == [1.61] and figures.steps_per_second == [5100.0]
        sleeper.terminate()


async def test_a_training_far_past_its_budget_is_stopped_by_the_app(
    sleeper: subprocess.Popen[bytes],
) -> None:
    # A child hung where its own clock cannot stop it: the app does, and says so.
    new_model("ada")
    async with training_section() as (pilot, screen):
        app = pilot.app
        notes = Notifications(app)
        screen.live = LiveRun("ada", pid=sleeper.pid, minutes=1, started=time.monotonic() - 60)
        screen._tick()
        assert sleeper.poll() is None  # within its budget and grace: left alone
        screen.live.started = time.monotonic() - 60 - 60 - 6 - 1  # budget, grace, a second
        screen._tick()
        assert sleeper.wait(timeout=10) == -signal.SIGTERM
        assert "ran well past its 1-minute budget; stopping it" in notes.text("warning")


MISSING_TRACK = events.Ended(
    0.0,
    "failed",
    "model 'ada' trains on track 'zzqxw': there is no track named 'zzqxw'; give a name that "
    "`racer-tui tracks list` shows, or the path of a DeepRacer .npy file",
    0,
    0,
    0.0,
    None,
    problem="model 'ada' trains on track 'zzqxw': there is no track named 'zzqxw'",
    fix="CHOOSE_TRACK",
)


def says_the_apps_remedy(text: str) -> bool:
    flat = " ".join(text.split())
    return (
        "there is no track named 'zzqxw'; press e in the Garage to choose another" in flat
        and "Press t to train again." in flat
        and "racer-tui" not in flat
    )


async def test_a_failed_training_says_the_apps_remedy_live_and_after_a_restart() -> None:
    """The child writes the command line's sentence and, apart, the problem and its remedy:
    the app offers its own key, never a shell command, in its toast and its run line, and
    again from the trainer's state file after a restart."""
    folder = new_model("ada")
    app = create_app(start="training")
    async with app.run_test(size=(120, 40)) as pilot:
        notes = Notifications(app)
        await settle(pilot)
        screen = app.screen
        assert isinstance(screen, TrainingScreen)
        screen.apply_event("ada", MISSING_TRACK)
        charts = screen.query_one(TrainingCharts)
        charts.redraw_now()
        assert "press e in the Garage to choose another" in notes.text("error")
        assert "racer-tui" not in notes.text("error")
        # Its run line, once laid out (a longer text takes a frame to get its height).
        await wait_for(pilot, lambda: says_the_apps_remedy(painted(charts)))
    state = {
        "state": "failed",
        "pid": 999_999_999,
        "started_at": datetime(2026, 11, 20, 21, 0, tzinfo=UTC).isoformat(),
        "updated_at": datetime(2026, 11, 20, 21, 1, tzinfo=UTC).isoformat(),
        "message": MISSING_TRACK.message,
        "problem": MISSING_TRACK.problem,
        "fix": MISSING_TRACK.fix,
    }
    folder.training_state_file.write_text(json.dumps(state))
    app = create_app(start="training")
    async with app.run_test(size=(120, 40)) as pilot:
        await settle(pilot)
        charts = app.screen.query_one(TrainingCharts)
        charts.redraw_now()
        await wait_for(pilot, lambda: says_the_apps_remedy(painted(charts)))
        assert "last run failed" in painted(charts)
    # A state file naming a remedy this racer-tui does not know keeps the message as is.
    folder.training_state_file.write_text(json.dumps({**state, "fix": "WIPE_DISK"}))
    from racer_tui.app.screens.training import last_ending

    ended, _ = last_ending(folder)
    assert ended is not None and ended.remedy is None and ended.message == MISSING_TRACK.message


def test_the_counters_count_every_cars_episodes() -> None:
    """The metrics file holds every car's episodes; the trainer's own count in its updates
    runs a write ahead of the file: the larger is shown, never the stream's one-car share."""
    from racer_tui.app.widgets.training_charts import counters

    figures = TrainingFigures()
    figures.fold_rows(sample_rows())
    assert counters(figures).plain.startswith("3 episodes  ")
    figures.fold(
        events.Update(2.0, 2, 9000, 11418, 1.5, 0, 0.4, 0, 0.1, 5000.0, 40, 16.0, 50.0, 1, None)
    )
    assert counters(figures).plain.startswith("11,418 episodes  ")
    alone = TrainingFigures()
    alone.fold_rows(sample_rows()[:1])
    assert counters(alone).plain.startswith("1 episode  ")


def test_a_finished_run_shows_no_process_figures_as_if_live() -> None:
    """The host walk: a run that had ended still said its last CPU and memory."""
    from racer_tui.app.widgets.training_charts import counters

    figures = TrainingFigures()
    figures.fold(events.System(2.0, 97.0, 310.0))
    assert "CPU 97%  mem 310 MB" in counters(figures).plain
    figures.fold(events.Ended(3.0, "finished", "the time limit was reached", 2048, 3, 55.0, None))
    said = counters(figures).plain
    assert "process ended" in said and "CPU" not in said and "310" not in said


def test_the_agents_eye_view_shows_boxes_that_stand_still_and_says_when_it_cannot() -> None:
    import math
    from dataclasses import replace

    import numpy as np

    from racer_tui.app.screens import training
    from sim.deepracer.files import SimTraceRow, sim_trace_text, write_training_params
    from sim.physics.objects.seen import SeenObjects, write_seen
    from sim.physics.simulation import LOOK_AHEAD
    from sim.sensors import camera_scene as scene

    folder = new_model("dodger", sensors=["camera"])
    params = folder.training_params()
    fixed = replace(
        params,
        race_type="OBJECT_AVOIDANCE",
        extra={**params.extra, "OBJECT_POSITIONS": ["0.1,1"]},
    )
    write_training_params(folder.training_params_file, fixed)
    folder.training_trace_dir.mkdir()
    track = folder.track()
    box_s = 0.1 * track.length
    x, y = track.centerline.point_at(np.array([box_s - 1.0]))[0].tolist()
    dx, dy = track.centerline.direction_at(np.array([box_s - 1.0]))[0].tolist()
    yaw = math.degrees(math.atan2(dy, dx))
    ahead_x = x + LOOK_AHEAD * math.cos(math.radians(yaw))
    ahead_y = y + LOOK_AHEAD * math.sin(math.radians(yaw))
    row = SimTraceRow(
        1, 4, ahead_x, ahead_y, yaw, 0, 1, 0, 1.0, False, True, 1, 0, track.length, 1.0,
        "in_progress",
    )  # fmt: skip
    (folder.training_trace_dir / "1-iteration.csv").write_text(sim_trace_text([row]))
    seen = training.latest_observation(folder)
    assert isinstance(seen, Observation) and seen.frame is not None
    assert (seen.frame == scene.BOX_SIDE).sum() > 100  # the box a metre ahead

    shuffled = replace(
        params,
        race_type="OBJECT_AVOIDANCE",
        extra={**params.extra, "NUMBER_OF_OBSTACLES": 3, "RANDOMIZE_OBSTACLE_LOCATIONS": True},
    )
    write_training_params(folder.training_params_file, shuffled)
    seen = training.latest_observation(folder)
    assert isinstance(seen, Observation) and "its shuffled boxes are not shown" in seen.caption

    # The trainer kept where they stood at this row: drawn there. A bot car there instead.
    box_yaw = math.atan2(dy, dx)
    for bots, tone in ((False, scene.BOX_SIDE), (True, scene.BOT_CAR_SIDE)):
        box_x, box_y = track.centerline.point_at(np.array([box_s]))[0].tolist()
        write_seen(folder.path, SeenObjects(1, 4, bots, ((box_x, box_y, box_yaw),)))
        seen = training.latest_observation(folder)
        assert isinstance(seen, Observation) and seen.frame is not None
        assert "not shown" not in seen.caption
        assert (seen.frame == tone).sum() > 100
    # Kept for another row (the trace moved on): not drawn, and the caption says so.
    write_seen(folder.path, SeenObjects(1, 5, False, ((box_x, box_y, box_yaw),)))
    seen = training.latest_observation(folder)
    assert isinstance(seen, Observation) and "not shown" in seen.caption
