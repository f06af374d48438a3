"""The monkey: the real app driven headless with random input, until something breaks.

Issue 42: nothing a person types may crash the app. The monkey builds the app as the
launcher does (`create_app`), in a scratch data home with a few models, and for each action
picks at random (from a seed, so a run can be repeated):
- a key from a weighted alphabet: the section keys, every binding active on the current
  screen, arrows, PageUp/PageDown, Home/End, Tab/Shift+Tab, Enter, Esc, ?, the palette's
  ctrl+p and printable characters;
- a burst of such keys, queued at once as a terminal delivers keys typed quickly
  (`keys_as_delivered.burst`, not Pilot's one-key-then-idle `press`), or of typed text;
- a paste, a mouse click at a random cell, or a resize between 60x20 and 200x60.
After each action it checks that nothing raised (the app's first error, which also writes
its crash report), that the app still runs, that the footer shows the keys its screen has
now (`stale_footer`), and that the screen renders. The quit keys (q,
ctrl+q, ctrl+c) are never pressed; when the app leaves anyway (the palette's Quit command,
typed at random) a new one is started and the run goes on. A crash is recorded with the
actions that led to it, and a new app goes on from there too.

Trainings run in children: by default a stand-in child that exits at once replaces the
worker, so a run costs no training CPU (`real_training=True` keeps the real worker, tiny
budgets are still whatever was typed). Heats run in the app's threads as they do for a
racer. Typed text never holds `/` or `~`, so a path typed into an export dialog is relative
and lands in the scratch folder the monkey works in, never elsewhere.

`python -m benchmarks.app.monkey` is the long run; tests/racer_tui/test_monkey.py the short.
"""

from __future__ import annotations

import contextlib
import os
import random
import string
import sys
import tempfile
import time
import traceback
from collections import Counter
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import psutil
from textual.pilot import OutOfBounds

from racer_tui.app.application import create_app
from racer_tui.app.keys_as_delivered import burst, drain, paste, typed
from racer_tui.app.screens import training
from racer_tui.app.screens.kiosk import KioskScreen, LeaveKiosk
from racer_tui.app.widgets.footer import RacerFooter, screen_keys
from sim.foundation.home import LEAGUE_ENV, home_at
from sim.garage.options import new_model

if TYPE_CHECKING:
    from textual.pilot import Pilot

    from racer_tui.app.application import RacerTuiApp

QUIT_KEYS = frozenset({"q", "ctrl+q", "ctrl+c", "ctrl+z"})  # ctrl+z would stop the process
SECTION_KEYS = ("1", "2", "3", "4", "5")
NAVIGATION = (
    "up", "down", "left", "right", "pageup", "pagedown", "home", "end",
    "tab", "shift+tab", "enter", "escape", "space", "backspace", "delete",
)  # fmt: skip
APP_KEYS = ("question_mark", "ctrl+p", "escape", "enter", "f1")
# Typed text: no `/` or `~` (see the module's note), no q (it quits from a section).
PRINTABLE = string.ascii_letters.replace("q", "") + string.digits + " -_.,:=+"
TEXT_PIECES = ("5", "10", "abc", "my-model", "0.5", "reinvent_base", "on", "light,noise=0.5")
# What a terminal sends, read by Textual's own parser as the app reads it: Esc alone and
# before keys (a host's Esc then `?` or a digit typed quickly), arrows and F1 as escape
# sequences, Enter, Backspace, Tab. No q, and none of the control keys that quit or stop.
TERMINAL_PIECES = (
    "\x1b", "\x1b", "\x1b[A", "\x1b[B", "\x1b[C", "\x1b[D", "\x1bOP", "\x1b[1;5C",
    "\r", "\x7f", "\t", "?", "1", "2", "3", "4", "5", "n", "a", "x", "y", "5", "-", " ",
)  # fmt: skip
MIN_SIZE = (60, 20)
MAX_SIZE = (200, 60)
START_SIZE = (80, 24)
# How often each kind of action is chosen (relative weights).
ACTION_WEIGHTS: dict[str, int] = {
    "key": 44,
    "burst": 24,
    "text": 8,
    "terminal": 4,
    "paste": 4,
    "click": 12,
    "resize": 3,
    "section": 6,
}
KEY_SOURCES: dict[str, int] = {
    "binding": 34,
    "navigation": 36,
    "section": 6,
    "app": 10,
    "printable": 14,
}
NIGHTS_SHARE = 0.3  # of the "section" actions: to the League's nights
MODELS = ("monkey-a", "monkey-b")
WARMUP_ACTIONS = 200  # memory is compared from here (5% of a shorter run)


@dataclass
class Crash:
    """An error the app raised, with what led to it."""

    action_number: int
    error: str  # the exception's last line
    traceback: str
    recent_actions: list[str]
    report: Path | None  # the app's own crash report (in the scratch home: gone after)
    report_text: str  # what it said, kept


