"""Helpers for the app's Pilot tests: what a widget paints, notifications, trained models."""

from __future__ import annotations

import contextlib
from collections.abc import Callable
from typing import Any

from textual.app import App
from textual.pilot import Pilot
from textual.screen import Screen
from textual.widget import Widget
from textual.worker import WorkerCancelled, WorkerFailed

from sim.garage.folder import ModelFolder
from sim.garage.options import new_model


def painted(widget: Widget) -> str:
    """The text on screen where `widget` is (children, borders and all), line by line.

    Read from the screen's compositor, so it is what the racer sees: a widget on a hidden
    tab or scrolled out of view paints nothing."""
    region = widget.region
    if not region.area:
        return ""
    lines = widget.screen._compositor.render_strips()
    return "\n".join(
        line.crop(region.x, region.right).text for line in lines[region.y : region.bottom]
    )


async def settle(pilot: Pilot[Any]) -> None:
    """Let workers finish and the messages they posted be handled (twice: a handler may
    start another worker, as a saved model reloads the garage)."""
    for _ in range(3):
        for worker in list(pilot.app.workers):
            with contextlib.suppress(WorkerCancelled, WorkerFailed):
                await worker.wait()
        await pilot.pause()


async def wait_for(pilot: Pilot[Any], condition: Callable[[], bool], tries: int = 300) -> None:
    """Let timers run until `condition()` holds (for the looping demo's playback clock);
    up to 15 s of pauses, as a loaded machine (CI's two cores) may need."""
    for _ in range(tries):
        if condition():
            return
        await pilot.pause(0.05)
    raise AssertionError("the app never got there")


class Notifications:
    """Records every notification the app shows (and still shows it)."""

    def __init__(self, app: App[Any]) -> None:
        self.messages: list[tuple[str, str]] = []
        original = app.notify

        def record(message: str, **options: Any) -> None:
            self.messages.append((message, str(options.get("severity", "information"))))
            original(message, **options)

        app.notify = record  # type: ignore[method-assign]

    def text(self, severity: str | None = None) -> str:
        return "\n".join(m for m, s in self.messages if severity is None or s == severity)


def trained_model(name: str, **options: Any) -> ModelFolder:
    """A model with a freshly initialised (untrained, but loadable) policy."""
    from sim.training.policy import build_network, save_policy

    folder = new_model(name, **options)
    save_policy(folder.policy_file, build_network(folder.metadata()))
    return folder


class OneScreenApp(App[None]):
    """An app showing one screen, as a section would push it."""

    def __init__(self, screen: Screen[Any]) -> None:
        super().__init__()
        self.shown = screen

    def on_mount(self) -> None:
        self.push_screen(self.shown)
