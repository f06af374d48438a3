"""SVG snapshots of the Training section and the evaluation screen with injected events
(no process, no weights), at 80x24 and 120x40. Update with --snapshot-update after a
deliberate change, and look at the SVGs before committing."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from textual.pilot import Pilot
from textual.widgets import Input

from racer_tui.app.application import create_app
from racer_tui.app.screens.training import TrainingScreen
from racer_tui.app.widgets.training_charts import TrainingCharts
from sim.deepracer.files import TrainingEpisode, TrainingMetrics, append_training_metrics
from sim.garage.folder import open_model
from sim.garage.options import new_model
from sim.training import events
from tests.racer_tui.screens.tui_helpers import settle
from tests.racer_tui.snapshots.sizes import SIZES

Compare = Callable[..., bool]


def a_run() -> list[events.Event]:
    """A deterministic run: 120 episodes that slowly learn, updates and system readings."""
    out: list[events.Event] = [
        events.Started(0.0, "hairpin-hero", "hairpin", ("vector",), 64, "scratch", 0, 10.0, 1)
    ]
    for i in range(1, 121):
        progress = min(100.0, 8.0 + 0.8 * i + (i * 37 % 11))
        lap = 14.0 - i * 0.02 if progress >= 100 else None
        status = "Lap complete" if lap else ("Off track" if i % 5 else "Reversed")
        out.append(events.Episode(i * 0.5, i, 0, progress * 0.6, progress, lap, status, 100))
        if i % 10 == 0:
            out.append(
                events.Update(i * 0.5, i // 10, i * 800, i, 1.7 - i * 0.006, -0.01, 0.3,
                              0.004, 0.1, 5000.0 + (i * 13 % 400), 10, 30.0, 60.0, 1, None)
            )  # fmt: skip
            out.append(events.System(i * 0.5, 96.0 + (i % 3), 300.0 + i * 0.2))
    return out


def as_row(episode: events.Episode) -> TrainingEpisode:
    """An episode as the trainer's logbook writes it to TrainingMetrics.json."""
    ms = round((episode.lap_time or episode.steps / 15) * 1000)
    end = round(episode.elapsed * 1000)
    return TrainingEpisode(
        episode.reward, end, end - ms, ms, episode.episode, episode.episode, "training",
        episode.progress, episode.status,
    )  # fmt: skip


@SIZES
def test_training_with_a_run(snap_compare: Compare, size: tuple[int, int]) -> None:
    new_model("hairpin-hero")
    new_model("lidar-lou", sensors=["lidar"], track="speedway", continuous=True)

    async def inject(pilot: Pilot[Any]) -> None:
        await settle(pilot)
        screen = pilot.app.screen
        assert isinstance(screen, TrainingScreen)
        # The episodes in the model's metrics file, as the trainer writes them; the
        # stream's events through the screen, as the log tail applies them.
        run = a_run()
        append_training_metrics(
            open_model("hairpin-hero").training_metrics_file,
            [as_row(event) for event in run if isinstance(event, events.Episode)],
            TrainingMetrics(()),
        )
        for event in run:
            screen.apply_event("hairpin-hero", event)
        await screen.read_metrics("hairpin-hero")
        charts = screen.query_one(TrainingCharts)
        charts.show(screen.figures["hairpin-hero"], "hairpin-hero")
        charts.redraw_now()
        await pilot.pause()

    app = create_app(start="training")
    assert snap_compare(app, terminal_size=size, run_before=inject)


@SIZES
def test_evaluation_screen(snap_compare: Compare, size: tuple[int, int]) -> None:
    new_model("hairpin-hero")

    async def open_it(pilot: Pilot[Any]) -> None:
        await settle(pilot)
        await pilot.press("e")
        await pilot.pause()
        pilot.app.screen.query_one(Input).cursor_blink = False

    app = create_app(start="training")
    assert snap_compare(app, terminal_size=size, run_before=open_it)
