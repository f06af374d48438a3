"""Names typed in the app are refused as the command line refuses them (issue 42, points 11
and 13): U+202E is kept and refused in the CLI's sentence, not silently dropped; a long bad
name is echoed cut short, not in nine lines under the field."""

from __future__ import annotations

from pathlib import Path

from textual.widgets import Input, Static

from racer_tui.app.application import create_app
from racer_tui.app.keys_as_delivered import drain, typed
from racer_tui.app.model_form import check_name
from racer_tui.app.screens.dialogs import ImportDialog, InputDialog
from racer_tui.app.screens.model_editor import ModelEditorScreen
from sim.garage.folder import ModelError, check_model_name, list_models
from sim.garage.options import new_model
from tests.racer_tui.screens.tui_helpers import painted, settle

OVERRIDE = "abc\u202edef"


def _cli_sentence(name: str) -> str:
    """What `racer-tui model new NAME` says (without its `racer-tui: ` prefix)."""
    try:
        check_model_name(name)
    except ModelError as error:
        return str(error)
    raise AssertionError(f"{name!r} was accepted")


def _said(screen: object, selector: str) -> str:
    line = screen.query_one(selector, Static)  # type: ignore[attr-defined]
    return " ".join(painted(line).split())


async def test_a_bidi_override_typed_in_the_clone_dialog_is_refused_as_the_cli_does() -> None:
    new_model("one")
    app = create_app(start="garage")
    async with app.run_test(size=(100, 30)) as pilot:
        await settle(pilot)
        await pilot.press("c")
        await drain(pilot)
        dialog = app.screen
        assert isinstance(dialog, InputDialog)
        await pilot.press("ctrl+a", "ctrl+k")
        typed(app, OVERRIDE)  # as a terminal delivers it: key right_to_left_override
        await drain(pilot)
        assert dialog.query_one(Input).value == OVERRIDE  # kept, not silently dropped
        await pilot.press("enter")
        await drain(pilot)
        assert app.screen is dialog
        said = _said(dialog, "#problem")
        assert said == " ".join(_cli_sentence(OVERRIDE).split())
        assert [folder.name for folder in list_models()] == ["one"]


async def test_a_bidi_override_typed_in_the_editor_is_refused_by_the_name_field() -> None:
    app = create_app(start="garage")
    async with app.run_test(size=(120, 40)) as pilot:
        await settle(pilot)
        await pilot.press("n")
        await drain(pilot)
        editor = app.screen
        assert isinstance(editor, ModelEditorScreen)
        typed(app, OVERRIDE)
        await drain(pilot)
        assert editor.query_one("#name", Input).value == OVERRIDE
        await pilot.press("ctrl+s")
        await settle(pilot)
        said = _said(editor, "#name-problem")
        assert said == " ".join(check_name(OVERRIDE, set()).split())  # type: ignore[union-attr]
        assert "cannot be a model name" in said
        assert list_models() == []


async def test_a_long_bad_name_is_echoed_cut_short_in_the_import_dialog(tmp_path: Path) -> None:
    folder = tmp_path / "source"
    folder.mkdir()
    app = create_app(start="garage")
    async with app.run_test(size=(80, 24)) as pilot:
        await settle(pilot)
        await pilot.press("i")
        dialog = app.screen
        assert isinstance(dialog, ImportDialog)
        dialog.query_one("#path", Input).value = str(folder)
        dialog.query_one("#name", Input).value = "x!" * 150
        await pilot.press("enter")
        await drain(pilot)
        assert app.screen is dialog
        problem = dialog.query_one("#problem", Static)
        said = painted(problem)
        assert "(300 characters) cannot be a model name" in " ".join(said.split())
        assert said.count("x!") < 30  # not the whole name again
        assert problem.region.height <= 3
