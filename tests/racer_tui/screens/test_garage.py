"""The garage screen: list and detail, clone, delete, import, export and race."""

from __future__ import annotations

import io
import json
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

from rich.console import Console
from textual.screen import Screen
from textual.widgets import DataTable, Input, Static

from racer_tui.app.application import create_app
from racer_tui.app.keys_as_delivered import burst, drain
from racer_tui.app.screens.dialogs import ConfirmDialog, ImportDialog, InputDialog
from racer_tui.app.screens.garage import GarageScreen
from racer_tui.app.screens.race_screen import RaceScreen
from racer_tui.app.screens.train_dialog import TrainDialog
from racer_tui.app.widgets.model_detail import ModelDetail
from sim.garage.bundle import read_bundle
from sim.garage.folder import list_models, open_model
from sim.garage.options import new_model
from sim.training.evaluation import evaluate_model
from tests.racer_tui.screens.tui_helpers import (
    Notifications,
    painted,
    settle,
    trained_model,
    wait_for,
)


def _names() -> list[str]:
    return [folder.name for folder in list_models()]


async def test_the_table_lists_models_and_the_detail_follows_the_cursor() -> None:
    new_model("ada", max_speed=2.0, speed_levels=1)
    new_model("bob", sensors=["lidar"])
    app = create_app()
    async with app.run_test(size=(140, 40)) as pilot:
        await settle(pilot)
        garage = app.screen
        assert isinstance(garage, GarageScreen)
        table = garage.query_one("#models", DataTable)
        assert [table.get_row_at(i)[0].plain for i in range(table.row_count)] == ["ada", "bob"]
        assert table.get_row_at(0)[1].plain == "untrained"
        detail = garage.query_one(ModelDetail)
        assert "5 discrete, up to 2 m/s" in painted(detail)
        await pilot.press("down")
        await settle(pilot)
        text = painted(detail)
        assert "bob" in text and "lidar" in text


async def test_an_evaluation_made_before_the_last_training_is_marked_old() -> None:
    """A retrained model's evaluation laps are its old policy's: the list and the detail
    say so (the host walk read a retrained model's old lap as its own)."""
    folder = trained_model("eva", track="beginner-oval")
    evaluate_model(folder, trials=1)
    trained_model("fresh", track="beginner-oval")
    evaluate_model(open_model("fresh"), trials=1)
    state = {"state": "finished", "updated_at": "2999-01-01T00:00:00+00:00"}  # trained since
    folder.training_state_file.write_text(json.dumps(state), encoding="utf-8")
    app = create_app(start="garage")
    async with app.run_test(size=(140, 40)) as pilot:
        await settle(pilot)
        table = app.screen.query_one("#models", DataTable)
        best = {table.get_row_at(i)[0].plain: table.get_row_at(i)[-1].plain for i in range(2)}
        assert best["eva"].endswith(" old") and not best["fresh"].endswith(" old")
        assert best["eva"].removesuffix(" old") != "-"
        evaluations = _evaluations_said(app.screen)
        assert "(before the last training)" in evaluations
        assert "press v to evaluate it again" in evaluations
        await pilot.press("down")  # fresh: evaluated after its training
        await settle(pilot)
        evaluations = _evaluations_said(app.screen)
        assert "1/1" in evaluations and "before the last training" not in evaluations


def _evaluations_said(screen: Screen[Any]) -> str:
    """The detail's evaluations section whole (it may be scrolled out of view)."""
    console = Console(width=200, record=True, file=io.StringIO())
    console.print(screen.query_one("#detail-evaluations", Static).content)
    return " ".join(console.export_text().split())


