"""The Sync screen, end to end through a real shared folder (`dir:` store) in tmp_path:
two racers on separate "machines" (separate data folders) sync from the app until one sees
the other's result, a store that is down, a malformed record in the store, a bad URL, and
a conflict with both sides shown."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest
from textual.pilot import Pilot
from textual.widgets import DataTable, Input

from league.local_racer import save_local_racer_name
from league.opening import open_league
from league.races import record_race
from league.store import now_iso
from league.sync import local, open_store
from league.sync.dir_store import MARKER_NAME
from league.sync.session import save_store, sync_league
from league.trust.keys import load_or_create_key
from league.trust.membership import found_league
from racer_tui.app.application import RacerTuiApp, create_app
from racer_tui.app.screens.dialogs import ConfirmDialog
from racer_tui.app.screens.league import LeagueScreen
from racer_tui.app.screens.sync import SyncScreen
from racer_tui.app.widgets.job_line import JobLine
from racer_tui.app.widgets.sync_status import NO_STORE, SyncStatusLine
from sim.foundation.home import data_home
from tests.league.helpers import race_result
from tests.racer_tui.screens.tui_helpers import Notifications, painted, settle

MARKUP_NAME = "[bold red]x"
BAD_ID = "01M7YFZPX152TMAJ036HERQMZZ"


@pytest.fixture
def store_url(tmp_path: Path) -> str:
    url = f"dir:{tmp_path / 'league-share'}"
    with open_store(url) as store:
        store.init()
    return url


def found_here(url: str) -> None:
    """What the organiser's `racer-tui sync init` does on this machine: the store is set up
    and this machine's key founds the league (so everyone accepts what it signs)."""
    with open_league() as league, open_store(url) as store:
        store.init()
        found_league(league, load_or_create_key())


def on_machine(monkeypatch: pytest.MonkeyPatch, home: Path) -> None:
    """Switch the data folder: each racer's machine has its own league."""
    monkeypatch.setenv("RACER_TUI_HOME", str(home))
    data_home().mkdir(parents=True, exist_ok=True)


def record(racer: str, laps: list[float]) -> None:
    with open_league() as league:
        # Raced now: a racer's result dated before the league was founded is not its own.
        record_race(league, race_result(racer, laps, model="the-car", started_at=now_iso()))


def database_dump() -> list[str]:
    with open_league() as league:
        return list(league.conn.iterdump())


async def open_sync(pilot: Pilot[int]) -> SyncScreen:
    await settle(pilot)
    await pilot.press("y")
    await settle(pilot)
    screen = pilot.app.screen
    assert isinstance(screen, SyncScreen)
    return screen


async def set_store(pilot: Pilot[int], screen: SyncScreen, url: str) -> None:
    """Type the URL (set directly: typing a long path key by key is slow) and press Enter."""
    field = screen.query_one("#sync-url", Input)
    field.focus()
    field.value = url
    await pilot.press("enter")
    await settle(pilot)


async def sync_with(pilot: Pilot[int], url: str) -> SyncScreen:
    """Open the Sync screen, set the store and press s: what a racer does to sync."""
    screen = await open_sync(pilot)
    await set_store(pilot, screen, url)
    await pilot.press("s")
    await settle(pilot)
    return screen


def summary(screen: SyncScreen) -> str:
    """What the last sync did, as shown under the store (unwrapped)."""
    return screen.last_summary.plain if screen.last_summary is not None else ""


def status_line(app: RacerTuiApp) -> str:
    return painted(app.screen.query_one(SyncStatusLine))


def board_racers(app: RacerTuiApp) -> list[str]:
    screen = app.screen
    assert isinstance(screen, LeagueScreen)
    return [row.racer for row in screen.rows]


