"""The racer-tui Textual app: sections (garage, tracks, races) as Textual modes, a first-run
welcome with a live demo race, a help screen and a command palette built from BINDINGS.

`create_app()` is the one factory: the CLI (`run_app`), the Pilot tests and the snapshot
tests all build the app through it. This is the module that imports Textual; the headless
CLI never imports it (tests/test_architecture.py checks both).
"""

from __future__ import annotations

import asyncio
import time
from collections import deque
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import Any, ClassVar

from textual import events, on
from textual.app import App, ScreenStackError
from textual.binding import Binding, BindingType
from textual.command import CommandPalette
from textual.dom import DOMNode
from textual.message_pump import MessagePump
from textual.notifications import Notify
from textual.screen import Screen
from textual.widget import AwaitMount, Widget
from textual.widgets import DataTable
from textual.worker import WorkerState

from racer_tui.app.crash_report import (
    EXIT_CRASH,
    RecentKeys,
    drop_unread_keys,
    now,
    report_text,
    say_crash,
    write_report,
)
from racer_tui.app.long_running import (
    CALM_SECONDS,
    CHECK_SECONDS,
    FREEZE_AFTER_SECONDS,
    IdleCollector,
    favour_the_interface,
    freeze_long_lived,
    limit_malloc_arenas,
    malloc_trim,
    memoise_background_styles_by_colour,
)
from racer_tui.app.palette import PaletteCommand, RacerCommands
from racer_tui.app.removed_widget_clicks import ignore_clicks_on_removed_widgets
from racer_tui.app.rendered_lines import let_removed_widgets_lines_go, make_strip_caches_lazy
from racer_tui.app.screens.base import ModelAdded, push_kept
from racer_tui.app.screens.coach import CoachScreen
from racer_tui.app.screens.dialogs import ConfirmDialog, ImportDialog, InputDialog, ask
from racer_tui.app.screens.evaluation import EvaluationScreen
from racer_tui.app.screens.garage import GarageScreen
from racer_tui.app.screens.help import HelpScreen, HelpTopic, binding_topics, declared_bindings
from racer_tui.app.screens.league import LeagueScreen
from racer_tui.app.screens.match_timekeeper import MatchTimekeeperScreen
from racer_tui.app.screens.model_editor import ModelEditorScreen
from racer_tui.app.screens.night_projector import NightProjectorScreen
from racer_tui.app.screens.nights import AddEntrantDialog, NewNightDialog, NightsScreen
from racer_tui.app.screens.projector import ProjectorScreen
from racer_tui.app.screens.race_screen import RaceScreen
from racer_tui.app.screens.races import RacesScreen
from racer_tui.app.screens.sync import SyncScreen
from racer_tui.app.screens.timekeeper import TimekeeperScreen
from racer_tui.app.screens.tracks import TracksScreen
from racer_tui.app.screens.training import RUN_GROUP as TRAINING_RUN_GROUP
from racer_tui.app.screens.training import LeaveWhileTraining, TrainingScreen
from racer_tui.app.screens.welcome import WelcomeScreen
from racer_tui.app.sections import SECTIONS, WELCOME_MODE, section_for
from racer_tui.app.textual_workarounds import apply_workarounds
from sim.foundation.home import data_home
from sim.garage.folder import list_models