async def test_the_list_follows_changes_made_outside_it_and_keeps_the_cursor_on_its_model() -> None:
    new_model("ada")
    new_model("bob")
    app = create_app()
    async with app.run_test(size=(100, 30)) as pilot:
        await settle(pilot)
        garage = app.screen
        assert isinstance(garage, GarageScreen)
        await pilot.press("down")
        await settle(pilot)
        assert garage.highlighted_name == "bob"

        def status_of(name: str) -> str:
            table = garage.query_one("#models", DataTable)
            rows = [table.get_row_at(i) for i in range(table.row_count)]
            return next(row[1].plain for row in rows if row[0].plain == name)

        # The host starts a training of ada from the command line, and someone copies a
        # model in that sorts first: nobody presses a key in the app.
        sleeper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
        try:
            state = {"state": "running", "pid": sleeper.pid, "message": "training"}
            open_model("ada").training_state_file.write_text(json.dumps(state))
            new_model("aaa")
            await wait_for(pilot, lambda: status_of("ada") == "training", tries=200)
            assert garage.highlighted_name == "bob"  # the model, not the row number
            assert [row["name"] for row in garage.rows] == ["aaa", "ada", "bob"]
        finally:
            sleeper.kill()
            sleeper.wait()
        # The training process is gone: the list says so by itself.
        await wait_for(pilot, lambda: status_of("ada") == "untrained", tries=200)
        assert garage.highlighted_name == "bob"


async def test_a_model_made_elsewhere_is_selected_when_the_garage_shows_it() -> None:
    # Created from the Tracks screen (n) after the Garage was shown once: the Garage's own
    # reload on coming back must not drop the model it was asked to select.
    new_model("ada")
    new_model("bob")
    app = create_app()
    async with app.run_test(size=(100, 30)) as pilot:
        await settle(pilot)
        garage = app.screen
        assert isinstance(garage, GarageScreen) and garage.highlighted_name == "ada"
        await pilot.press("2")
        await settle(pilot)
        new_model("cy")
        await app.show_model("cy")
        await settle(pilot)
        assert app.screen is garage
        assert garage.highlighted_name == "cy"


async def test_clone_takes_a_name_and_copies_the_model() -> None:
    trained_model("ada")
    app = create_app()
    async with app.run_test(size=(120, 36)) as pilot:
        await settle(pilot)
        await pilot.press("c")
        dialog = app.screen
        assert isinstance(dialog, InputDialog)
        assert dialog.query_one(Input).value == "ada-2"
        await pilot.press("enter")
        await settle(pilot)
        assert _names() == ["ada", "ada-2"]
        clone = open_model("ada-2")
        assert clone.has_policy()  # training continues from the source's weights
        assert clone.training_params().extra["CLONED_FROM"] == "ada"
        assert isinstance(app.screen, GarageScreen)
        assert app.screen.highlighted_name == "ada-2"


async def test_clone_refuses_a_taken_name_in_the_dialog() -> None:
    new_model("ada")
    new_model("ada-2")
    app = create_app()
    async with app.run_test(size=(120, 36)) as pilot:
        await settle(pilot)
        await pilot.press("c")
        field = app.screen.query_one(Input)
        field.value = "ADA-2"
        await pilot.press("enter")
        assert isinstance(app.screen, InputDialog)  # still open, with the reason
        assert "already exists" in painted(app.screen.query_one("#problem"))
        await pilot.press("escape")
        assert _names() == ["ada", "ada-2"]


async def test_delete_asks_first_and_keeps_the_model_on_no() -> None:
    new_model("ada")
    new_model("bob")
    app = create_app()
    async with app.run_test(size=(120, 36)) as pilot:
        await settle(pilot)
        await pilot.press("d")
        assert isinstance(app.screen, ConfirmDialog)
        await pilot.press("enter")  # the focus starts on Cancel: Enter does not delete
        await settle(pilot)
        assert _names() == ["ada", "bob"]
        await pilot.press("d", "y")
        await settle(pilot)
        assert _names() == ["bob"]
        assert app.screen.query_one("#models", DataTable).row_count == 1


