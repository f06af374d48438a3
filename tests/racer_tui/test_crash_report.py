"""A crash is never silent (issue 42): an unexpected error writes a report beside the data,
one sentence says where, unread keys are dropped and the exit status is non-zero."""

from __future__ import annotations

import io
from pathlib import Path

import pytest

from racer_tui.app import application as app_module
from racer_tui.app.application import create_app, exit_status
from racer_tui.app.crash_report import CRASHES_DIR, crash_sentence, drop_unread_keys
from racer_tui.app.screens.garage import GarageScreen
from sim.garage.options import new_model


class InjectedError(RuntimeError):
    """The error a test plants in a screen's action."""


def _fail(self: GarageScreen) -> None:
    raise InjectedError("planted by the test")


async def test_an_unexpected_error_writes_a_report_and_exits_non_zero(
    racer_home: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    new_model("crashy")
    monkeypatch.setattr(GarageScreen, "action_reload", _fail)
    app = create_app(start="garage")
    with pytest.raises(InjectedError):
        async with app.run_test(size=(80, 24)) as pilot:
            await pilot.pause()
            await pilot.press("down", "ctrl+r")
            await pilot.pause()
    assert app.return_code not in (None, 0)
    reports = list((racer_home / CRASHES_DIR).glob("*.txt"))
    assert len(reports) == 1 and app.crash_report == reports[0]
    report = reports[0].read_text(encoding="utf-8")
    assert "InjectedError: planted by the test" in report  # the traceback
    assert "textual " in report and "python " in report and "racer-tui " in report
    assert "Last keys (oldest first): down ctrl+r" in report
    assert "Screen: GarageScreen" in report
    assert "crashy" in report  # the garage's table, as the screen showed it

    status = exit_status(app)
    assert status != 0
    said = capsys.readouterr().err.strip().splitlines()
    # Textual prints the traceback once the terminal is back; the last line says where.
    assert said[-1] == crash_sentence(reports[0])
    assert str(reports[0]) in said[-1]


async def test_a_report_that_cannot_be_written_still_exits_non_zero(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    def no_disk(text: str, when: object) -> Path:
        raise OSError("No space left on device")

    monkeypatch.setattr(app_module, "write_report", no_disk)
    monkeypatch.setattr(GarageScreen, "action_reload", _fail)
    app = create_app(start="garage")
    with pytest.raises(InjectedError):
        async with app.run_test(size=(80, 24)) as pilot:
            await pilot.press("ctrl+r")
    assert exit_status(app) != 0
    said = capsys.readouterr().err
    assert "could not write its report (No space left on device)" in said


async def test_a_quit_exits_zero_and_says_nothing(capsys: pytest.CaptureFixture[str]) -> None:
    app = create_app(start="garage")
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.press("q")
    assert exit_status(app) == 0
    assert capsys.readouterr().err == ""


def test_unread_keys_are_dropped_only_from_a_terminal(monkeypatch: pytest.MonkeyPatch) -> None:
    flushed: list[tuple[int, int]] = []
    monkeypatch.setattr(
        "racer_tui.app.crash_report.termios.tcflush", lambda fd, which: flushed.append((fd, which))
    )
    drop_unread_keys(io.StringIO("keys"))  # not a terminal: nothing to flush
    assert flushed == []

    class Terminal(io.StringIO):
        def isatty(self) -> bool:
            return True

        def fileno(self) -> int:
            return 7

    drop_unread_keys(Terminal())
    import termios

    assert flushed == [(7, termios.TCIFLUSH)]


def test_the_night_projector_command_ends_with_the_apps_status(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # The venue's screen runs the app as `racer-tui` does: a crash there ends non-zero.
    from league.nights import new_night
    from league.opening import open_league
    from racer_tui.cli.main import main
    from sim.foundation.home import data_home
    from sim.tracks.catalog import resolve_track

    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        night = new_night(league, resolve_track("beginner-oval"), name="friday")
    ran: list[str | None] = []

    def crashed(*, projector_night: str | None = None, db_path: Path | None = None) -> int:
        ran.append(projector_night)
        return 1

    monkeypatch.setattr(app_module, "run_app", crashed)
    assert main(["night", "projector", "friday"]) == 1
    assert ran == [night.id]
