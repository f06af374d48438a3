"""Help rows come from BINDINGS; the path field completes like a shell; the kept question
dialog asks each question afresh."""

from __future__ import annotations

from pathlib import Path
from typing import ClassVar

from textual.app import App
from textual.binding import Binding, BindingType
from textual.screen import Screen
from textual.widgets import Button, Static

from racer_tui.app.screens.dialogs import ConfirmDialog, PathSuggester, ask
from racer_tui.app.screens.help import binding_topics, declared_bindings, key_rows, topic_table
from tests.racer_tui.screens.tui_helpers import painted, settle


class Base(Screen[None]):
    BINDINGS: ClassVar[list[BindingType]] = [Binding("b", "base_thing", "Base thing")]


class Child(Base):
    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("n,insert", "new", "New", tooltip="make one"),
        Binding("x", "internal", show=False),  # no description: not for the help screen
    ]


class Silent(Screen[None]):
    """Declares no keys of its own."""


def test_bindings_are_collected_with_their_own_bases_and_grouped_by_action() -> None:
    # The bases here are test classes, not racer_tui ones: only racer_tui bases are walked.
    assert [b.action for b in declared_bindings(Child)] == ["new", "new", "internal"]
    rows = key_rows(declared_bindings(Child), lambda binding: binding.key)
    assert [(row.keys, row.description, row.tooltip) for row in rows] == [
        (("n", "insert"), "New", "make one")
    ]


def test_topics_skip_screens_without_described_keys_and_filter_by_words() -> None:
    topics = binding_topics(
        [("Child", Child), ("Silent", Silent)],
        lambda binding: binding.key,
        extra=[("Child", Binding("ctrl+p", "command_palette", "Command palette"))],
    )
    assert [topic.title for topic in topics] == ["Child"]
    assert topic_table(topics[0], ["palette"]) is not None
    assert topic_table(topics[0], ["nothing", "matches"]) is None


async def test_path_suggester_completes_the_last_part(tmp_path: Path) -> None:
    (tmp_path / "drfc-model").mkdir()
    (tmp_path / "notes.txt").write_text("x")
    suggester = PathSuggester()
    assert await suggester.get_suggestion(str(tmp_path / "drf")) == f"{tmp_path}/drfc-model/"
    assert await suggester.get_suggestion(str(tmp_path / "no")) == f"{tmp_path}/notes.txt"
    assert await suggester.get_suggestion(str(tmp_path / "zzz")) is None
    assert await suggester.get_suggestion(str(tmp_path / "missing" / "x")) is None
    # Several matches: as far as they agree, like a shell, never the first of them.
    (tmp_path / "walk").mkdir()
    (tmp_path / "walk2").mkdir()
    assert await suggester.get_suggestion(str(tmp_path / "wa")) == f"{tmp_path}/walk"
    assert await suggester.get_suggestion(str(tmp_path / "walk")) is None


async def test_a_forms_problem_goes_once_a_field_changes() -> None:
    """A problem is about what was typed: changing a field takes it away (the next confirm
    checks again), so a fixed date is not still called wrong."""
    from racer_tui.app.application import create_app
    from racer_tui.app.screens.nights import NewNightDialog

    app = create_app(start="league")
    async with app.run_test(size=(100, 40)) as pilot:
        await settle(pilot)
        await pilot.press("n")
        await settle(pilot)
        await pilot.press("o")
        await settle(pilot)
        dialog = app.screen
        assert isinstance(dialog, NewNightDialog)
        await pilot.press(*"friday", "enter", *"28 Nov", "ctrl+s")
        assert "is not a night's date" in str(dialog.query_one("#problem", Static).content)
        await pilot.press("backspace")
        assert not dialog.query_one("#problem", Static).has_class("-shown")


async def test_the_kept_question_dialog_asks_each_question_afresh() -> None:
    """One dialog is kept for every yes-or-no question: the second question shows its own
    words and button, starts on Cancel again even after the last one was left on the
    confirm button, and its answer goes to the second asker only."""
    answers: list[tuple[str, bool | None]] = []
    app: App[None] = App()
    async with app.run_test(size=(80, 24)) as pilot:
        ask(app, "Delete ada?", "Gone for good.", lambda yes: answers.append(("ada", yes)))
        await settle(pilot)
        first = app.screen
        assert isinstance(first, ConfirmDialog)
        await pilot.press("tab")  # onto the confirm button, then answer no with Esc
        assert app.screen.focused is first.query_one("#confirm", Button)
        await pilot.press("escape")
        await settle(pilot)
        ask(
            app,
            "Replace bob.racer-bundle?",
            "It exists.",
            lambda yes: answers.append(("bob", yes)),
            confirm_label="Replace",
        )
        await settle(pilot)
        assert app.screen is first  # the same dialog, not composed again
        text = painted(app.screen)
        assert "Replace bob.racer-bundle?" in text and "It exists." in text
        assert "Replace (y)" in text and "Delete" not in text and "ada" not in text
        assert app.screen.focused is first.query_one("#cancel", Button)
        await pilot.press("enter")  # Enter on Cancel: no
        await settle(pilot)
        assert answers == [("ada", False), ("bob", False)]
        ask(app, "Delete cy?", "Gone.", lambda yes: answers.append(("cy", yes)))
        await settle(pilot)
        await pilot.press("y")
        await settle(pilot)
        assert answers[-1] == ("cy", True)
        assert not isinstance(app.screen, ConfirmDialog)


async def test_a_longer_answer_after_a_shorter_one_is_shown_whole() -> None:
    # Issue 42's walk: "Close night (y)" showed as "Close night" in a two-row button: the
    # kept dialog had last asked "Delete (y)", and a button keeps its width when only its
    # label changes.
    app: App[None] = App()
    async with app.run_test(size=(60, 20)) as pilot:
        ask(app, "Delete ada?", "Gone for good.", lambda yes: None)
        await settle(pilot)
        await pilot.press("escape")
        await settle(pilot)
        ask(app, "Close friday?", "Final.", lambda yes: None, confirm_label="Close night")
        await settle(pilot)
        dialog = app.screen
        assert isinstance(dialog, ConfirmDialog)
        assert "Close night (y)" in painted(dialog.query_one("#confirm", Button))
        assert "Cancel (n)" in painted(dialog.query_one("#cancel", Button))


async def test_page_keys_scroll_the_help_while_its_filter_has_the_focus() -> None:
    # The walk at 60x20: PageDown did nothing until Tab left the filter.
    from textual.containers import VerticalScroll
    from textual.widgets import Input

    from racer_tui.app.application import create_app
    from racer_tui.app.screens.help import HelpScreen

    app = create_app(start="garage")
    async with app.run_test(size=(60, 20)) as pilot:
        await settle(pilot)
        await pilot.press("question_mark")
        await settle(pilot)
        assert isinstance(app.screen, HelpScreen)
        assert isinstance(app.focused, Input)
        topics = app.screen.query_one("#help-topics", VerticalScroll)
        await pilot.press("pagedown")
        await pilot.pause()
        paged = topics.scroll_target_y
        assert paged > 0
        await pilot.press("down")
        await pilot.pause()
        assert topics.scroll_target_y > paged
        await pilot.press("pageup", "pageup")
        await pilot.pause()
        assert topics.scroll_target_y == 0
        assert isinstance(app.focused, Input)  # typing still filters