async def test_import_the_shared_deepracer_folder(deepracer_dir: Path) -> None:
    app = create_app(start="garage")
    notes = Notifications(app)
    async with app.run_test(size=(120, 36)) as pilot:
        await settle(pilot)
        await pilot.press("i")
        assert isinstance(app.screen, ImportDialog)
        app.screen.query_one("#path", Input).value = str(deepracer_dir / "drfc-model")
        await pilot.press("enter")
        await settle(pilot)
        assert _names() == ["drfc-model"]
        assert isinstance(app.screen, GarageScreen)
        assert app.screen.highlighted_name == "drfc-model"
        told = notes.text()
        assert "Imported drfc-model" in told
        assert "template" in told  # it had no reward function: a template, said out loud
        # Remedies are the app's keys, not shell commands (the CLI prints those).
        assert "press t in the Garage to train it" in told
        assert "press e in the Garage to choose another" in told
        assert "`racer-tui" not in told
        # The job line keeps how the import ended after the notification fades.
        job = " ".join(painted(app.screen.query_one("#garage-job")).split())  # as read
        assert "Done at" in job and "Imported drfc-model." in job
        detail = app.screen.query_one(ModelDetail)
        detail.scroll_end(animate=False)
        await pilot.pause()
        shown = painted(detail)
        assert "Evaluations" in shown and "Not evaluated yet" not in shown
        assert "latest trials" in shown


def _friends_folder(deepracer_dir: Path, tmp_path: Path) -> Path:
    """A DeepRacer folder that brings someone else's reward_function.py."""
    folder = tmp_path / "from-a-friend"
    shutil.copytree(deepracer_dir / "drfc-model", folder)
    (folder / "reward_function.py").write_text(
        "def reward_function(params):\n    return 1.0\n", encoding="utf-8"
    )
    return folder


async def test_a_folder_with_someone_elses_reward_code_is_imported_only_when_confirmed(
    deepracer_dir: Path, tmp_path: Path
) -> None:
    folder = _friends_folder(deepracer_dir, tmp_path)
    app = create_app(start="garage")
    async with app.run_test(size=(120, 36)) as pilot:
        await settle(pilot)
        for answer in ("n", "y"):
            await pilot.press("i")
            app.screen.query_one("#path", Input).value = str(folder)
            await pilot.press("enter")
            await settle(pilot)
            assert isinstance(app.screen, ConfirmDialog)
            assert "code someone wrote" in painted(app.screen)
            await pilot.press(answer)
            await settle(pilot)
            assert _names() == ([] if answer == "n" else ["from-a-friend"])


async def test_a_droa_archive_brings_reward_code_and_is_asked_about_a_car_archive_not(
    deepracer_dir: Path, tmp_path: Path
) -> None:
    from tests.sim.garage.droa_archives import physical_model_archive, virtual_model_archive

    virtual = virtual_model_archive(deepracer_dir, tmp_path)
    physical = physical_model_archive(deepracer_dir, tmp_path, name="car-one")
    app = create_app(start="garage")
    async with app.run_test(size=(120, 36)) as pilot:
        await settle(pilot)
        await pilot.press("i")
        app.screen.query_one("#path", Input).value = str(virtual)
        await pilot.press("enter")
        await settle(pilot)
        assert isinstance(app.screen, ConfirmDialog)
        assert "archive's reward_function.py is code someone wrote" in painted(app.screen)
        await pilot.press("y")
        await settle(pilot)
        await pilot.press("i")
        app.screen.query_one("#path", Input).value = str(physical)
        await pilot.press("enter")
        await settle(pilot)
        assert not isinstance(app.screen, ConfirmDialog)  # a car archive has no reward code
    assert sorted(_names()) == ["car-one", "sample-model"]


async def test_import_of_a_missing_path_is_refused_in_the_dialog(tmp_path: Path) -> None:
    app = create_app(start="garage")
    async with app.run_test(size=(120, 36)) as pilot:
        await settle(pilot)
        await pilot.press("i")
        app.screen.query_one("#path", Input).value = str(tmp_path / "nope")
        await pilot.press("enter")
        assert isinstance(app.screen, ImportDialog)
        assert "does not exist" in painted(app.screen.query_one("#problem"))