@dataclass
class MonkeyRun:
    seed: int
    actions: int = 0
    apps_started: int = 0
    quits: int = 0  # the app left on its own (the palette's Quit): a new one went on
    crashes: list[Crash] = field(default_factory=list)
    kinds: Counter[str] = field(default_factory=Counter)
    screens: Counter[str] = field(default_factory=Counter)
    slowest_action: str = ""
    slowest_ms: float = 0.0
    rss_start_mb: float = 0.0
    rss_after_warmup_mb: float = 0.0  # the app built and its screens seen once or so
    warmup_actions: int = 0
    rss_halfway_mb: float = 0.0  # halfway through the actions after the warm-up
    halfway_actions: int = 0
    rss_end_mb: float = 0.0
    seconds: float = 0.0


def rss_mb() -> float:
    return float(psutil.Process().memory_info().rss) / 1e6


@contextlib.contextmanager
def scratch_home(real_training: bool = False) -> Iterator[Path]:
    """A temporary data home (and working folder) with the monkey's models, the training
    worker swapped for a stand-in unless `real_training`; children it started are stopped
    and everything is removed at the end."""

    before = {child.pid for child in psutil.Process().children(recursive=True)}
    league = os.environ.pop(LEAGUE_ENV, None)  # the league of the scratch home, not another
    with tempfile.TemporaryDirectory(prefix="racer-monkey-") as folder:
        root = Path(folder)
        cwd = Path.cwd()
        os.chdir(root)
        try:
            with home_at(root / "home"), _training_stand_in(not real_training):
                _fill_garage()
                yield root
        finally:
            os.chdir(cwd)
            _stop_children_started_since(before)
            if league is not None:
                os.environ[LEAGUE_ENV] = league


def _fill_garage() -> None:

    for name in MODELS:
        new_model(name)


@contextlib.contextmanager
def _training_stand_in(active: bool) -> Iterator[None]:
    """A training child that exits at once: the app follows it and says it ended."""
    if not active:
        yield
        return

    real = training.__dict__["worker_command"]

    def stand_in(model: str, minutes: float | None = None, extra: Any = ()) -> list[str]:
        return [sys.executable, "-c", "pass"]

    setattr(training, "worker_command", stand_in)  # noqa: B010 - imported there, patched there
    try:
        yield
    finally:
        setattr(training, "worker_command", real)  # noqa: B010


def _stop_children_started_since(before: set[int]) -> None:
    for child in psutil.Process().children(recursive=True):
        if child.pid not in before:
            with contextlib.suppress(psutil.Error):
                child.terminate()
                child.wait(timeout=5)


class Monkey:
    """One app, driven by one random generator; `act` does one action and checks."""

    def __init__(self, app: RacerTuiApp, pilot: Pilot[int], rng: random.Random) -> None:
        self.app = app
        self.pilot = pilot
        self.rng = rng
        self.size = START_SIZE

    # --- choosing --------------------------------------------------------------------------

    def _bindings(self) -> list[str]:
        keys = [key for key in self.app.active_bindings if key not in QUIT_KEYS]
        return keys or list(NAVIGATION)

    def key(self) -> str:
        source = self._weighted(KEY_SOURCES)
        if source == "binding":
            return self.rng.choice(self._bindings())
        if source == "navigation":
            return self.rng.choice(NAVIGATION)
        if source == "section":
            return self.rng.choice(SECTION_KEYS)
        if source == "app":
            return self.rng.choice(APP_KEYS)
        return self.rng.choice(PRINTABLE)

    def text(self) -> str:
        if self.rng.random() < 0.5:
            return self.rng.choice(TEXT_PIECES)
        return "".join(self.rng.choice(PRINTABLE) for _ in range(self.rng.randint(1, 40)))

    def _weighted(self, weights: dict[str, int]) -> str:
        return self.rng.choices(list(weights), weights=list(weights.values()))[0]

    def _on_kiosk(self) -> bool:

        return isinstance(self.app.screen, KioskScreen | LeaveKiosk)

    # --- acting ----------------------------------------------------------------------------

    async def act(self) -> tuple[str, str]:
        """One action; its kind and a description to replay it by."""
        kind = self._weighted(ACTION_WEIGHTS)
        app = self.app
        if kind == "key":
            key = self.key()
            burst(app, [key])
            said = key
        elif kind == "burst":
            keys = [self.key() for _ in range(self.rng.randint(2, 12))]
            burst(app, keys)
            said = " ".join(keys)
        elif kind == "text":
            text = self.text()
            burst(app, list(text))
            said = repr(text)
        elif kind == "terminal":
            sent = "".join(self.rng.choice(TERMINAL_PIECES) for _ in range(self.rng.randint(2, 8)))
            typed(app, sent)
            said = repr(sent)
        elif kind == "section":
            # Back to a section, as a racer finds the way: Esc, or the deliberate leave of
            # a venue screen (which Esc does not leave), then a section's key; now and
            # then on to the League's nights, which random keys found a few times in
            # 20,000 actions (their dialogs are a host's whole evening).
            keys = ["q", "y"] if self._on_kiosk() else ["escape", "escape"]
            if self.rng.random() < NIGHTS_SHARE:
                keys += ["5", "n"]
            else:
                keys.append(self.rng.choice(SECTION_KEYS))
            burst(app, keys)
            said = " ".join(keys)
        elif kind == "paste":
            pasted = self.text()
            paste(app, pasted)
            said = repr(pasted)
        elif kind == "click":
            x, y = self.rng.randrange(self.size[0]), self.rng.randrange(self.size[1])
            try:
                await self.pilot.click(offset=(x, y))
                said = f"({x}, {y})"
            except OutOfBounds:
                # Pilot's own refusal, before any event reaches the app: a screen pushed a
                # moment ago has no size until its first layout (seed 405, action 738). A
                # terminal would deliver the click; the next action will find it laid out.
                width, height = app.screen.size
                said = f"({x}, {y}) not sent: the screen was {width}x{height}"
        else:
            self.size = (
                self.rng.randint(MIN_SIZE[0], MAX_SIZE[0]),
                self.rng.randint(MIN_SIZE[1], MAX_SIZE[1]),
            )
            await self.pilot.resize_terminal(*self.size)
            said = f"{self.size[0]}x{self.size[1]}"
        await drain(self.pilot)
        return kind, f"{kind} {said}"

    def problem(self, screenshot: bool) -> BaseException | None:
        """What went wrong with the app, if anything: its first error, a footer that shows
        other keys than its screen has, or a screen that cannot be drawn."""
        app = self.app
        if app._exception is not None:
            return app._exception
        stale = stale_footer(app)
        if stale is not None:
            return stale
        if app.is_running and screenshot:
            try:
                app.export_screenshot()
            except Exception as error:  # the monkey reports any failure
                return error
        return None


