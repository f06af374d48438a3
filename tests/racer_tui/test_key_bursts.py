"""Keys in bursts, as a terminal delivers them (issue 42): nothing typed quickly crashes
the app. Each test is a crash found by hand or by the monkey, queued with `burst` (no wait
between keys), which `Pilot.press` (idle after every key) never reproduced."""

from __future__ import annotations

from textual.widgets import Input, OptionList

from racer_tui.app.application import create_app
from racer_tui.app.keys_as_delivered import burst, drain, typed
from racer_tui.app.screens.garage import GarageScreen
from racer_tui.app.screens.help import HelpScreen
from racer_tui.app.screens.league import LeagueScreen
from racer_tui.app.screens.model_editor import ModelEditorScreen
from sim.garage.options import new_model

EDITOR_BURST = "down down up pagedown home end tab shift+tab enter escape question_mark escape"


async def test_quick_keys_in_and_out_of_the_editor_never_crash_it() -> None:
    # Issue 42, point 1: Esc in the burst that opened the editor read the steering-levels
    # Select before it had mounted: int("Select.NULL") crashed the app.
    new_model("one")
    new_model("two")
    app = create_app(start="garage")
    async with app.run_test(size=(80, 24)) as pilot:
        await drain(pilot)
        burst(app, EDITOR_BURST.split() * 3)
        await drain(pilot)
        assert app._exception is None
        assert app.is_running
        assert isinstance(app.section_base, GarageScreen)


async def test_escape_right_after_opening_the_editor_closes_it_unchanged() -> None:
    new_model("one")
    app = create_app(start="garage")
    async with app.run_test(size=(80, 24)) as pilot:
        await drain(pilot)
        burst(app, ["e", "escape"])
        await drain(pilot)
        # Nothing was changed, so nothing is asked: the editor is simply closed.
        assert not isinstance(app.screen, ModelEditorScreen)
        assert isinstance(app.screen, GarageScreen)


async def test_a_page_key_right_after_opening_the_palette_moves_without_crashing() -> None:
    # Issue 42, point 2: a page key reaching the palette's list before its first layout
    # raised KeyError: 0 in Textual's OptionList._move_page.
    app = create_app(start="garage")
    async with app.run_test(size=(80, 24)) as pilot:
        await drain(pilot)
        for page in ("pagedown", "pageup"):
            burst(app, ["ctrl+p", page, page])
            await drain(pilot)
            assert app._exception is None
            burst(app, ["escape"])
            await drain(pilot)


async def test_a_page_key_right_after_opening_a_select_moves_without_crashing() -> None:
    new_model("one")
    app = create_app(start="garage")
    async with app.run_test(size=(80, 24)) as pilot:
        await drain(pilot)
        await pilot.press("e")
        await drain(pilot)
        burst(app, ["enter", "pagedown", "pagedown", "pageup", "escape", "enter", "pageup"])
        await drain(pilot)
        assert app._exception is None
        assert isinstance(app.screen, ModelEditorScreen)


async def test_a_page_key_before_layout_goes_to_the_end_it_points_at() -> None:
    # The workaround itself: a list not laid out yet pages to its last or first option.
    app = create_app(start="garage")
    async with app.run_test(size=(80, 24)):
        unshown = OptionList("a", "b", "c")
        unshown.highlighted = 0
        unshown._move_page(1)
        assert unshown.highlighted == 2
        unshown._move_page(-1)
        assert unshown.highlighted == 0


async def test_enter_then_escape_in_the_palette_closes_it_once() -> None:
    # Found by the monkey: Enter on a command, then Esc before the selection was handled,
    # dismissed the palette twice; the second pop found only the section's own screen
    # (ScreenStackError: Can't pop screen).
    app = create_app(start="garage")
    async with app.run_test(size=(80, 24)) as pilot:
        await drain(pilot)
        burst(app, ["ctrl+p", *"go to tracks"])
        await drain(pilot)
        burst(app, ["enter", "escape"])
        await drain(pilot)
        assert app._exception is None
        assert len(app.screen_stack) == 1


async def test_the_editor_form_reads_its_choices_before_the_selects_mount() -> None:
    # The root of point 1: a Select's value is Select.NULL until it mounts, whatever it was
    # built with; the form reads what it was built with until then.
    from textual.widgets import Select

    from racer_tui.app.screens.form_select import FormSelect, choice_of

    levels = FormSelect([("3", 3), ("5", 5)], value=5, id="steering-levels")
    assert levels.value == Select.NULL  # Textual's, before mounting
    assert levels.chosen == 5
    assert choice_of(levels, 3) == 5
    assert choice_of(Select([("a", "a")], prompt="pick"), "b") == "b"


