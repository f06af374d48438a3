"""Sync: the league's shared store from the app. Its URL (checked by the sync library's
parser and saved as the league's setting), a Sync action that pushes this league's new
records and pulls everyone else's with a progress bar, what the last sync did, and what
sync set aside: conflicts (both sides kept) and quarantined records (not added). And the
league's signing keys: this machine's and what it may sign, and for the organiser the
racers' keys waiting for admission, admitted here with `a` (`racer-tui racer admit`).

The work is league.sync's (session.py runs a sync exactly as `racer-tui sync` does,
status.py reads what it set aside); this screen calls it in thread workers, each with its
own database connection. Everything from the store is shown as plain text. A store that
is down is one notification with the library's sentence, and nothing local changes. A store
that is reachable but not set up yet is offered to be set up here (`racer-tui sync init` on
the command line), then synced.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from functools import partial
from pathlib import Path
from typing import ClassVar

from rich.text import Text
from textual import on, work
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal, Vertical
from textual.message import Message
from textual.widgets import Button, DataTable, Input, Label, Static
from textual.worker import Worker, WorkerState

from league.errors import LeagueError
from league.opening import open_league
from league.store import League
from league.sync import open_store
from league.sync.engine import SyncSummary
from league.sync.errors import (
    StoreFolderMissingError,
    StoreNotInitialisedError,
    StoreUrlError,
    SyncError,
)
from league.sync.session import check_record_store_url, found_store, save_store, sync_league
from league.sync.status import (
    SyncStatus,
    conflict_view,
    summary_details,
    summary_headline,
    sync_status,
)
from league.trust import membership
from league.trust.keys import KeyFileError, load_or_create_key
from league.trust.membership import KeyRow
from racer_tui.app.jobs import Job, sentence
from racer_tui.app.screens.base import (
    RacerScreen,
    error_message,
    notify_worker_failure,
)
from racer_tui.app.screens.dialogs import ask, show_problem
from racer_tui.app.widgets.footer import RacerFooter
from racer_tui.app.widgets.job_line import JobLine
from racer_tui.app.widgets.section_header import SectionHeader
from racer_tui.app.widgets.sync_status import local_time
from racer_tui.app.widgets.table_fill import Col, FittedTable, fill_table
from racer_tui.app.words import in_app_words

CONFLICT_COLUMNS = (
    "kind",
    Col("id", keep=1, shrink_to=8),
    Col("what differs", keep=0, shrink_to=12, collapses=False),
    Col("here", keep=0, shrink_to=10, collapses=False),
    Col("in the store", keep=0, shrink_to=12, collapses=False),
)
KEY_COLUMNS = (
    Col("racer", keep=0, shrink_to=10, collapses=False),
    Col("fingerprint", keep=0, collapses=False),
    Col("status", keep=1, shrink_to=8),
)
# The reason matters most (who, and what to do); where it was in the store gives way first.
QUARANTINE_COLUMNS = (
    "kind",
    Col("id", keep=1, shrink_to=8),
    Col("reason", keep=2, shrink_to=30, collapses=False),
    Col("where", keep=0, shrink_to=10),
)
CELL = 48  # characters of one side of a conflict or a reason in a cell; the rest is cut
URL_HINT = "dir:PATH (a shared folder) or dynamodb://TABLE?region=R"


def cut(text: str, limit: int = CELL) -> Text:
    """A cell of untrusted text: plain, one line, at most `limit` characters."""
    line = " ".join(text.split())
    return Text(line if len(line) <= limit else line[: limit - 1] + "…")


# --- messages from the workers --------------------------------------------------------------


@dataclass(frozen=True)
class Keys:
    """This machine's key and the keys waiting for admission, as the screen shows them."""

    mine: KeyRow | None
    waiting: tuple[KeyRow, ...] = ()
    organiser: bool = False
    problem: str = ""  # the key file cannot be used: the sentence saying what to do


def read_keys(league: League) -> Keys:
    try:
        key = load_or_create_key()
    except KeyFileError as error:
        return Keys(None, problem=str(error))
    rows = membership.key_rows(league, key)
    mine = next(row for row in rows if row.this_machine)
    waiting = tuple(row for row in rows if row.status == "proposed")
    return Keys(mine, waiting, mine.status in ("founder", "organiser"))


@dataclass
class SyncStatusRead(Message):
    status: SyncStatus
    keys: Keys


@dataclass
class StoreSaved(Message):
    url: str


@dataclass
class SyncFinished(Message):
    summary: SyncSummary
    notes: list[str]