async def test_two_racers_sync_from_the_app_and_see_each_others_results(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, store_url: str
) -> None:
    # Racer A, the organiser: records a race, sets the store from the Sync screen, syncs.
    on_machine(monkeypatch, tmp_path / "ada-laptop")
    found_here(store_url)
    record(MARKUP_NAME, [11.0, 10.5])
    app = create_app(start="league")
    async with app.run_test(size=(100, 30)) as pilot:
        notes = Notifications(app)
        await settle(pilot)
        assert NO_STORE in status_line(app)
        screen = await open_sync(pilot)
        await set_store(pilot, screen, store_url)
        assert f"This league syncs with {store_url}" in notes.text()
        await pilot.press("s")
        await settle(pilot)
        # The racer, track and race, and the league's founding record.
        assert f"Synced with {store_url}: pushed 4, pulled 0" in summary(screen)
        assert "0 conflicts, 0 quarantined" in summary(screen)
        await pilot.press("escape")
        await settle(pilot)
        line = status_line(app)
        assert "⇅ dir:/" in line and "0 to push" in line and "(↑4 ↓0)" in line

    # Racer B: an empty league on another machine syncs and sees A's result.
    on_machine(monkeypatch, tmp_path / "bob-desktop")
    record("bob", [12.0])
    app = create_app(start="league")
    async with app.run_test(size=(100, 30)) as pilot:
        await settle(pilot)
        assert board_racers(app) == ["bob"]
        screen = await open_sync(pilot)
        assert screen.focused is screen.query_one("#sync-url")  # no store yet: type one
        await set_store(pilot, screen, store_url)
        await pilot.press("s")
        await settle(pilot)
        assert "pulled 4" in summary(screen)
        await pilot.press("escape")
        await settle(pilot)
        assert sorted(board_racers(app)) == sorted([MARKUP_NAME, "bob"])
        assert MARKUP_NAME in painted(app.screen.query_one("#board"))  # literally, not markup
        assert "0 to push" in status_line(app)  # bob's race went to the store too


async def test_at_80_columns_the_status_line_keeps_room_for_the_store(
    tmp_path: Path, store_url: str
) -> None:
    data_home()
    found_here(store_url)
    record("ana", [11.0])
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        await sync_with(pilot, store_url)
        await pilot.press("escape")
        await settle(pilot)
        line = status_line(app)
        # What matters stays (when, what waits); zero warnings and the arrows go, so the
        # store's URL is more than an ellipsis.
        assert "synced" in line and "0 to push" in line
        assert "conflicts" not in line and "↑" not in line
        assert "⇅ dir:/" in line
        await pilot.resize_terminal(120, 30)
        await settle(pilot)
        assert "0 conflicts" in status_line(app) and "(↑4 ↓0)" in status_line(app)


async def test_the_organiser_admits_a_racers_key_from_the_sync_screen(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, store_url: str
) -> None:
    # bob races on his own machine and syncs: his key is proposed, his race held back.
    on_machine(monkeypatch, tmp_path / "host")
    found_here(store_url)
    on_machine(monkeypatch, tmp_path / "bob-laptop")
    record("bob", [12.0])
    with open_league() as league:
        save_local_racer_name(league, "bob")  # `racer-tui racer me bob`
        sync_league(league, store_url)
        bob_key = load_or_create_key().fingerprint

    on_machine(monkeypatch, tmp_path / "host")
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        notes = Notifications(app)
        screen = await sync_with(pilot, store_url)
        title = painted(screen.query_one("#sync-keys-title"))
        assert "Keys waiting for admission (1)" in title
        keys = painted(screen.query_one("#sync-keys"))
        assert "bob" in keys and bob_key in keys
        assert "Admit key" in painted(screen.query_one("RacerFooter"))
        await pilot.press("a")
        await settle(pilot)
        assert isinstance(app.screen, ConfirmDialog)
        await pilot.press("y")
        await settle(pilot)
        assert f"Admitted bob's key {bob_key}" in notes.text()
        assert "Your signing key" in painted(screen.query_one("#sync-keys-title"))
        assert "Admit key" not in painted(screen.query_one("RacerFooter"))
        await pilot.press("escape")
        await settle(pilot)
        assert board_racers(app) == ["bob"]  # his held race, let in by the admission


async def test_a_store_that_is_down_is_one_notification_and_changes_nothing(
    tmp_path: Path,
) -> None:
    data_home()
    record("ana", [11.0])
    with open_league() as league:
        save_store(league, f"dir:{tmp_path / 'usb-stick-not-plugged-in' / 'league'}")
    before = database_dump()
    app = create_app(start="league")
    async with app.run_test(size=(100, 30)) as pilot:
        notes = Notifications(app)
        screen = await open_sync(pilot)
        await pilot.press("s")
        await settle(pilot)
        errors = notes.text("error")
        assert "is not there" in errors and "Traceback" not in errors
        assert errors.count("\n") == 0  # one sentence
        job = " ".join(painted(screen.query_one(JobLine)).split())
        assert "Failed at" in job and "is not there" in job and "press s to try again" in job
        assert "%" not in job  # no bar left standing
        assert not screen.syncing  # the action can be tried again
    # No record changed; only the failure is noted, for the status lines.
    after = [line for line in database_dump() if "last_failure" not in line]
    assert after == before