async def test_a_save_that_ends_while_discard_is_asked_closes_the_editor_and_its_question() -> None:
    # Found by the monkey: ctrl+s, then Esc while the save ran. The save's end closed the
    # editor, but Textual popped the screen on top (the "Discard your changes?" question)
    # and left the editor open with its result given; its Discard then raised
    # InvalidStateError.
    from racer_tui.app.screens.dialogs import ConfirmDialog
    from racer_tui.app.screens.model_editor import ModelSaved

    new_model("one")
    app = create_app(start="garage")
    async with app.run_test(size=(80, 24)) as pilot:
        await drain(pilot)
        await pilot.press("e")
        await drain(pilot)
        editor = app.screen
        assert isinstance(editor, ModelEditorScreen)
        editor.query_one("#max-minutes", Input).value = "12"  # a change, so that Esc asks
        await pilot.press("escape")
        await drain(pilot)
        assert isinstance(app.screen, ConfirmDialog)
        editor.post_message(ModelSaved("one", created=False))  # the save ends now
        await drain(pilot)
        assert app._exception is None
        assert isinstance(app.screen, GarageScreen)
        assert editor not in app.screen_stack
        burst(app, ["y", "escape"])  # what the racer pressed next reaches the Garage
        await drain(pilot)
        assert app._exception is None
        assert isinstance(app.screen, GarageScreen)


async def test_a_click_on_the_header_of_a_table_without_columns_does_nothing() -> None:
    # Found by the monkey on the Nights screen (its heats table before a draw): Textual's
    # DataTable read the clicked header's column by index and raised IndexError.
    from textual.app import App, ComposeResult
    from textual.widgets import DataTable

    from racer_tui.app.textual_workarounds import apply_workarounds

    class OneTable(App[None]):
        def compose(self) -> ComposeResult:
            yield DataTable(cursor_type="row")

    apply_workarounds()
    app = OneTable()
    async with app.run_test(size=(40, 10)) as pilot:
        table = app.query_one(DataTable)
        await pilot.click(DataTable, offset=(3, 0))
        table.add_columns("heat", "car")
        table.add_row("1", "ada")
        await pilot.pause()
        table.clear(columns=True)
        await pilot.click(DataTable, offset=(3, 0))
        await pilot.pause()
        assert app._exception is None
        assert app.is_running


async def test_a_palette_search_that_starts_after_the_palette_closed_ends_quietly() -> None:
    # Found by the monkey: the palette's search worker looked up its result list after
    # the palette had closed (ctrl+p and Esc in one burst), and its NoMatches stopped the
    # app. The search is started here on a palette already closed, as the race left it.
    from textual.command import CommandPalette

    app = create_app(start="garage")
    async with app.run_test(size=(80, 24)) as pilot:
        await drain(pilot)
        burst(app, ["ctrl+p"])
        await drain(pilot)
        palette = app.screen
        assert isinstance(palette, CommandPalette)
        burst(app, ["escape"])
        await drain(pilot)
        palette._gather_commands("go")
        await drain(pilot)
        assert app._exception is None
        assert app.is_running and isinstance(app.screen, GarageScreen)


async def test_the_palette_opened_again_as_the_last_one_closes_never_crashes() -> None:
    # The monkey (seed 401): a palette command chosen with Enter and ctrl+p in the same
    # burst opened a second palette while the first was still being taken down; Textual
    # gives its palette one fixed id, so that was a DuplicateIds crash. Sooner, the ctrl+p
    # met the first palette still open and was lost.
    from textual.command import CommandPalette

    app = create_app(start="garage")
    async with app.run_test(size=(80, 24)) as pilot:
        await drain(pilot)
        for _ in range(3):
            burst(app, ["ctrl+p", "enter", "ctrl+p"])
            await drain(pilot)
            assert app._exception is None
            assert isinstance(app.screen, CommandPalette)  # the second one opened
            burst(app, ["escape"])
            await drain(pilot)


async def test_escape_and_a_key_read_together_are_both_keys() -> None:
    """Esc, then `?` or a section's digit, typed quickly reach the app in one read, which
    Textual took for Alt+key and then dropped the Esc (or, for a digit, read as a macOS
    Option character): the host's help opened over the dialog, or nothing happened."""
    app = create_app(start="garage")
    async with app.run_test(size=(80, 24)) as pilot:
        await drain(pilot)
        await pilot.press("question_mark")
        await drain(pilot)
        assert isinstance(app.screen, HelpScreen)
        typed(app, "\x1b5")  # close the help, then the League
        await drain(pilot)
        assert isinstance(app.screen, LeagueScreen)
        await pilot.press("n")  # the Nights screen, whose Esc goes back to the League
        await drain(pilot)
        typed(app, "\x1b?")
        await drain(pilot)
        assert isinstance(app.screen, HelpScreen)
        await pilot.press("escape")
        await drain(pilot)
        assert isinstance(app.screen, LeagueScreen)
        # A real sequence that starts with Esc is still one key.
        typed(app, "\x1b[B")
        await drain(pilot)
        assert isinstance(app.screen, LeagueScreen) and app.is_running


async def test_enter_escape_help_escape_in_one_read_leaves_the_garage_as_it_was() -> None:
    # The host walk: `Enter Escape ? Escape` sent at once ended in the model's editor: the
    # first Esc, with `?` and another Esc behind it, was read as `^`.
    new_model("one")
    app = create_app(start="garage")
    async with app.run_test(size=(80, 24)) as pilot:
        await drain(pilot)
        typed(app, "\r\x1b?\x1b")
        await drain(pilot)
        assert isinstance(app.screen, GarageScreen)
        assert app.recent_keys.listed()[-4:] == ["enter", "escape", "question_mark", "escape"]