async def test_a_bad_import_is_said_in_the_dialog_with_the_path_kept(tmp_path: Path) -> None:
    # Issue 42, point 10: the dialog closed on Enter and the failure was a toast; the typed
    # path was lost and a second Enter opened the editor of the highlighted model.
    (tmp_path / "empty").mkdir()
    new_model("kept")
    app = create_app(start="garage")
    notes = Notifications(app)
    async with app.run_test(size=(120, 36)) as pilot:
        await settle(pilot)
        await pilot.press("i")
        dialog = app.screen
        assert isinstance(dialog, ImportDialog)
        dialog.query_one("#path", Input).value = str(tmp_path / "empty")
        await pilot.press("enter")
        await settle(pilot)
        assert app.screen is dialog  # still open, the path still there to correct
        assert dialog.query_one("#path", Input).value == str(tmp_path / "empty")
        said = " ".join(painted(dialog.query_one("#problem")).split())
        assert "has no model_metadata.json" in said
        assert notes.text("error") == ""
        await pilot.press("enter")  # a second Enter tries again, in the dialog
        await settle(pilot)
        assert app.screen is dialog
        assert app.is_running and _names() == ["kept"]
        await pilot.press("escape")
        await settle(pilot)
        assert isinstance(app.screen, GarageScreen)


async def test_a_second_garage_job_waits_for_the_first() -> None:
    """The job line speaks of one job: while one runs, another is refused in a sentence."""
    new_model("ada")
    app = create_app(start="garage")
    notes = Notifications(app)
    async with app.run_test(size=(80, 24)) as pilot:
        await settle(pilot)
        garage = app.screen
        assert isinstance(garage, GarageScreen)
        garage.jobs.begin("Exporting ada", "x")
        await pilot.press("d")
        await settle(pilot)
        assert app.screen is garage  # no delete question
        assert "Exporting ada is still running" in notes.text("warning")
        assert "Exporting ada" in painted(garage.query_one("#garage-job"))


async def test_export_writes_a_bundle(tmp_path: Path) -> None:
    trained_model("ada")
    app = create_app()
    notes = Notifications(app)
    async with app.run_test(size=(120, 36)) as pilot:
        await settle(pilot)
        await pilot.press("x")
        assert isinstance(app.screen, InputDialog)
        app.screen.query_one(Input).value = str(tmp_path / "for-the-host")
        await pilot.press("enter")
        await settle(pilot)
        written = tmp_path / "for-the-host.racer-bundle"
        assert read_bundle(written).name == "ada"
        assert str(written) in notes.text()

        # Exporting over it asks first; saying no leaves the bundle as it was.
        written.write_bytes(b"the host's only copy")
        for answer, expected in (("n", b"the host's only copy"), ("y", None)):
            await pilot.press("x")
            app.screen.query_one(Input).value = str(written)
            await pilot.press("enter")
            await settle(pilot)
            assert isinstance(app.screen, ConfirmDialog)
            await pilot.press(answer)
            await settle(pilot)
            if expected is None:
                assert read_bundle(written).name == "ada"
            else:
                assert written.read_bytes() == expected


async def test_an_untrained_model_cannot_race_or_export() -> None:
    new_model("ada")
    app = create_app()
    notes = Notifications(app)
    async with app.run_test(size=(120, 36)) as pilot:
        await settle(pilot)
        await pilot.press("r", "x")
        assert isinstance(app.screen, GarageScreen)
        told = notes.text("warning")
        assert "has not been trained yet" in told and "no trained policy to export" in told


async def test_a_trained_model_races_with_its_own_policy() -> None:
    trained_model("ada", track="beginner-oval")
    app = create_app()
    async with app.run_test(size=(120, 36)) as pilot:
        await settle(pilot)
        await pilot.press("r")
        race = app.screen
        assert isinstance(race, RaceScreen)
        assert race.setup.track.name == "beginner-oval"
        await settle(pilot)
        assert race.failure is None
        assert race.result is not None and race.result.racer == "ada"
        assert race.result.model_hash == open_model("ada").content_hash()
        await pilot.press("escape")
        assert isinstance(app.screen, GarageScreen)

        # The race is one of this session's races in the Races section, ready to submit.
        await pilot.press("3")
        await settle(pilot)
        session = app.screen.query_one("#race-results", DataTable)
        assert session.row_count == 1
        assert "ada" in str(session.get_row_at(0)[1])