@pytest.mark.parametrize("made", [False, True], ids=["no folder yet", "empty folder"])
async def test_a_new_store_is_set_up_from_the_app_when_the_racer_says_so(
    tmp_path: Path, made: bool
) -> None:
    share = tmp_path / "league-share"
    if made:
        share.mkdir()
    url = f"dir:{share}"
    data_home()
    record("ana", [11.0])
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        notes = Notifications(app)
        screen = await sync_with(pilot, url)
        dialog = app.screen
        assert isinstance(dialog, ConfirmDialog)
        text = painted(dialog)
        assert "Set up a store at" in text
        assert ("does not exist" in text) is not made  # a missing folder may be a drive
        await pilot.press("n")
        await settle(pilot)
        job = " ".join(painted(screen.query_one(JobLine)).split())
        assert "not set up" in job and "Press s to be asked again" in job
        assert not (share / MARKER_NAME).exists()
        await pilot.press("s")
        await settle(pilot)
        await pilot.press("y")
        await settle(pilot)
        assert app.screen is screen
        assert (share / MARKER_NAME).is_file()
        # The racer, track and race, and the founding record: the host set the store up.
        assert f"Synced with {url}: pushed 4" in summary(screen)
        assert "is the league's organiser key" in summary(screen)
        assert "racer-tui sync init" not in notes.text()  # no command line needed


async def test_a_failed_sync_never_shows_the_last_success_as_news(
    tmp_path: Path, store_url: str
) -> None:
    data_home()
    record("ana", [11.0])
    app = create_app(start="league")
    async with app.run_test(size=(100, 30)) as pilot:
        screen = await sync_with(pilot, store_url)
        assert "Synced with" in summary(screen)
        # The shared folder goes away (the USB stick is pulled) and the racer syncs again.
        shutil.rmtree(store_url.removeprefix("dir:"))
        await pilot.press("s")
        await settle(pilot)
        shown = painted(screen.query_one("#sync-summary"))
        assert "Synced with" not in shown
        assert "The last sync failed at" in shown and "press s to try again" in shown
        job = painted(screen.query_one(JobLine))
        assert "Failed at" in job and "%" not in job  # stopped, not spinning
        await pilot.press("escape")
        await settle(pilot)
        assert "sync failed" in status_line(app)
        # A sync that works again clears it.
        with open_store(store_url) as store:
            store.init()
        screen = await open_sync(pilot)
        await pilot.press("s")
        await settle(pilot)
        await pilot.press("escape")
        await settle(pilot)
        assert "sync failed" not in status_line(app)


async def test_the_sync_screen_opened_again_shows_the_present_not_the_last_visit(
    tmp_path: Path, store_url: str
) -> None:
    # The app keeps one Sync screen (composing it is most of what opening it costs); a
    # second visit must look like a first one, read afresh.
    data_home()
    record("ana", [11.0])
    app = create_app(start="league")
    async with app.run_test(size=(100, 30)) as pilot:
        first = await open_sync(pilot)
        await set_store(pilot, first, store_url)
        await pilot.press("s")
        await settle(pilot)
        assert "Synced with" in summary(first)
        assert "Done at" in painted(first.query_one(JobLine))
        # The racer types a URL that is refused, then half of another, and leaves without
        # saving.
        field = first.query_one("#sync-url", Input)
        field.focus()
        field.value = "ftp://nowhere"
        await pilot.press("enter")
        await settle(pilot)
        assert painted(first.query_one("#problem")).strip()  # said under the field
        assert field.has_class("-problem") and first.query_one("#problem").has_class("-shown")
        field.value = "dir:/mnt/half-typ"
        await pilot.press("escape", "escape")
        await settle(pilot)
        assert isinstance(app.screen, LeagueScreen)
        record("bo", [12.0])  # a race recorded since: not pushed yet
        again = await open_sync(pilot)
        assert again is first
        assert again.query_one("#sync-url", Input).value == store_url
        assert not again.query_one("#sync-url", Input).has_class("-problem")
        assert not again.query_one("#problem").has_class("-shown")
        assert summary(again) == ""  # the last visit's sync is not news
        assert painted(again.query_one(JobLine)).strip() == ""
        shown = painted(again.query_one("#sync-summary"))
        assert "Last push:" in shown and "new here, not pushed yet" in shown
        assert "0 new here" not in shown  # bo's race (racer and race records) is counted
        await pilot.press("s")
        await settle(pilot)
        assert "Synced with" in summary(again)
        assert again.pulled == 0  # this visit pulled nothing new


async def test_a_racer_with_no_name_yet_is_told_how_to_give_one_in_the_app(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, store_url: str
) -> None:
    on_machine(monkeypatch, tmp_path / "organiser")
    found_here(store_url)
    with open_league() as league:
        sync_league(league, store_url)
    on_machine(monkeypatch, tmp_path / "newcomer")  # has never said who they are
    app = create_app(start="league")
    async with app.run_test(size=(100, 30)) as pilot:
        screen = await sync_with(pilot, store_url)
        said = summary(screen)
        assert "no racer name is saved here yet" in said
        assert "submit a result under your name (u in the Garage), then sync again" in said
        assert "racer-tui" not in said  # the command line's words stay there