class SyncScreen(RacerScreen[bool]):
    """The shared store of the league at `db_path` (None: the data folder's league).
    Dismissed with True when a sync pulled records, so the leaderboard reads them."""

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("s", "sync", "Sync now", tooltip="Push this league's new records, then pull"),
        Binding("e", "edit_store", "Edit store", tooltip="Change the shared store's URL"),
        Binding("a", "admit", "Admit key", tooltip="Admit the selected racer's signing key"),
        Binding("escape", "leave", "Back", tooltip="Leave the field, then back to the league"),
        Binding("ctrl+r", "reload", "Reload", tooltip="Read the sync status again", show=False),
    ]
    AUTO_FOCUS = "#sync-now"

    def __init__(self, *, db_path: Path | None = None) -> None:
        super().__init__()
        self.db_path = db_path
        self.status: SyncStatus | None = None
        self.syncing = False
        self.pulled = 0  # records pulled while this screen was open
        self._syncing_url = ""
        self.job = Job()
        self._shown_progress: tuple[str, int] | None = None
        self.last_summary: Text | None = None  # what the sync run here did
        self.keys = Keys(None)
        self._url_from_status = True  # the next status read fills the URL field
        # Empty until the first read, and usually after it: a class changed after the
        # screen is laid out restyles all of it (about 15 ms at 80x24).
        self.add_class("-no-conflicts", "-no-quarantine", "-no-waiting-keys")

    def compose(self) -> ComposeResult:
        yield SectionHeader("league", "shared store")
        with Vertical(id="sync-body"):
            with Horizontal(id="sync-store-row"):
                yield Label("Store", id="sync-store-label")
                yield Input(placeholder=URL_HINT, id="sync-url")
                yield Button("Save", id="sync-save")
                yield Button("Sync now (s)", id="sync-now", variant="primary")
            yield Static("", id="problem", classes="field-problem")
            yield JobLine(id="sync-job")
            yield Static("", id="sync-summary")
            yield Label("Conflicts", id="sync-conflicts-title", classes="field-label")
            yield FittedTable(id="sync-conflicts", cursor_type="row", zebra_stripes=True)
            yield Label("Quarantined", id="sync-quarantine-title", classes="field-label")
            yield FittedTable(id="sync-quarantine", cursor_type="row", zebra_stripes=True)
            yield Static("Signing key", id="sync-keys-title", classes="field-label")
            yield FittedTable(id="sync-keys", cursor_type="row", zebra_stripes=True)
        yield RacerFooter()

    def on_mount(self) -> None:
        self.action_reload()

    def reset(self) -> None:
        """As a fresh Sync screen opens (the app keeps one and shows it again): what the
        last visit's sync did is not news now, the URL field shows the saved store again,
        and the status is read again at once."""
        if not self.is_mounted or self.syncing:
            return  # composing now, or still syncing (leaving is refused until it ends)
        self.pulled = 0
        self.last_summary = None
        self._show_job(Job())
        show_problem(self.query_one("#problem", Static), "")
        url = self.query_one("#sync-url", Input)
        url.remove_class("-problem")
        self._url_from_status = True  # the fresh read fills the field, not the last one
        if self.status is not None:  # the last read's store and tables until then
            url.value = self.status.overview.store or ""
            self._show_status(self.status)
        self.action_reload()

    # --- reading the status ------------------------------------------------------------

    def action_reload(self) -> None:
        self._read_status()

    @work(thread=True, exclusive=True, group="sync-status", exit_on_error=False)
    def _read_status(self) -> None:
        with open_league(self.db_path) as league:
            status = sync_status(league)
            keys = read_keys(league)
        self.post_message(SyncStatusRead(status, keys))

    def on_sync_status_read(self, message: SyncStatusRead) -> None:
        self.status = message.status
        self._show_keys(message.keys)
        store = message.status.overview.store
        if self._url_from_status:  # as it opens; later the field is the racer's
            self._url_from_status = False
            url = self.query_one("#sync-url", Input)
            if url.value != (store or ""):
                url.value = store or ""
            (self.query_one("#sync-now", Button) if store else url).focus()
        self._show_status(message.status)

    def _show_status(self, status: SyncStatus) -> None:
        if not self.syncing:
            self.query_one("#sync-summary", Static).update(
                self.last_summary or self._last_runs_text()
            )
        self._fill_tables(status)

    def _last_runs_text(self) -> Text:
        if self.status is None or self.status.overview.store is None:
            return Text(
                "No shared store yet. Type the folder or table your league shares (ask the "
                "league host), for example dir:/mnt/league-share, and press Enter."
            )
        overview = self.status.overview
        lines = []
        if overview.failure is not None:
            lines.append(
                f"The last sync failed at {local_time(overview.failure.at)}: "
                f"{sentence(overview.failure.message)} Fix that and press s to try again."
            )
        for direction in ("push", "pull"):
            run = overview.runs.get(direction)
            if run is None:
                lines.append(f"Last {direction}: never")
            else:
                when = local_time(run.finished_at)
                lines.append(
                    f"Last {direction}: {when} ({overview.moved(direction)} {direction}ed)"
                )
        lines.append(
            f"{overview.to_push} new here, not pushed yet; the store holds {overview.in_store} "
            "of this league's records."
        )
        return Text("\n".join(lines))

    def _fill_tables(self, status: SyncStatus) -> None:
        views = [conflict_view(row) for row in status.conflicts]
        fill_table(
            self.query_one("#sync-conflicts", DataTable),
            CONFLICT_COLUMNS,
            [
                [
                    Text(view.kind),
                    Text(view.record_id),
                    cut(view.what),
                    cut(view.here),
                    cut(view.there),
                ]
                for view in views
            ],
        )
        fill_table(
            self.query_one("#sync-quarantine", DataTable),
            QUARANTINE_COLUMNS,
            [
                [
                    Text(row.kind or "?"),
                    Text(row.record_id or "?"),
                    cut(row.reason, 160),
                    cut(row.location, 60),
                ]
                for row in status.quarantined
            ],
        )
        conflicts, quarantined = len(status.conflicts), len(status.quarantined)
        self.query_one("#sync-conflicts-title", Label).update(
            Text(
                f"Conflicts ({conflicts}): both sides kept, this league shows its own"
                if conflicts
                else "Conflicts: none"
            )
        )
        self.query_one("#sync-quarantine-title", Label).update(
            Text(
                f"Quarantined ({quarantined}): on no leaderboard, each with its reason"
                if quarantined
                else "Quarantined: none"
            )
        )
        self.set_class(not conflicts, "-no-conflicts")
        self.set_class(not quarantined, "-no-quarantine")

    # --- signing keys ------------------------------------------------------------------

    def _show_keys(self, keys: Keys) -> None:
        self.keys = keys
        title = self.query_one("#sync-keys-title", Static)
        waiting = keys.waiting if keys.organiser else ()
        if keys.mine is None:
            title.update(Text(f"Signing key: {keys.problem}"))
        elif waiting:
            title.update(
                Text(
                    f"Keys waiting for admission ({len(waiting)}): check the fingerprint with "
                    "the racer, then press a"
                )
            )
        else:
            title.update(Text(f"Your signing key {_key_line(keys.mine)}"))
        fill_table(
            self.query_one("#sync-keys", DataTable),
            KEY_COLUMNS,
            [[Text(row.racer), Text(row.fingerprint), Text("waiting")] for row in waiting],
        )
        self.set_class(not waiting, "-no-waiting-keys")
        self.refresh_bindings()

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        if action == "admit":
            return bool(self.keys.organiser and self.keys.waiting)
        return True

    def action_admit(self) -> None:
        table = self.query_one("#sync-keys", DataTable)
        if not self.keys.waiting or not 0 <= table.cursor_row < len(self.keys.waiting):
            return
        row = self.keys.waiting[table.cursor_row]
        ask(
            self.app,
            f"Admit {row.racer}'s key {row.fingerprint}?",
            f"Ask {row.racer} to read out the fingerprint on their own Sync screen first: an "
            f"admitted key's results reach every leaderboard as {row.racer}'s. What it "
            "signed so far is let in now, and the admission goes out with the next sync.",
            partial(self._admit_answered, row),
            confirm_label="Admit",
        )

    def _admit_answered(self, row: KeyRow, yes: bool | None) -> None:
        if yes:
            self._admit(row)

    @work(thread=True, exclusive=True, group="sync-admit", exit_on_error=False)
    def _admit(self, row: KeyRow) -> None:
        with open_league(self.db_path) as league:
            membership.admit(league, load_or_create_key(), row.public_key)
        self.app.call_from_thread(
            self.notify,
            f"Admitted {row.racer}'s key {row.fingerprint}. Press s to share it with the league.",
            markup=False,
        )
        self.app.call_from_thread(self.action_reload)

    # --- the store's URL ---------------------------------------------------------------

    def action_edit_store(self) -> None:
        self.query_one("#sync-url", Input).focus()

    def _checked_url(self) -> str | None:
        """The typed URL in its canonical form, or None (the problem is shown)."""
        field = self.query_one("#sync-url", Input)
        text = field.value.strip()
        problem = ""
        url = None
        if not text:
            problem = f"Type the shared store's URL first: {URL_HINT}."
        else:
            try:
                url = str(check_record_store_url(text))
            except StoreUrlError as error:
                problem = sentence(str(error))
        show_problem(self.query_one("#problem", Static), problem)
        field.set_class(bool(problem), "-problem")
        return url

    @on(Input.Submitted, "#sync-url")
    @on(Button.Pressed, "#sync-save")
    def _save_url(self) -> None:
        url = self._checked_url()
        if url is not None:
            self._save(url)

    @work(thread=True, exclusive=True, group="sync-save", exit_on_error=False)
    def _save(self, url: str) -> None:
        with open_league(self.db_path) as league:
            save_store(league, url)
        self.post_message(StoreSaved(url))

    def on_store_saved(self, message: StoreSaved) -> None:
        self.query_one("#sync-url", Input).value = message.url
        self.query_one("#sync-now", Button).focus()
        self.notify(
            f"This league syncs with {message.url}. Press s to sync now.",
            markup=False,
        )
        self.action_reload()

    # --- syncing -----------------------------------------------------------------------

    @on(Button.Pressed, "#sync-now")
    def _sync_pressed(self) -> None:
        self.action_sync()

    def action_sync(self) -> None:
        if self.syncing:
            self.notify("A sync is already running.", severity="warning")
            return
        url = self._checked_url()
        if url is None:
            self.query_one("#sync-url", Input).focus()
            return
        saved = self.status.overview.store if self.status is not None else None
        self._begin(url, f"Reaching {url}…")
        self._sync(url, save=url != saved)

    def _begin(self, url: str, stage: str) -> None:
        self.syncing = True
        self._syncing_url = url
        self._shown_progress = None
        self.query_one("#sync-now", Button).disabled = True
        self._show_job(self.job.running(stage, total=None, now=time.monotonic(), wall=time.time()))

    def _show_job(self, job: Job) -> None:
        self.job = job
        self.query_one(JobLine).show(job)

    @work(thread=True, exclusive=True, group="sync-run", exit_on_error=False)
    def _sync(self, url: str, save: bool, set_up: bool = False) -> None:
        with open_league(self.db_path) as league:
            notes_first: list[str] = []
            if set_up:  # the host sets the store up: their key founds the league
                with open_store(url) as store:
                    store.init()
                    # The sync below pushes the founding record first (the roster leads).
                    notes_first.append(found_store(league, store, url, push_now=False))
            if save:
                save_store(league, url)
            summary, notes = sync_league(league, url, progress=self._progress_from_thread)
            notes = notes_first + notes
        self.post_message(SyncFinished(summary, notes))

    def _failed(self, error: BaseException | None) -> Job:
        wall = time.time()
        if error is None:
            return self.job.stopped(wall=wall)
        if isinstance(error, StoreNotInitialisedError | StoreFolderMissingError):
            return self.job.failed(
                f"There is no racer-tui store at {self._syncing_url} yet.",
                "Press s to set one up.",
                wall=wall,
            )
        # A league's refusal may end in a command-line remedy: error_message words it the
        # app's way. A sync error is already a sentence for the racer.
        text = sentence(str(error)) if isinstance(error, SyncError) else None
        return self.job.failed(
            text or error_message(error), "Fix that and press s to try again.", wall=wall
        )

    def _synced_before(self, url: str) -> bool:
        overview = self.status.overview if self.status is not None else None
        return overview is not None and overview.store == url and bool(overview.runs)

    def _offer_set_up(self, url: str, folder_missing: bool) -> None:
        where = (
            "That folder does not exist. If the shared drive is not connected, cancel, "
            "connect it and press s again. "
            if folder_missing
            else "There is no racer-tui store there yet. "
        )
        ask(
            self.app,
            f"Set up a store at {url}?",
            f"{where}Setting one up makes it ready for the whole league, with your key as "
            "its organiser's, then this league syncs with it; every other racer then sets "
            "the same URL here and presses s.",
            partial(self._set_up_answered, url),
            confirm_label="Set up and sync",
        )

    def _set_up_answered(self, url: str, yes: bool | None) -> None:
        if not yes:
            self._show_job(
                self.job.failed(
                    "The store was not set up; nothing was synced.",
                    "Press s to be asked again.",
                    wall=time.time(),
                )
            )
            return
        self._begin(url, f"Setting up {url}…")
        self._sync(url, save=True, set_up=True)

    def _progress_from_thread(self, direction: str, done: int, total: int | None) -> None:
        # One screen update per percent (or per pulled page): a big push reports every
        # record, and each call waits for the UI thread.
        step = done * 100 // total if total else done
        if (direction, step) == self._shown_progress:
            return
        self._shown_progress = (direction, step)
        self.app.call_from_thread(self._show_progress, direction, done, total)

    def _show_progress(self, direction: str, done: int, total: int | None) -> None:
        if not self.is_attached or not self.syncing:
            return
        of = f"/{total}" if total is not None else ""
        doing = f"{direction.capitalize()}ing {done}{of} records"
        self._show_job(self.job.doing(doing).progressed(done, total))  # a pull: its own total

    def on_sync_finished(self, message: SyncFinished) -> None:
        summary = message.summary
        self._sync_ended()
        self.pulled += summary.pulled
        self._show_job(self.job.finished(summary_headline(summary), wall=time.time()))
        # Conflicts and quarantined records are in the tables below, with their reasons.
        # Remedies by the app's keys, not the command line's commands.
        shown = replace(summary, notes=[in_app_words(note) for note in summary.notes])
        notes = [in_app_words(note) for note in message.notes]
        lines = [summary_headline(summary), *summary_details(shown, notes, items=False)]
        self.last_summary = Text("\n".join(lines))  # text from the store: plain
        self.query_one("#sync-summary", Static).update(self.last_summary)
        problems = bool(summary.conflicts or summary.quarantined)
        self.notify(
            summary_headline(summary),
            severity="warning" if problems else "information",
            markup=False,
        )
        self.action_reload()

    def _sync_ended(self) -> None:
        self.syncing = False
        button = self.query_one("#sync-now", Button)
        button.disabled = False
        if self.focused is None or isinstance(self.focused, Input):
            button.focus()  # disabling it moved the focus; Esc and s act on the screen again

    def on_worker_state_changed(self, event: Worker.StateChanged) -> None:
        event.prevent_default()  # the base screen's handler would report the error again
        worker = event.worker
        if worker.group == "sync-run" and worker.state in (
            WorkerState.ERROR,
            WorkerState.CANCELLED,
        ):
            self._sync_ended()
            # Nothing may still look like it is syncing, nor the last success like news:
            # the job line says it failed, and the summary is read again (it leads with
            # the failure).
            self._show_job(self._failed(worker.error))
            self.last_summary = None
            self.action_reload()
        error = worker.error
        if (
            worker.state is WorkerState.ERROR
            and isinstance(error, StoreNotInitialisedError | StoreFolderMissingError)
            and not self._synced_before(self._syncing_url)
        ):
            # A new store: the library's sentence names the command line's `sync init`;
            # here it is a key. (A store this league synced with before that is gone now is
            # a drive not connected, reported as it is: a new store there would be wrong.)
            self._offer_set_up(self._syncing_url, isinstance(error, StoreFolderMissingError))
            return
        if worker.state is WorkerState.ERROR and isinstance(error, SyncError | LeagueError):
            # The library's sentence says what is wrong and what to do: a sync error as it
            # is, a league's with the app's own remedy where it has one.
            said = error_message(error) if isinstance(error, LeagueError) else str(error)
            self.notify(sentence(said), severity="error", timeout=15, markup=False)
            return
        notify_worker_failure(self, worker)

    # --- leaving -----------------------------------------------------------------------

    def action_leave(self) -> None:
        if isinstance(self.focused, Input):
            self.query_one("#sync-now", Button).focus()
            return
        if self.syncing:
            self.notify(
                "A sync is running: wait for its summary, then leave (stopping halfway is "
                "safe but would need another sync).",
                severity="warning",
            )
            return
        self.dismiss(self.pulled > 0)


_KEY_STATUS = {
    "founder": "the organiser's (it founded the league)",
    "organiser": "an organiser's",
    "racer": "admitted",
    "proposed": "waiting for the organiser to admit it",
    "retired": "retired: what it signs now does not count",
    "revoked": "revoked: nothing it signed counts",
    "unknown": "not proposed yet (the next sync proposes it)",
}


def _key_line(row: KeyRow) -> str:
    whose = f"{row.racer}'s, " if row.racer else ""
    return f"{row.fingerprint}: {whose}{_KEY_STATUS[row.status]}"
