"""The app shell: first run, sections, help from BINDINGS, and the command palette."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from textual.command import CommandPalette
from textual.widgets import DataTable, Input

from racer_tui.app.application import OTHER_SCREENS, SECTION_SCREENS, RacerTuiApp, create_app
from racer_tui.app.screens.garage import GarageScreen
from racer_tui.app.screens.help import HelpScreen, declared_bindings
from racer_tui.app.screens.model_editor import ModelEditorScreen
from racer_tui.app.screens.nights import NightsScreen
from racer_tui.app.screens.races import RacesScreen
from racer_tui.app.screens.tracks import TracksScreen
from racer_tui.app.screens.welcome import WelcomeScreen
from racer_tui.app.widgets.demo_race import DemoRace
from racer_tui.app.widgets.section_header import HelpHint, SectionTab
from sim.garage.options import new_model
from tests.racer_tui.screens.tui_helpers import Notifications, painted, settle, wait_for


async def test_first_run_opens_the_welcome_screen_with_a_moving_car() -> None:
    app = create_app()
    async with app.run_test(size=(100, 30)) as pilot:
        await pilot.pause()
        assert isinstance(app.screen, WelcomeScreen)
        demo = app.screen.query_one(DemoRace)
        await wait_for(pilot, lambda: demo.car is not None, tries=300)
        first = demo.car
        await wait_for(pilot, lambda: demo.car != first, tries=300)  # playback moves it
        assert demo.frames >= 2
        assert "reference driver" in painted(demo.query_one("#demo-caption"))


async def test_with_models_the_app_opens_on_the_garage() -> None:
    new_model("ada")
    app = create_app()
    async with app.run_test(size=(100, 30)) as pilot:
        await pilot.pause()
        assert isinstance(app.screen, GarageScreen)
        await settle(pilot)
        assert app.screen.highlighted_name == "ada"


async def test_first_model_from_the_welcome_screen_lands_in_the_garage() -> None:
    app = create_app()
    async with app.run_test(size=(100, 30)) as pilot:
        await pilot.pause()
        await pilot.press("n")
        assert isinstance(app.screen, ModelEditorScreen)
        await pilot.press(*"first")
        await pilot.press("ctrl+s")
        await settle(pilot)
        assert isinstance(app.screen, GarageScreen)
        assert app.screen.highlighted_name == "first"


async def test_number_keys_switch_sections_and_keep_their_state() -> None:
    new_model("ada")
    app = create_app()
    async with app.run_test(size=(100, 30)) as pilot:
        await pilot.pause()
        await pilot.press("2")
        assert isinstance(app.screen, TracksScreen)
        await pilot.press("down")
        await pilot.press("3", "2")
        # Row 0 is the "Built-in" heading, 1 the first track: down kept across switches.
        assert app.screen.query_one("#tracks").cursor_row == 2  # type: ignore[attr-defined]
        await pilot.press("1")
        assert isinstance(app.screen, GarageScreen)


async def test_a_section_shown_before_is_painted_at_once() -> None:
    """Textual holds screen updates back for 50 ms on every mode switch (to hide a first
    compose); a section already composed is painted as soon as its key is handled."""
    new_model("ada")
    app = create_app()
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.pause()
        shown: list[str] = []
        original = app._display

        def display(screen: Any, renderable: Any) -> None:
            if renderable is not None and not app._batch_count:
                shown.append(type(screen).__name__)
            original(screen, renderable)

        app._display = display  # type: ignore[method-assign]
        # Under load the start-up screen's own hold may still be on; count from there.
        held_before = app._batch_count
        app.switch_mode("tracks")  # first visit: composed now, so updates are held
        assert app._batch_count == held_before + 1
        await settle(pilot)
        await wait_for(pilot, lambda: app._batch_count == 0)
        app.switch_mode("garage")  # shown before: painted inside the switch itself
        assert app._batch_count == 0
        assert shown[-1] == "GarageScreen"
        await settle(pilot)


async def test_the_header_tabs_switch_sections_with_the_mouse() -> None:
    app = create_app(start="garage")
    async with app.run_test(size=(100, 30)) as pilot:
        await pilot.pause()
        tabs = list(app.screen.query(SectionTab))
        assert [tab.mode for tab in tabs] == ["garage", "tracks", "races", "training", "league"]
        assert tabs[0].has_class("-current")
        await pilot.click(tabs[2])
        await pilot.pause()
        assert isinstance(app.screen, RacesScreen)
        assert app.screen.query(SectionTab)[2].has_class("-current")
        await pilot.click(HelpHint)
        assert isinstance(app.screen, HelpScreen)


async def test_digits_and_q_do_not_leave_the_editor() -> None:
    new_model("ada")
    app = create_app()
    async with app.run_test(size=(100, 30)) as pilot:
        await pilot.pause()
        await pilot.press("n")
        await pilot.press("tab")  # off the name field, onto the track picker
        await pilot.press("2", "q")
        assert isinstance(app.screen, ModelEditorScreen)
        assert app.is_running


async def test_ctrl_q_quits_from_a_screen_pushed_on_a_section() -> None:
    """q quits only from a section's own screen (never a stray q in an editor or a heat);
    ctrl+q quits from any, the Nights screen among them."""
    app = create_app(start="league")
    async with app.run_test(size=(100, 30)) as pilot:
        await pilot.pause()
        await pilot.press("n")  # the Nights screen, pushed on the League section
        await pilot.pause()
        assert len(app.screen_stack) > 1
        notes = Notifications(app)
        await pilot.press("q", "1")
        assert isinstance(app.screen, NightsScreen) and app.is_running
        assert "Esc goes back to the League; from there 1-5 switch sections." in notes.text()
        # Help says so, for the digits as for q (a host pressed 1 here and wondered).
        await pilot.press("question_mark")
        await pilot.pause()
        assert isinstance(app.screen, HelpScreen)
        help_lines = _help_text(app.screen).splitlines()
        garage = next(i for i, line in enumerate(help_lines) if line.startswith("1 "))
        garage_row = " ".join(" ".join(help_lines[garage : garage + 2]).split())
        assert "race; from a section's own screen" in garage_row
        await pilot.press("escape")
        await pilot.press("ctrl+q")
        await pilot.pause()
        assert not app.is_running


def _help_text(screen: HelpScreen) -> str:
    return "\n".join(
        painted(static)
        for static in screen.query(".help-topic, .help-topic-title")
        if static.display
    )


async def test_help_lists_every_binding_of_every_screen() -> None:
    app = create_app(start="garage")
    async with app.run_test(size=(140, 200)) as pilot:  # tall: the whole reference shows
        await pilot.pause()
        await pilot.press("question_mark")
        assert isinstance(app.screen, HelpScreen)
        text = _help_text(app.screen)
        # Every screen's keys: the sections', the app's, and every other screen's (the
        # timekeeper's among them: "every key of every screen").
        # (Tables' own keys are summed up in a few lines of their own.)
        others = [cls for _, cls in OTHER_SCREENS if cls is not DataTable]
        screens = [*SECTION_SCREENS.values(), RacerTuiApp, *others]
        for screen_class in screens:
            for binding in declared_bindings(screen_class):
                if binding.description:
                    assert binding.description in text, (screen_class, binding)
        assert "^p" in text and "Command palette" in text
        # Typing filters the reference.
        await pilot.press(*"clone")
        await pilot.pause()
        filtered = _help_text(app.screen)
        assert "Clone" in filtered and "Delete" not in filtered
        # Back from the palette over it, the filter is still there.
        help_screen = app.screen
        await pilot.press("ctrl+p")
        await pilot.pause()
        await pilot.press("escape")
        await pilot.pause()
        assert app.screen is help_screen and _help_text(app.screen) == filtered
        await pilot.press("escape")
        assert isinstance(app.screen, GarageScreen)
        # Opened again (the same screen, kept), it is unfiltered and ready for typing.
        await pilot.press("question_mark")
        await pilot.pause()
        assert app.screen is help_screen
        assert _help_text(app.screen) == text
        await pilot.press(*"delete")
        await pilot.pause()
        assert "Delete" in _help_text(app.screen) and "Clone" not in _help_text(app.screen)


async def test_help_opens_while_it_is_open_under_another_section() -> None:
    app = create_app(start="garage")
    async with app.run_test(size=(100, 30)) as pilot:
        await pilot.pause()
        await pilot.press("question_mark")
        kept = app.screen
        assert isinstance(kept, HelpScreen)
        await app.run_section_action("tracks", "app.help")  # as the palette would
        await pilot.pause()
        assert isinstance(app.screen, HelpScreen) and app.screen is not kept
        await pilot.press("escape")
        assert isinstance(app.screen, TracksScreen)


async def test_f1_opens_help_from_the_editor() -> None:
    app = create_app(start="garage")
    async with app.run_test(size=(120, 40)) as pilot:
        await pilot.pause()
        await pilot.press("n", "f1")
        assert isinstance(app.screen, HelpScreen)
        await pilot.press("escape")
        assert isinstance(app.screen, ModelEditorScreen)


async def test_palette_finds_actions_of_other_sections_and_runs_them() -> None:
    new_model("ada")
    app = create_app()
    async with app.run_test(size=(120, 40)) as pilot:
        await pilot.pause()
        await pilot.press("2")
        assert isinstance(app.screen, TracksScreen)
        await pilot.press("ctrl+p")
        assert isinstance(app.screen, CommandPalette)
        await pilot.press(*"garage clone")
        await pilot.pause(0.3)  # the palette searches asynchronously, then shows hits
        await pilot.press("enter")
        await pilot.pause()
        assert isinstance(app.screen_stack[0], GarageScreen)
        dialog_input = app.screen.query_one(Input)
        assert dialog_input.value == "ada-2"


async def test_palette_lists_every_section_action() -> None:
    app = create_app(start="garage")
    async with app.run_test(size=(120, 40)) as pilot:
        await pilot.pause()
        texts = [command.text for command in app.palette_commands(app.screen)]
        for section, screen_class in SECTION_SCREENS.items():
            for binding in declared_bindings(screen_class):
                if binding.description:
                    assert any(binding.description in text for text in texts), (section, binding)
        assert "Go to Races" in texts


async def test_importing_from_the_welcome_screen_opens_the_garage(deepracer_dir: Path) -> None:
    app = create_app()
    async with app.run_test(size=(120, 36)) as pilot:
        await pilot.pause()
        assert isinstance(app.screen, WelcomeScreen)
        await pilot.press("i")
        app.screen.query_one("#path", Input).value = str(deepracer_dir / "drfc-model")
        await pilot.press("enter")
        await settle(pilot)
        assert isinstance(app.screen, GarageScreen)
        assert app.screen.highlighted_name == "drfc-model"


async def test_a_failed_import_on_the_welcome_screen_is_said_in_the_dialog(tmp_path: Path) -> None:
    # A folder that is not a DeepRacer model: as in the Garage (issue 42, point 10), the
    # import dialog stays open with the path and says what stopped it, in place.
    (tmp_path / "not-a-model").mkdir()
    app = create_app()
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.pause()
        welcome = app.screen
        assert isinstance(welcome, WelcomeScreen)
        await pilot.press("i")
        dialog = app.screen
        dialog.query_one("#path", Input).value = str(tmp_path / "not-a-model")
        await pilot.press("enter")
        await settle(pilot)
        assert app.screen is dialog
        assert dialog.query_one("#path", Input).value == str(tmp_path / "not-a-model")
        said = " ".join(painted(dialog.query_one("#problem")).split())
        assert "has no model_metadata.json" in said
        await pilot.press("escape")
        await settle(pilot)
        assert app.screen is welcome


async def test_a_sentence_on_screen_is_not_stacked_and_a_dialogs_notes_leave_its_buttons() -> None:
    """The host walk: three screens each said the league was too new, three notes high;
    at 60x20 a note at the bottom covered the dialog's buttons it was about."""
    from textual.widgets import Button
    from textual.widgets._toast import Toast  # not exported; its class is the test's subject

    from racer_tui.app.screens.dialogs import InputDialog

    app = create_app(start="league")
    async with app.run_test(size=(60, 20), notifications=True) as pilot:
        await settle(pilot)
        app.push_screen(InputDialog("Rename", "A new name:", confirm_label="Rename"))
        await settle(pilot)
        for _ in range(3):
            app.notify("The league is newer than this racer-tui.", severity="error")
        app.notify("Something else.")
        await settle(pilot)
        toasts = list(app.screen.query(Toast))
        assert len(toasts) == 2  # the repeated sentence once, the other beside it
        lowest_note = max(toast.region.bottom for toast in toasts)
        buttons = app.screen.query(Button)
        assert lowest_note <= min(button.region.y for button in buttons)