async def test_a_malformed_record_in_the_store_is_listed_as_quarantined(
    store_url: str,
) -> None:
    folder = Path(store_url.removeprefix("dir:")) / "records" / "racer" / "Z"
    folder.mkdir(parents=True)
    junk = folder / f"{BAD_ID}.json"
    junk.write_text(f'{{"name": "{MARKUP_NAME}", "oops"')
    os.utime(junk, (1_700_000_000, 1_700_000_000))  # old enough not to be a write in flight
    data_home()
    record("ana", [11.0])
    with open_league() as league:
        save_store(league, store_url)
    app = create_app(start="league")
    async with app.run_test(size=(120, 36)) as pilot:
        screen = await open_sync(pilot)
        await pilot.press("s")
        await settle(pilot)
        assert "1 quarantined" in summary(screen)
        table = screen.query_one("#sync-quarantine", DataTable)
        assert table.row_count == 1
        shown = painted(table)
        assert BAD_ID in shown and "racer" in shown
        assert "Quarantined (1)" in painted(screen.query_one("#sync-quarantine-title"))
        await pilot.press("escape")
        await settle(pilot)
        assert "1 quarantined" in status_line(app)


async def test_a_bad_url_is_refused_with_a_sentence_and_not_saved() -> None:
    data_home()
    app = create_app(start="league")
    async with app.run_test(size=(100, 30)) as pilot:
        screen = await open_sync(pilot)
        await set_store(pilot, screen, "ftp://league-share")
        problem = painted(screen.query_one("#problem"))
        assert "is not a store URL" in problem and "dir:PATH" in problem
        await set_store(pilot, screen, "s3://bucket/bundles")
        assert "holds model bundles" in painted(screen.query_one("#problem"))
        await pilot.press("escape", "s")  # leave the field; Sync checks the URL again
        await settle(pilot)
        assert "holds model bundles" in painted(screen.query_one("#problem"))
    with open_league() as league:
        assert local.get_setting(league, local.STORE_SETTING) is None


async def test_conflicts_show_what_differs_and_both_sides() -> None:
    data_home()
    with open_league() as league:
        save_store(league, "dir:/media/league-share")
        with league.transaction():
            local.add_conflict(
                league,
                "dir:/media/league-share",
                "racer",
                BAD_ID,
                "racer differs",
                local=("a" * 64, 0, '{"name":"ada"}'),
                remote=("b" * 64, 0, f'{{"name":"{MARKUP_NAME}"}}'),
            )
    app = create_app(start="league")
    async with app.run_test(size=(140, 36)) as pilot:
        await settle(pilot)
        assert "1 conflict" in status_line(app)
        screen = await open_sync(pilot)
        shown = painted(screen.query_one("#sync-conflicts", DataTable))
        assert BAD_ID in shown and "name" in shown
        assert 'name="ada"' in shown and f'name="{MARKUP_NAME}"' in shown
        # The action is in the command palette, with the other League keys.
        titles = [command.text for command in app.palette_commands(app.screen)]
        assert "League: Sync" in titles and "This screen: Sync now" in titles


async def test_a_league_refusal_during_a_sync_names_the_apps_key(
    monkeypatch: pytest.MonkeyPatch, store_url: str
) -> None:
    """A league error that ends in a remedy the app offers with a key is said with that key,
    in the toast and on the job line, never as the command line's command."""
    import racer_tui.app.screens.sync as sync_screen
    from league.errors import LeagueError
    from sim.foundation.remedies import Fix

    found_here(store_url)

    def refuse(*_: object, **__: object) -> None:
        problem = "a pulled race is on track 'zzqxw', which is not on this machine"
        raise LeagueError(
            f"{problem}; import it with `racer-tui tracks import FILE`.",
            problem=problem,
            fix=Fix.IMPORT_TRACK,
        )

    monkeypatch.setattr(sync_screen, "sync_league", refuse)
    app = create_app(start="league")
    async with app.run_test(size=(100, 30)) as pilot:
        notes = Notifications(app)
        screen = await sync_with(pilot, store_url)
        said = notes.text("error")
        assert "not on this machine; import its .npy file on the Tracks screen (i there)" in said
        assert "racer-tui" not in said
        line = painted(screen.query_one(JobLine))
        assert "(i there)" in " ".join(line.split()) and "racer-tui" not in line