class InvariantError(AssertionError):
    """The app runs, but shows something untrue."""


def stale_footer(app: RacerTuiApp) -> InvariantError | None:
    """The footer must show the keys its screen has now (their enabled state too): a
    footer that still says `space Pause` on a paused race tells the host a key that does
    not do what it says. Checked once the app has handled its input."""
    if not app.is_running or not app.input_settled():
        return None
    screen = app.screen
    for footer in screen.query(RacerFooter):
        shown = (footer.shown_keys, footer.shown_palette)
        keys = screen_keys(screen)
        if shown != keys:
            said = ", ".join(f"{k.display} {k.description}" for k in shown[0])
            has = ", ".join(f"{k.display} {k.description}" for k in keys[0])
            return InvariantError(
                f"the footer of {type(screen).__name__} shows [{said}] but the screen has [{has}]"
            )
    return None


async def run_monkey(
    actions: int,
    seed: int,
    *,
    screenshot_every: int = 1,
    on_progress: Callable[[MonkeyRun], None] | None = None,
    stop_at_first_crash: bool = False,
) -> MonkeyRun:
    """Drive apps (a new one after each quit or crash) for `actions` actions in all; the
    caller provides the scratch home (`scratch_home`)."""

    run = MonkeyRun(seed=seed, rss_start_mb=rss_mb())
    run.warmup_actions = min(WARMUP_ACTIONS, max(actions // 20, 1))
    run.halfway_actions = run.warmup_actions + (actions - run.warmup_actions) // 2
    rng = random.Random(seed)
    started = time.perf_counter()
    recent: list[str] = []
    while run.actions < actions:
        app = create_app()
        run.apps_started += 1
        crash: BaseException | None = None
        try:
            async with app.run_test(size=START_SIZE) as pilot:
                monkey = Monkey(app, pilot, rng)
                await drain(pilot)
                while run.actions < actions and app.is_running:
                    began = time.perf_counter()
                    kind, said = await monkey.act()
                    took = (time.perf_counter() - began) * 1000.0
                    run.actions += 1
                    run.kinds[kind] += 1
                    recent = [*recent[-19:], said]
                    if app.is_running:
                        run.screens[type(app.screen).__name__] += 1
                    if run.actions == run.warmup_actions:
                        run.rss_after_warmup_mb = rss_mb()
                    if run.actions == run.halfway_actions:
                        run.rss_halfway_mb = rss_mb()
                    if took > run.slowest_ms:
                        run.slowest_ms, run.slowest_action = took, said
                    crash = monkey.problem(run.actions % screenshot_every == 0)
                    if crash is not None:
                        break
                    if on_progress is not None:
                        on_progress(run)
                if crash is None and not app.is_running:
                    run.quits += 1
        except Exception as error:  # Pilot re-raises the app's error here
            crash = crash or error
        if crash is not None:
            report = app.crash_report
            run.crashes.append(
                Crash(
                    run.actions,
                    f"{type(crash).__name__}: {crash}",
                    "".join(traceback.format_exception(crash)),
                    list(recent),
                    report,
                    report.read_text(encoding="utf-8") if report is not None else "",
                )
            )
            if stop_at_first_crash:
                break
    run.seconds = time.perf_counter() - started
    run.rss_end_mb = rss_mb()
    return run