SECTION_SCREENS: dict[str, type[Screen[Any]]] = {
    "garage": GarageScreen,
    "tracks": TracksScreen,
    "races": RacesScreen,
    "training": TrainingScreen,
    "league": LeagueScreen,
}
# Screens that are not sections but have keys of their own, for the help screen.
OTHER_SCREENS: tuple[tuple[str, type[DOMNode]], ...] = (
    ("Welcome", WelcomeScreen),
    ("Model editor", ModelEditorScreen),
    ("Race view", RaceScreen),
    ("League nights", NightsScreen),
    ("Timekeeper (a physical car's heat)", TimekeeperScreen),
    ("Timekeeper of a bracket match (two physical cars)", MatchTimekeeperScreen),
    ("Night projector", NightProjectorScreen),
    ("Evaluation", EvaluationScreen),
    ("Coach (a lap against the limit lap)", CoachScreen),
    ("Projector", ProjectorScreen),
    ("Shared store (sync)", SyncScreen),
    ("League night dialogs", NewNightDialog),
    ("Add entrant dialog", AddEntrantDialog),
    ("Confirm dialog", ConfirmDialog),
    ("Input dialogs", InputDialog),
    ("Import dialog", ImportDialog),
    ("Help", HelpScreen),
    ("Tables", DataTable),
)
EVERYWHERE = "Everywhere"
# A key waits for the one before it (see `_ready_for_input`): first by yielding to the
# widgets at work, then by polling; a key lost on its way stops holding the next after:
HELD_KEY_YIELDS = 200
HELD_KEY_POLL_SECONDS = 0.002
KEY_FLIGHT_SECONDS = 5.0  # a key neither stopped nor back at the app by then was lost
# Once a key is used, the next waits for what it set off (messages on the way up from the
# widget it went to: a field's Submitted that moves the focus), this long at most: a screen
# whose timers keep it busy must not slow the keys.
CONSEQUENCE_WAIT_SECONDS = 0.25
READY_WAIT_SECONDS = 3.0  # keys wait this long at most for a screen to be ready for them
HELD_KEY_CHECKS = HELD_KEY_YIELDS + int(KEY_FLIGHT_SECONDS / HELD_KEY_POLL_SECONDS) + 1
HELP_SCREEN = "help"  # the installed help screen's name
# ctrl+p as a palette closes waits this long at most for it to be gone, looking this often.
PALETTE_WAIT_SECONDS = 2.0
PALETTE_RETRY_SECONDS = 0.02


def _section_bindings() -> list[BindingType]:
    return [
        Binding(
            section.key,
            f"switch_section({section.mode!r})",
            section.title,
            # Like q, from a section's own screen only (see `check_action`): Help says so.
            tooltip=f"{section.summary}; from a section's own screen",
            show=False,
        )
        for section in SECTIONS
    ]


def _busy(node: MessagePump) -> bool:
    """`node` has messages waiting or one in hand, or callbacks for after it."""
    return (
        not node._message_queue.empty()
        or node._pending_message is not None
        or bool(node._next_callbacks)
    )