async def test_a_damaged_model_is_listed_with_its_problem_and_not_edited() -> None:
    new_model("ada")
    broken = new_model("bob")
    broken.metadata_file.write_text('{"sensor": ["VECTOR"]}', encoding="utf-8")
    app = create_app()
    notes = Notifications(app)
    async with app.run_test(size=(140, 40)) as pilot:
        await settle(pilot)
        table = app.screen.query_one("#models", DataTable)
        assert table.get_row_at(1)[1].plain == "damaged"
        await pilot.press("down")
        await settle(pilot)
        assert "action_space" in painted(app.screen.query_one(ModelDetail))  # the problem
        await pilot.press("e")
        assert isinstance(app.screen, GarageScreen)
        assert "before editing it" in notes.text("error")
    assert broken.metadata_file.read_text(encoding="utf-8") == '{"sensor": ["VECTOR"]}'


async def test_the_train_dialog_offers_the_last_budget_and_refuses_less_than_a_minute() -> None:
    folder = trained_model("ada")
    state = {"state": "finished", "budget_minutes": 7.5}  # the last run's budget
    folder.training_state_file.write_text(json.dumps(state), encoding="utf-8")
    app = create_app()
    async with app.run_test(size=(80, 24)) as pilot:
        await settle(pilot)
        await pilot.press("t")
        await settle(pilot)
        dialog = app.screen
        assert isinstance(dialog, TrainDialog)
        assert dialog.query_one("#minutes", Input).value == "7.5"  # not the model's 60 again
        dialog.query_one("#minutes", Input).value = "0"
        await pilot.press("enter")
        assert app.screen is dialog  # refused in the dialog
        assert "from 1 to 100000 minutes" in str(dialog.query_one("#problem").render())
        await pilot.press("escape")


async def test_export_for_a_deepracer_car_and_import_it_back(tmp_path: Path) -> None:
    """x with a .tar.gz name writes the car's archive; i imports it as a model that races
    but is never trained (t says why)."""
    from sim.car_archive.archive import read_car_archive

    trained_model("cam", sensors=["camera"])
    app = create_app(start="garage")
    notes = Notifications(app)
    async with app.run_test(size=(120, 36)) as pilot:
        await settle(pilot)
        await pilot.press("x")
        assert isinstance(app.screen, InputDialog)
        body = " ".join(painted(app.screen.query_one(".dialog-body")).split())
        assert ".tar.gz for a physical DeepRacer car" in body
        app.screen.query_one(Input).value = str(tmp_path / "for-my-car.tar.gz")
        await pilot.press("enter")
        await wait_for(pilot, (tmp_path / "for-my-car.tar.gz").is_file)
        await settle(pilot)
        archive = read_car_archive(tmp_path / "for-my-car.tar.gz")
        assert archive.metadata == open_model("cam").metadata()
        assert "For a DeepRacer car" in notes.text()

        await pilot.press("i")
        assert isinstance(app.screen, ImportDialog)
        app.screen.query_one("#path", Input).value = str(tmp_path / "for-my-car.tar.gz")
        await pilot.press("enter")
        await wait_for(pilot, lambda: "for-my-car" in _names())
        await settle(pilot)
        assert open_model("for-my-car").has_car_archive()
        assert isinstance(app.screen, GarageScreen)
        assert app.screen.highlighted_name == "for-my-car"
        await pilot.press("t")
        await settle(pilot)
        assert "drives with a DeepRacer car archive" in notes.text("error")


async def test_the_export_dialog_says_when_a_car_cannot_run_the_model() -> None:
    trained_model("vec")
    app = create_app(start="garage")
    async with app.run_test(size=(120, 36)) as pilot:
        await settle(pilot)
        await pilot.press("x")
        assert isinstance(app.screen, InputDialog)
        text = " ".join(painted(app.screen.query_one(".dialog-body")).split())
        assert "A DeepRacer car cannot run this model" in text and "VECTOR" in text


async def test_y_typed_right_after_enter_answers_the_import_question(
    deepracer_dir: Path, tmp_path: Path
) -> None:
    # A new host's walk at 60x20: the path, Enter and y in one burst left no question and
    # the y at the end of the path; the question comes when Enter is heard.
    folder = _friends_folder(deepracer_dir, tmp_path)
    app = create_app(start="garage")
    async with app.run_test(size=(60, 20)) as pilot:
        await settle(pilot)
        burst(app, ["i", *str(folder), "enter", "y"])
        await drain(pilot)
        await settle(pilot)
        assert _names() == ["from-a-friend"]