class RacerTuiApp(App[int]):
    """The whole app. Each section is a mode with its own screen stack, so leaving the
    garage for the tracks and coming back finds the garage as it was left."""

    TITLE = "racer-tui"
    CSS_PATH = "app.tcss"
    COMMANDS: ClassVar[set[type[Any] | Callable[[], type[Any]]]] = {
        *App.COMMANDS,
        RacerCommands,
    }
    MODES: ClassVar[dict[str, str | Callable[[], Screen[Any]]]] = {
        WELCOME_MODE: WelcomeScreen,
        **SECTION_SCREENS,
    }
    BINDINGS: ClassVar[list[BindingType]] = [
        *_section_bindings(),
        Binding("question_mark,f1", "help", "Help", tooltip="Every key of every screen"),
        Binding("q", "quit", "Quit", tooltip="From a section's own screen"),
        # Textual binds ctrl+q to "quit", which `check_action` allows only on a section's
        # screen (so a stray q never leaves an editor or a heat): ctrl+q quits from any.
        Binding(
            "ctrl+q", "quit_anywhere", "Quit", tooltip="From any screen", show=False, priority=True
        ),
    ]

    def __init__(
        self,
        *,
        start: str | None = None,
        long_running: bool = False,
        projector_night: str | None = None,
        db_path: Path | None = None,
    ) -> None:
        """`start` forces the first mode (tests); by default the garage, or the welcome
        screen when the garage is empty. `long_running` is the app a racer or host keeps
        open for hours: it tunes garbage collection for that (`racer_tui.app.long_running`);
        tests build many apps in one process and leave it off. `projector_night` opens
        on that night's projector (`racer-tui night projector`), in league `db_path`."""
        apply_workarounds()
        super().__init__()
        self.start_mode = start
        self.projector_night = projector_night
        self.db_path = db_path
        self.long_running = long_running
        self._frozen_modes: set[str] = set()
        self._stacks_seen: tuple[int, ...] = ()  # the screens open at the last idle check
        self._stacks_changed_at = 0.0
        self.calm_clock: Callable[[], float] = time.monotonic  # a test moves its own
        self._switching_to_shown_mode = False
        self.collector = IdleCollector(trim=malloc_trim())
        self.recent_keys = RecentKeys()
        self._held_input: deque[events.Key | events.Paste] = deque()  # one key at a time
        self._key_in_flight: events.Key | None = None
        self._palette_due = False  # ctrl+p waits for a closing palette (`_open_palette`)
        self._key_sent_to: MessagePump | None = None  # the widget the key in flight went to
        self._key_sent_at = 0.0
        self._key_handled_at: float | None = None  # when the key in flight was used
        self._unready_since: tuple[Screen[Any], float] | None = None  # the screen, since when
        self._release_task: asyncio.Task[None] | None = None
        self.crash_report: Path | None = None  # written on the first unexpected error
        self.crash_report_problem: str | None = None  # why it could not be written
        memoise_background_styles_by_colour()  # for every app: tests keep many in one process
        make_strip_caches_lazy()
        let_removed_widgets_lines_go()
        ignore_clicks_on_removed_widgets()
        if long_running:
            limit_malloc_arenas()  # before the app starts its worker threads
            favour_the_interface()

    def on_mount(self) -> None:
        first = self.start_mode or self._first_mode()
        self.switch_mode(first)
        self._freeze_after_first_visit(first)
        if self.projector_night is not None:
            self.push_screen(NightProjectorScreen(self.projector_night, db_path=self.db_path))
        if self.long_running:
            self.collector.start()
            self.set_interval(CHECK_SECONDS, self._collect_when_idle, name="idle-collector")

    def _collect_when_idle(self) -> None:
        # Calm (only the sections open, no work in a thread, no screen come or gone for a
        # few seconds): what survives a sweep lives on, so it may be frozen. A key the
        # driver has posted but the app has not handled yet would wait for the collection:
        # the timer runs outside the app's queue, so it looks there first, and at the keys
        # the app holds back until the one in flight is handled.
        keys_waiting: bool = not self._message_queue.empty() or not self.input_settled()
        self.collector.tick(quiet=self._calm(), keys_waiting=keys_waiting)

    def _calm(self) -> bool:
        """Nothing transient is alive to be frozen by a sweep: only the sections are open,
        no worker runs (a heat, a sync, a reload; following a training is no transient
        work), and no screen has come or gone for `CALM_SECONDS` (what a closed dialog or
        race view built is still being let go)."""
        now = self.calm_clock()
        stacks = tuple(id(screen) for stack in self._screen_stacks.values() for screen in stack)
        if stacks != self._stacks_seen:
            self._stacks_seen, self._stacks_changed_at = stacks, now
        if now - self._stacks_changed_at < CALM_SECONDS or not self._quiet():
            return False
        return not any(
            worker.state is WorkerState.RUNNING and worker.group != TRAINING_RUN_GROUP
            for worker in self.workers
        )

    @on(Notify)
    def _say_it_once(self, message: Notify) -> None:
        """A sentence already on screen is not stacked again: screens that each open the
        league said "newer schema" in three identical notes (the host walk)."""
        new = message.notification
        if any(
            (shown.message, shown.title, shown.severity) == (new.message, new.title, new.severity)
            for shown in self._notifications  # Textual's own: it drops those timed out
        ):
            message.prevent_default()  # Textual's handler, which would add it, is skipped

    def on_unmount(self) -> None:
        self.collector.stop()
        if self._release_task is not None:
            self._release_task.cancel()

    async def on_event(self, event: events.Event) -> None:
        if isinstance(event, events.InputEvent):
            self.collector.input_seen()
        if isinstance(event, events.Key | events.Paste) and not event.is_forwarded:
            if isinstance(event, events.Key):
                self.recent_keys.key(event.key)
            else:
                self.recent_keys.paste(event.text)
            # After a key a widget used, the next goes through the app's queue: behind what
            # that key set off there (a field's focus moves by a callback queued on the app).
            if self._held_input or self._key_in_flight is not None or not self._ready_for_input():
                self._hold(event)
                return
            await self._deliver(event)
            return
        await super().on_event(event)
        if event is self._key_in_flight:  # back up at the app, its bindings checked: used
            self._key_used()

    # --- one key at a time --------------------------------------------------------------------

    # Keys typed quickly arrive in one read from the terminal, and Textual hands each to the
    # focused widget as soon as it comes, before the keys ahead of it have been handled. A
    # key's binding runs only once the key has bubbled back up to the app, so the keys after
    # one that opens a dialog went to the screen below, or to a dialog not yet mounted and
    # focused, and were lost (issue 42: `t`, Backspace Backspace 5 left the Train dialog's
    # field empty; a paste the same). The app hands over one key at a time instead: the
    # next waits while the last is in flight (not yet stopped by a widget or handled by the
    # app), while the screen on top has not mounted, or while its first list has not landed
    # (`t` before the Garage's models are read found none); waiting keys keep their order.

    def input_settled(self) -> bool:
        """Every key and paste received has been handled, bindings included (for `drain`)."""
        return not self._held_input and self._ready_for_input()

    def _ready_for_input(self) -> bool:
        if self._palette_due:  # the keys after ctrl+p are for the palette about to open
            return False
        try:
            screen = self.screen
        except ScreenStackError:  # starting or stopping: Textual's own handling says what
            return True
        if not screen.is_mounted or not self._screen_ready(screen):
            return False
        event = self._key_in_flight
        if event is None:
            return True
        if self._key_lost():
            self._key_in_flight = None  # lost: the next key may go
            return True
        if event._stop_propagation:
            self._key_used()  # by a widget
        # Used, and what it set off done: the next may go. The key stays "in flight" until
        # the next is sent, so that each check looks again (a binding's action may run a
        # moment after its key was stopped, and post more).
        return self._key_handled_at is not None and (
            not self._key_consequences_pending()
            or time.monotonic() - self._key_handled_at > CONSEQUENCE_WAIT_SECONDS
        )

    def _key_used(self) -> None:
        if self._key_handled_at is None:
            self._key_handled_at = time.monotonic()

    def _key_consequences_pending(self) -> bool:
        """Messages wait on the way from the widget the last key went to up to its screen:
        what the key set off is not done yet. Enter in a field posts Submitted, and the
        dialog moves the focus when it hears it; the keys typed right after Enter belong to
        the field it moves to (issue 42: "cy Enter reference" gave racer "cyre")."""
        target = self._key_sent_to
        if not isinstance(target, DOMNode) or not target.is_attached:
            return False
        if any(_busy(node) for node in target.ancestors_with_self if node is not self):
            return True
        # The palette chooses a command in its list, beside the field the key went to:
        # Enter there closes it a few messages later, and a ctrl+p typed right after met it
        # still open (and was lost). Its few widgets are all looked at.
        screen = target.screen if isinstance(target, Widget) else target
        return isinstance(screen, CommandPalette) and any(
            _busy(node) for node in screen.walk_children(with_self=True)
        )

    def _screen_ready(self, screen: Screen[Any]) -> bool:
        """The screen on top is ready for keys (`ready_for_keys`): a section whose list
        comes from a worker has it (`t` typed as the Garage opens trains the model under the
        cursor instead of finding none), and a dialog a worker is preparing is open (keys
        typed after `o` on the Nights screen go into the new night's dialog). Each wait is
        cut at `READY_WAIT_SECONDS`: a list that cannot be read must not hold keys back."""
        if getattr(screen, "ready_for_keys", True):
            self._unready_since = None
            return True
        now = time.monotonic()
        if self._unready_since is None or self._unready_since[0] is not screen:
            self._unready_since = (screen, now)
        return now - self._unready_since[1] > READY_WAIT_SECONDS

    def _key_lost(self) -> bool:
        """The key in flight will never come back: the widget it went to was removed with
        the key in its queue. A clock is the last resort, and a long one: on a busy laptop a
        key can take over a second to come back up through a screen at work, and a key let
        go too early could reach the screen below the dialog it opens."""
        target = self._key_sent_to
        if target is not None and not target.is_attached:
            return True
        return time.monotonic() - self._key_sent_at > KEY_FLIGHT_SECONDS

    async def _deliver(self, event: events.Key | events.Paste) -> None:
        if isinstance(event, events.Key):
            self._key_in_flight, self._key_sent_at = event, time.monotonic()
            self._key_sent_to = self._input_target()
            self._key_handled_at = None
        await super().on_event(event)
        if not event.is_forwarded and event is self._key_in_flight:
            self._key_used()  # by a priority binding, here and then

    def _input_target(self) -> MessagePump | None:
        try:
            return self.focused or self.screen  # where Textual forwards a key
        except ScreenStackError:
            return None

    def _hold(self, event: events.Key | events.Paste) -> None:
        self._held_input.append(event)
        self._release_when_ready()

    def _release_when_ready(self) -> None:
        if self._release_task is not None and not self._release_task.done():
            return
        self._release_task = asyncio.create_task(self._wait_then_release(), name="held keys")

    async def _wait_then_release(self) -> None:
        for attempt in range(HELD_KEY_CHECKS):
            if self._ready_for_input():
                break
            screen = self.screen  # mounted or not: `_ready_for_input` read it
            if not screen.is_mounted:
                await screen._mounted_event.wait()
            else:  # the widget the last key went to is still at it: let it run
                await asyncio.sleep(0 if attempt < HELD_KEY_YIELDS else HELD_KEY_POLL_SECONDS)
        # Through the app's queue, behind the focus a screen set as it mounted.
        self.call_later(self._release_held)

    async def _release_held(self) -> None:
        while self._held_input:
            if not self._ready_for_input():  # a key just let go is in flight
                self._release_when_ready()
                return
            await self._deliver(self._held_input.popleft())

    # --- a crash is never silent -------------------------------------------------------------

    def _handle_exception(self, error: Exception) -> None:
        """An error no handler caught: Textual stops the app (restoring the terminal and
        printing the traceback); first, the report of the first such error is written, while
        the screen it happened on is still there to be read. Writing it can never stand in
        the way of the exit."""
        if self._exception is None and self.crash_report is None:
            try:
                when = now()
                text = report_text(
                    error,
                    screen=type(self.screen).__name__ if self._screen_stacks else "(none)",
                    screen_text=self._screen_text(),
                    keys=self.recent_keys.listed(),
                    when=when,
                )
                self.crash_report = write_report(text, when)
            except Exception as failure:  # the app is going down either way
                self.crash_report_problem = str(failure) or type(failure).__name__
        super()._handle_exception(error)

    def _screen_text(self) -> str:
        """The screen as text, line by line, as the racer last saw it."""
        try:
            strips = self.screen._compositor.render_strips()
            return "\n".join(strip.text.rstrip() for strip in strips)
        except Exception as failure:  # a broken screen may be why it crashed
            return f"(could not be read: {failure!r})"

    def _freeze_after_first_visit(self, mode: str) -> None:
        """In the long-running app, once a section has been shown the first time (and its
        data read), keep what that built out of later garbage collections: modules, Textual
        and the sections live as long as the app, and every full collection walked them
        all (about 220,000 objects once every section has been seen). Measured on a short
        run right after start-up, full-collection pauses went from 160-225 ms to 26-66 ms."""
        if not self.long_running or mode in self._frozen_modes:
            return
        self._frozen_modes.add(mode)
        self.set_timer(FREEZE_AFTER_SECONDS, self._freeze_if_quiet)

    def _quiet(self) -> bool:
        """Only the sections are open: nothing that will close soon (a dialog, a race view)
        would be frozen with them."""
        return all(len(stack) <= 1 for stack in self._screen_stacks.values())

    def _freeze_if_quiet(self) -> None:
        # With a dialog open, later: the section's own objects must not stay unfrozen until
        # a sweep, which needs a calm that steady keys never give (a soak whose help opened
        # within a second of a section's first visit kept 65,000 more objects unfrozen, and
        # every full collection walked them: 130-170 ms each beside a training).
        if self._quiet():
            freeze_long_lived()
        else:
            self.set_timer(FREEZE_AFTER_SECONDS, self._freeze_if_quiet)

    def _first_mode(self) -> str:
        try:
            return "garage" if list_models() else WELCOME_MODE
        except OSError as error:
            self.notify(
                f"Cannot read the garage in {data_home()}: {error.strerror}.",
                severity="error",
                markup=False,
            )
            return WELCOME_MODE

    # --- sections ------------------------------------------------------------------------

    @property
    def section_base(self) -> Screen[Any]:
        """The current mode's own screen (under any editor or race pushed on it)."""
        return self.screen_stack[0]

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        if action in ("switch_section", "quit"):
            # Only from a section's own screen: in an editor or a race, a stray digit or q
            # must not leave it (ctrl+q still quits from anywhere).
            return len(self.screen_stack) <= 1
        if action == "quit_anywhere":
            return True
        if action == "help":
            return not isinstance(self.screen, HelpScreen)
        return True

    def switch_mode(self, mode: str) -> AwaitMount:
        stack = self._screen_stacks.get(mode) or []
        self._switching_to_shown_mode = bool(stack) and stack[0].is_mounted
        try:
            return super().switch_mode(mode)
        finally:
            self._switching_to_shown_mode = False

    def delay_update(self, delay: float = 0.05) -> None:
        # Textual's switch_mode holds every screen update back for 50 ms, to hide a screen
        # being composed for the first time. A section shown before is composed already, and
        # switch_mode lays it out and paints it at once, so the hold was only latency: 50 of
        # the 65 ms a section switch took. It still holds for a section's first visit.
        if not self._switching_to_shown_mode:
            super().delay_update(delay)

    async def action_switch_section(self, mode: str) -> None:
        if mode in self.MODES and mode != self.current_mode:
            await self.switch_mode(mode)
            self._freeze_after_first_visit(mode)

    async def run_section_action(self, mode: str, action: str) -> None:
        """A palette command of another section: go there, then run it on its screen."""
        await self.switch_mode(mode)
        await self.section_base.run_action(action)

    # --- leaving while a training runs ---------------------------------------------------------

    def training_screen(self) -> TrainingScreen | None:
        """The Training section's screen, if it was opened in this session."""
        try:
            stack = self.get_screen_stack("training")
        except KeyError:  # never opened
            return None
        return stack[0] if stack and isinstance(stack[0], TrainingScreen) else None

    async def action_quit_anywhere(self) -> None:
        await self.action_quit()

    async def action_quit(self) -> None:
        """Quit; in the middle of a night's heat or match, first ask (Ctrl+Q quits from any
        screen, and the host walk quit a timed heat with it); with a training running, then
        ask whether to stop it or keep it running."""
        unfinished = next(
            (
                words
                for screen in reversed(self.screen_stack)
                if (words := getattr(screen, "unfinished_race", ""))
            ),
            "",
        )
        if not unfinished:
            self._quit_after_training()
            return

        def answered(yes: bool | None) -> None:
            if yes:
                self._quit_after_training()

        ask(
            self,
            "Quit in the middle of the race?",
            f"{unfinished[:1].upper()}{unfinished[1:]}.",
            answered,
            confirm_label="Quit",
            cancel_label="Keep racing",
        )

    def _quit_after_training(self) -> None:
        training = self.training_screen()
        model = training.training_here if training is not None else None
        if training is None or model is None:
            self.exit()
            return

        def answered(answer: str | None) -> None:
            if answer == "stop":
                training.stop_training()
            if answer in ("stop", "keep"):
                self.exit()

        self.push_screen(LeaveWhileTraining(model), answered)

    async def on_model_added(self, message: ModelAdded) -> None:
        await self.show_model(message.name)

    async def show_model(self, name: str) -> None:
        """Open the garage with `name` highlighted (after creating or importing it)."""
        await self.switch_mode("garage")
        garage = self.section_base
        if isinstance(garage, GarageScreen):
            garage.reload(select=name)

    # --- help and palette ------------------------------------------------------------------

    def action_command_palette(self) -> None:
        """Textual's palette, never lost nor doubled when ctrl+p comes as one closes.

        Enter on a palette command closes the palette a few messages later: a ctrl+p typed
        right after it met the palette still open and did nothing (the key was lost), or
        met it taken off the screen but not yet removed, and Textual, which opens every
        palette with one fixed id, crashed on a second one (DuplicateIds: the monkey, seed
        401). So ctrl+p waits, up to `PALETTE_WAIT_SECONDS`, for the closing palette to be
        gone."""
        self._open_palette(time.monotonic() + PALETTE_WAIT_SECONDS)

    def _open_palette(self, deadline: float) -> None:
        try:
            screen = self.screen
        except ScreenStackError:  # quitting
            return
        # Textual 8.2.8's own fields: a command chosen (the palette is closing) and the
        # screens the app holds, the one still being taken down among them.
        closing = isinstance(screen, CommandPalette) and screen._selected_command is not None
        leaving = any(
            isinstance(node, CommandPalette) and node is not screen for node in self._nodes
        )
        # A palette still to open: the keys after ctrl+p are its own, and wait for it.
        self._palette_due = (closing or leaving) and time.monotonic() < deadline
        if self._palette_due:
            self.set_timer(PALETTE_RETRY_SECONDS, partial(self._open_palette, deadline))
        if closing or leaving:
            return  # (past the deadline: no second palette, which would be a crash)
        super().action_command_palette()

    def help_topics(self) -> list[HelpTopic]:
        classes: list[tuple[str, type[DOMNode]]] = [(EVERYWHERE, type(self))]
        classes += [(s.title, SECTION_SCREENS[s.mode]) for s in SECTIONS]
        classes += list(OTHER_SCREENS)
        palette = Binding(self.COMMAND_PALETTE_BINDING, "command_palette", "Command palette")
        return binding_topics(
            classes,
            self.get_key_display,
            extra=[
                (EVERYWHERE, palette),
                (EVERYWHERE, Binding("tab", "focus_next", "Next field")),
                (EVERYWHERE, Binding("shift+tab", "focus_previous", "Previous field")),
            ],
        )

    def action_help(self) -> None:
        if isinstance(self.screen, HelpScreen):
            return
        push_kept(self, HELP_SCREEN, self._new_help)  # the same help for every screen

    def _new_help(self) -> HelpScreen:
        notes = (
            f"Your models, tracks and league live in {data_home()} "
            "(set RACER_TUI_HOME to use another folder)."
        )
        return HelpScreen(self.help_topics(), notes)

    def palette_commands(self, screen: Screen[object]) -> list[PaletteCommand]:
        """Every section's keys as commands, plus the keys of the screen the palette was
        opened on when that is not a section (the editor, a race, the welcome screen)."""
        commands: list[PaletteCommand] = []
        for section in SECTIONS:
            commands.append(
                PaletteCommand(
                    f"Go to {section.title}",
                    section.summary,
                    partial(self.action_switch_section, section.mode),
                )
            )
        for section in SECTIONS:
            for binding in self._described(SECTION_SCREENS[section.mode]):
                commands.append(
                    PaletteCommand(
                        f"{section.title}: {binding.description}",
                        binding.tooltip or f"key {self.get_key_display(binding)}",
                        partial(self.run_section_action, section.mode, binding.action),
                    )
                )
        if section_for(self.current_mode) is None or screen is not self.section_base:
            name = "Welcome" if isinstance(screen, WelcomeScreen) else "This screen"
            for binding in self._described(type(screen)):
                commands.append(
                    PaletteCommand(
                        f"{name}: {binding.description}",
                        binding.tooltip or f"key {self.get_key_display(binding)}",
                        partial(screen.run_action, binding.action),
                    )
                )
        commands.append(
            PaletteCommand(
                "Help: every key", "the key reference, generated from the screens", self.action_help
            )
        )
        if self.current_mode != WELCOME_MODE:
            commands.append(
                PaletteCommand(
                    "Welcome: demo race",
                    "the first-run screen with the reference driver lapping",
                    partial(self.switch_mode, WELCOME_MODE),
                )
            )
        return commands

    @staticmethod
    def _described(screen_class: type[DOMNode]) -> list[Binding]:
        seen: set[str] = set()
        described = []
        for binding in declared_bindings(screen_class):
            if binding.description and binding.action not in seen:
                seen.add(binding.action)
                described.append(binding)
        return described


def create_app(
    *,
    start: str | None = None,
    long_running: bool = False,
    projector_night: str | None = None,
    db_path: Path | None = None,
) -> RacerTuiApp:
    """The app, as the CLI, the tests and the snapshots build it."""
    return RacerTuiApp(
        start=start, long_running=long_running, projector_night=projector_night, db_path=db_path
    )


def run_app(*, projector_night: str | None = None, db_path: Path | None = None) -> int:
    """Run the app in the terminal; the exit status for the shell (non-zero after a crash)."""
    app = create_app(long_running=True, projector_night=projector_night, db_path=db_path)
    app.run()
    return exit_status(app)


def exit_status(app: RacerTuiApp) -> int:
    """Once the app has stopped and the terminal is back: after a crash, the keys typed for
    the app that it never read are thrown away (they would run in the shell), one sentence
    on stderr says where the report is, and the status is non-zero."""
    code = app.return_code or 0
    if code == 0 and app._exception is None:
        return 0
    drop_unread_keys()
    say_crash(app.crash_report, app.crash_report_problem)
    return code or EXIT_CRASH
