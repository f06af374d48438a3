"""The garage: the racer's models in a table, the highlighted one in detail, and what can be
done with it (new, edit, clone, delete, import, export, race).

Reading model folders, cloning, deleting, importing and exporting all happen in thread
workers; each posts a past-tense message when it is done, and a failure becomes one error
notification (see `racer_tui.app.screens.base`). The job line under the table says what the
last of them is doing or how it ended (a `Job`), so a slow import is never silent and a
failure stays readable after its notification fades.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import Any, ClassVar

from rich.text import Text
from textual import on, work
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Container
from textual.message import Message
from textual.screen import Screen
from textual.widgets import DataTable
from textual.worker import Worker

from racer_tui.app.model_form import check_name, taken_names
from racer_tui.app.screens.base import RacerScreen, ScreenJobs, error_message
from racer_tui.app.screens.coach import CoachScreen
from racer_tui.app.screens.dialogs import ImportDialog, ImportRequest, InputDialog, ask
from racer_tui.app.screens.evaluation import EvaluationScreen
from racer_tui.app.screens.export_path import export_folder
from racer_tui.app.screens.league_submit import RacerPrompt, submit_model_from
from racer_tui.app.screens.model_editor import ModelEditorScreen
from racer_tui.app.screens.race_screen import RaceScreen, RaceSetup
from racer_tui.app.screens.training import TrainingScreen
from racer_tui.app.session import keep_race
from racer_tui.app.widgets.footer import RacerFooter
from racer_tui.app.widgets.job_line import JobLine
from racer_tui.app.widgets.model_detail import ModelDetail, seconds_text, status_text
from racer_tui.app.widgets.section_header import SectionHeader
from racer_tui.app.widgets.table_fill import Col, FittedTable, fill_table
from racer_tui.app.words import in_app_words
from sim.car_archive.car_mapping import car_refusal
from sim.car_archive.file_names import CAR_ARCHIVE_SUFFIX, car_archive_path, is_car_archive_name
from sim.deepracer.action_space import ActionSpace
from sim.deepracer.files import locate_files
from sim.garage.bundle import bundle_path, export_bundle
from sim.garage.clone import clone_model
from sim.garage.coach_session import coach_model
from sim.garage.deepracer_notes import export_notes
from sim.garage.folder import ModelError, ModelFolder, delete_model, list_models, open_model
from sim.garage.imported import BUNDLE_SUFFIX
from sim.garage.importing import import_model
from sim.garage.model_archive import may_hold_reward_code
from sim.garage.options import spec_of
from sim.garage.overview import listing_signature, model_details, model_row
from sim.race.rules import DEFAULT_RULES
from sim.training.drivers import model_driver

# In a narrow terminal the sensor gives way first, then the action space (the detail panel
# shows both), then a long model name loses its end, and only then does the track go.
COLUMNS = (
    Col("model", keep=3, shrink_to=16, collapses=False),
    Col("status"),
    Col("track", keep=4),
    Col("sensor", keep=1),
    Col("actions", keep=2),
    Col("best eval"),  # the best lap of the model's evaluations (v), not of its training
)
NARROW = 120  # below this many columns the detail panel goes under the table
WATCH_SECONDS = 2.0  # how often the Garage looks for changes made outside it


def short_actions(row: dict[str, Any]) -> str:
    """The table's compact form of `describe_actions`: "10 × ≤3 m/s", "continuous ≤4 m/s"."""
    text = str(row["actions"] or "-")
    if text.startswith("continuous") and ".." in text:
        return "continuous ≤" + text.rsplit("..", 1)[-1]
    return text.replace(" discrete, up to ", " × ≤")


# --- messages from the workers --------------------------------------------------------------


@dataclass
class ModelsLoaded(Message):
    rows: list[dict[str, Any]]
    select: str | None
    generation: int  # a cancelled, slower read must not win
    signature: tuple[tuple[object, ...], ...]  # what the rows were read from (`listing_signature`)


@dataclass
class ListingLooked(Message):
    signature: tuple[tuple[object, ...], ...]


@dataclass
class ModelDetailsLoaded(Message):
    name: str
    details: dict[str, Any]
    space: ActionSpace


@dataclass
class ModelDetailsFailed(Message):
    name: str
    problem: str


@dataclass
class ModelDeleted(Message):
    name: str


@dataclass
class ModelCloned(Message):
    source: str
    name: str


@dataclass
class ModelImported(Message):
    name: str
    notes: tuple[str, ...]
    trains: bool = True  # False: it drives with a car archive, never trained here


@dataclass
class BundleExported(Message):
    name: str
    path: Path
    notes: tuple[str, ...] = ()


def import_into_garage(request: ImportRequest) -> ModelImported:
    """Run in a worker: the import itself (ModelError says what is wrong with the source)."""
    result = import_model(
        Path(request.path).expanduser(), name=request.name, untrained=request.untrained
    )
    return ModelImported(
        result.folder.name, result.notes, not result.folder.drives_with_car_archive()
    )


def confirm_someone_elses_code(
    screen: Screen[Any], request: ImportRequest, then: Callable[[ImportRequest], object]
) -> None:
    """A DeepRacer folder brings its author's reward_function.py: importing never runs it,
    but training will, with the racer's rights, so the racer says yes to that first."""
    source = Path(request.path).expanduser()
    if source.is_dir():
        brings_code = locate_files(source).reward_function is not None
    else:  # a DeepRacer on AWS model's archive brings one too
        brings_code = is_car_archive_name(source) and may_hold_reward_code(source)
    if not brings_code:
        then(request)
        return

    def answered(yes: bool | None) -> None:
        if yes:
            then(request)

    kind = "folder" if source.is_dir() else "archive"
    ask(
        screen.app,
        f"Import {source.name} with its reward function?",
        f"The {kind}'s reward_function.py is code someone wrote. Importing only reads it; "
        "training this model, or Check (ctrl+r) in the editor, runs it, held to a time and "
        "memory limit and kept from starting programs (on Linux also from your files). If "
        "it is not yours, read it first (e, Reward function tab) before you run it.",
        answered,
        confirm_label="Import",
    )


def import_model_dialog(screen: Screen[Any]) -> ImportDialog[ModelImported]:
    """The model import dialog, which imports before it closes (asking first about a
    folder's reward code): what stops an import is said in it, the path kept."""
    return ImportDialog(
        import_into_garage,
        ask_first=lambda request, go: confirm_someone_elses_code(screen, request, go),
    )


def notify_imported(screen: Screen[Any], message: ModelImported) -> None:
    notes = "".join(f"\n• {in_app_words(note)}" for note in message.notes)
    what = "track or reward function" if message.trains else "track"
    advice = f"\nPress e in the garage to change its {what}." if notes else ""
    screen.notify(f"Imported {message.name}.{notes}{advice}", timeout=15, markup=False)


class GarageScreen(RacerScreen[None]):
    """Model list on the left (or top), details of the highlighted model beside it."""

    # In the order the footer keeps them when it is narrow (80 columns fit the first nine
    # and help); every key is in the help screen and the palette.
    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("n", "new_model", "New", tooltip="Create a model in the editor"),
        Binding("e", "edit_model", "Edit", tooltip="Change the highlighted model (also Enter)"),
        Binding("t", "train_model", "Train", tooltip="Train in the background, live charts"),
        Binding("v", "evaluate_model", "Eval", tooltip="Time-trial trials, one lap each"),
        Binding("r", "race_model", "Race", tooltip="A 4-minute time trial, live"),
        Binding(
            "u",
            "submit_model",
            "Submit",
            tooltip="Submit the model's latest evaluation to the league, as `racer-tui submit`",
        ),
        Binding("c", "clone_model", "Clone", tooltip="A new model starting from this one"),
        Binding("d", "delete_model", "Delete", tooltip="Delete the highlighted model (asks)"),
        Binding(
            "i",
            "import_model",
            "Import",
            tooltip="A DeepRacer folder, a .racer-bundle or a car archive (.tar.gz)",
        ),
        Binding(
            "x",
            "export_model",
            "Export",
            tooltip="A .racer-bundle for the league, or a .tar.gz for a DeepRacer car",
        ),
        Binding(
            "o",
            "coach_model",
            "Coach",
            tooltip="The latest evaluation's best lap against the limit lap, by sector",
        ),
        Binding("ctrl+r", "reload", "Reload", tooltip="Read the model folders again", show=False),
    ]

    def __init__(self) -> None:
        super().__init__()
        self.rows: list[dict[str, Any]] = []
        self.loaded = False
        self._generation = 0
        self.racer_prompt = RacerPrompt(self)
        self.jobs = ScreenJobs(self, "#garage-job", "garage-change")
        self._signature: tuple[tuple[object, ...], ...] = ()  # of the rows shown
        self._pending_select: str | None = None  # a model to select when the list lands

    def compose(self) -> ComposeResult:
        yield SectionHeader("garage")
        with Container(id="garage-body"):
            yield FittedTable(id="models", cursor_type="row", zebra_stripes=True)
            yield ModelDetail(id="model-detail")
        yield JobLine(id="garage-job")
        yield RacerFooter()

    def on_mount(self) -> None:
        self.reload()
        self.set_interval(WATCH_SECONDS, self._watch)

    @property
    def ready_for_keys(self) -> bool:
        """The app holds keys typed before the list has landed (racer_tui.app.application)."""
        return self.loaded

    def on_resize(self) -> None:
        self.set_class(self.size.width < NARROW, "-narrow")

    def on_screen_resume(self) -> None:
        if self.loaded:
            self.reload()

    # --- loading ---------------------------------------------------------------------------

    def reload(self, select: str | None = None) -> None:
        """Read the garage again (in a worker); `select` moves the cursor to that model, or
        else it stays on the model it is on when the list arrives. A model asked for is
        selected even when a later reload (a return to the Garage) overtakes this one."""
        if select is not None:
            self._pending_select = select
        self._generation += 1
        self._load_models(self._pending_select, self._generation)

    @work(thread=True, exclusive=True, group="garage-list", exit_on_error=False)
    def _load_models(self, select: str | None, generation: int) -> None:
        signature = listing_signature()  # before the rows: a change after it is seen next
        rows = [model_row(folder) for folder in list_models()]
        self.post_message(ModelsLoaded(rows, select, generation, signature))

    def _watch(self) -> None:
        # A training started or ended from the command line (or the Training section), new
        # weights or an evaluation change what the list says: it is read again when they
        # do, while the Garage is on screen (it is read again on every return anyway).
        if self.loaded and self.is_current and not self.workers_in("garage-list"):
            self._read_signature()

    @work(thread=True, exclusive=True, group="garage-watch", exit_on_error=False)
    def _read_signature(self) -> None:
        self.post_message(ListingLooked(listing_signature()))

    def on_listing_looked(self, message: ListingLooked) -> None:
        if message.signature != self._signature and not self.workers_in("garage-list"):
            self.reload()

    def workers_in(self, group: str) -> bool:
        return any(worker.group == group and worker.is_running for worker in self.workers)

    def on_models_loaded(self, message: ModelsLoaded) -> None:
        if message.generation != self._generation:
            return
        self.loaded = True
        self._signature = message.signature
        self._pending_select = None
        select = message.select if message.select is not None else self.highlighted_name
        self.rows = message.rows
        cells = [
            (
                Text(row["name"]),  # names are plain text, never markup
                status_text(row["status"]),
                Text(row["track"] or "-"),
                Text(row["sensor"] or "-"),
                Text(short_actions(row)),
                best_eval_cell(row),
            )
            for row in message.rows
        ]
        table = self.query_one("#models", DataTable)
        fill_table(table, COLUMNS, cells, keys=[row["name"] for row in message.rows])
        count = len(message.rows)
        self.query_one(SectionHeader).set_context(
            f"{count} model{'s' if count != 1 else ''}" if count else ""
        )
        detail = self.query_one(ModelDetail)
        if not message.rows:
            detail.show_message(
                "No models yet. Press n to create one, or i to import a DeepRacer model."
            )
            return
        names = [row["name"] for row in message.rows]
        index = names.index(select) if select in names else 0
        table.move_cursor(row=index)
        self._load_details(names[index])

    @property
    def highlighted_name(self) -> str | None:
        table = self.query_one("#models", DataTable)
        if not self.rows or not 0 <= table.cursor_row < len(self.rows):
            return None
        return str(self.rows[table.cursor_row]["name"])

    @on(DataTable.RowHighlighted, "#models")
    def _highlighted(self, event: DataTable.RowHighlighted) -> None:
        if 0 <= event.cursor_row < len(self.rows):
            self._load_details(self.rows[event.cursor_row]["name"])

    @on(DataTable.RowSelected, "#models")
    def _selected(self) -> None:
        self.action_edit_model()

    @work(thread=True, exclusive=True, group="garage-detail", exit_on_error=False)
    def _load_details(self, name: str) -> None:
        try:
            folder = open_model(name)
            details = model_details(folder)
            space = folder.metadata().action_space
        except ModelError as error:
            self.post_message(ModelDetailsFailed(name, error_message(error)))
            return
        self.post_message(ModelDetailsLoaded(name, details, space))

    def on_model_details_loaded(self, message: ModelDetailsLoaded) -> None:
        if message.name == self.highlighted_name:
            self.query_one(ModelDetail).show_details(message.details, message.space)

    def on_model_details_failed(self, message: ModelDetailsFailed) -> None:
        if message.name == self.highlighted_name:
            self.query_one(ModelDetail).show_message(message.problem)

    # --- actions -----------------------------------------------------------------------------

    def _highlighted_folder(self, doing: str) -> ModelFolder | None:
        name = self.highlighted_name
        if name is None and not self.loaded:  # the app waited for the list: it cannot be read
            self.notify(
                f"The garage's models have not been read, so there is none to {doing} yet; "
                "press ctrl+r to read them again.",
                severity="warning",
            )
            return None
        if name is None:
            self.notify(f"There is no model to {doing}; press n to create one.", severity="warning")
            return None
        try:
            return open_model(name)
        except ModelError as error:
            self.notify(error_message(error), severity="error", markup=False)
            return None

    def action_reload(self) -> None:
        self.reload()

    def action_new_model(self) -> None:
        self.app.push_screen(ModelEditorScreen(), self._editor_closed)

    def action_edit_model(self) -> None:
        folder = self._highlighted_folder("edit")
        if folder is None:
            return
        try:
            spec_of(folder)  # a damaged folder is not opened: saving would overwrite it
        except ModelError as error:
            self.notify(
                f"{error} Fix the file (or delete the model) before editing it.",
                severity="error",
                markup=False,
            )
            return
        self.app.push_screen(ModelEditorScreen(folder), self._editor_closed)

    def _editor_closed(self, saved: str | None) -> None:
        if saved is not None:
            self.reload(select=saved)

    def action_clone_model(self) -> None:
        if self.jobs.busy():
            return
        folder = self._highlighted_folder("clone")
        if folder is None:
            return
        problem = folder.car_archive_problem("clone")
        if problem is not None:
            self.notify(problem[0].upper() + problem[1:], severity="warning", markup=False)
            return
        taken = taken_names()
        suggestion = next(
            f"{folder.name}-{n}" for n in range(2, 10_000) if f"{folder.name}-{n}" not in taken
        )
        start = (
            "The clone starts from this model's trained policy, so training continues from it."
            if folder.has_policy()
            else "The clone copies this model's settings (it has no trained policy yet)."
        )
        dialog = InputDialog(
            f"Clone {folder.name}",
            f"{start} Name the new model:",
            value=suggestion,
            confirm_label="Clone",
            check=lambda name: check_name(name, taken_names()),
        )
        self.app.push_screen(dialog, partial(self._clone_named, folder))

    def _clone_named(self, source: ModelFolder, name: str | None) -> None:
        if name is not None:
            self.jobs.begin(f"Cloning {source.name} as {name}", "c")
            self._clone(source, name)

    @work(thread=True, group="garage-change", exit_on_error=False)
    def _clone(self, source: ModelFolder, name: str) -> None:
        clone_model(source, name)
        self.post_message(ModelCloned(source.name, name))

    def on_model_cloned(self, message: ModelCloned) -> None:
        done = f"Cloned {message.source} as {message.name}."
        self.jobs.finish(done)
        self.notify(done, markup=False)
        self.reload(select=message.name)

    def action_delete_model(self) -> None:
        if self.jobs.busy():
            return
        folder = self._highlighted_folder("delete")
        if folder is None:
            return
        ask(
            self.app,
            f"Delete {folder.name}?",
            f"This deletes the folder {folder.path} with its policy, checkpoints, metrics and "
            "reward function. It cannot be undone; export a bundle first to keep a copy.",
            partial(self._delete_confirmed, folder),
        )

    def _delete_confirmed(self, folder: ModelFolder, yes: bool | None) -> None:
        if yes:
            self.jobs.begin(f"Deleting {folder.name}", "d")
            self._delete(folder)

    @work(thread=True, group="garage-change", exit_on_error=False)
    def _delete(self, folder: ModelFolder) -> None:
        delete_model(folder)
        self.post_message(ModelDeleted(folder.name))

    def on_model_deleted(self, message: ModelDeleted) -> None:
        done = f"Deleted {message.name}."
        self.jobs.finish(done)
        self.notify(done, markup=False)
        self.reload()

    def action_import_model(self) -> None:
        if self.jobs.busy():
            return
        self.app.push_screen(import_model_dialog(self), self._imported)

    def _imported(self, message: ModelImported | None) -> None:
        if message is not None:
            self.jobs.finish(f"Imported {message.name}.")
            notify_imported(self, message)
            self.reload(select=message.name)

    def action_export_model(self) -> None:
        if self.jobs.busy():
            return
        folder = self._highlighted_folder("export")
        if folder is None:
            return
        if not folder.has_policy():
            self.notify(
                f"{folder.name} has no trained policy to export yet; train it first.",
                severity="warning",
            )
            return

        refusal = car_refusal(folder.metadata())
        if folder.has_car_archive():
            text = (
                "This model drives with a DeepRacer car archive: it goes back to the car as a "
                ".tar.gz file (a physical DeepRacer's Models, Upload). Save it as:"
            )
            suffix = CAR_ARCHIVE_SUFFIX
        else:
            car = (
                f"A DeepRacer car cannot run this model: {refusal}."
                if refusal
                else "End the name with .tar.gz for a physical DeepRacer car instead (its "
                "Models, Upload page)."
            )
            text = (
                "A .racer-bundle holds the model's metadata, policy weights (tensors only) and "
                f"training summary: everything a league host needs to race it. {car} Save as:"
            )
            suffix = BUNDLE_SUFFIX
        dialog = InputDialog(
            f"Export {folder.name}",
            text,
            value=str(export_folder() / f"{folder.name}{suffix}"),
            confirm_label="Export",
            paths=True,
        )
        self.app.push_screen(dialog, partial(self._export_to, folder))

    def _export_to(self, folder: ModelFolder, path: str | None) -> None:
        if path is None:
            return
        chosen = Path(path).expanduser()
        for_car = is_car_archive_name(chosen) or folder.has_car_archive()
        target = car_archive_path(chosen) if for_car else bundle_path(chosen)
        if not target.exists():
            self.jobs.begin(f"Exporting {folder.name}", "x")
            self._export(folder, target, for_car=for_car)
            return

        def answered(replace: bool | None) -> None:
            if replace:
                self.jobs.begin(f"Exporting {folder.name}", "x")
                self._export(folder, target, replace=True, for_car=for_car)

        ask(
            self.app,
            f"Replace {target.name}?",
            f"{target} already exists. Replacing it loses the model it holds now.",
            answered,
            confirm_label="Replace",
        )

    @work(thread=True, group="garage-change", exit_on_error=False)
    def _export(
        self, folder: ModelFolder, path: Path, *, replace: bool = False, for_car: bool = False
    ) -> None:
        if for_car:
            from sim.car_export.export import export_car_archive  # noqa: PLC0415 (torch: only for an export)

            exported = export_car_archive(folder, path, replace=replace)
            note = (
                "For a DeepRacer car: upload it on the car's Models page; `racer-tui model "
                f"show {folder.name}` lists how the car drives each action."
            )
            self.post_message(BundleExported(folder.name, exported.path, (note, *exported.notes)))
            return
        written = export_bundle(folder, path, replace=replace)
        self.post_message(BundleExported(folder.name, written, export_notes(folder.metadata())))

    def on_bundle_exported(self, message: BundleExported) -> None:
        self.jobs.finish(f"Exported {message.name} to {message.path}.")
        notes = "".join(f"\n• {note}" for note in message.notes)
        self.notify(
            f"Exported {message.name} to {message.path}.{notes}",
            timeout=15 if notes else 10,
            markup=False,
        )

    def on_worker_state_changed(self, event: Worker.StateChanged) -> None:
        self.jobs.worker_changed(event.worker)
        # RacerScreen's handler runs next (Textual calls one per class) and notifies: the
        # line keeps the failure after the toast fades.

    async def action_train_model(self) -> None:
        """Open the Training section on this model and ask for the time budget."""
        folder = self._highlighted_folder("train")
        if folder is None:
            return
        await self.app.switch_mode("training")
        training = self.app.screen_stack[0]
        if isinstance(training, TrainingScreen):
            training.ask_to_train(folder.name)

    def action_evaluate_model(self) -> None:
        folder = self._highlighted_folder("evaluate")
        if folder is None:
            return
        if not folder.has_policy():
            self.notify(
                f"{folder.name} has not been trained yet, so it cannot drive; train it first.",
                severity="warning",
            )
            return
        self.app.push_screen(EvaluationScreen(folder.name))

    def action_coach_model(self) -> None:
        folder = self._highlighted_folder("coach")
        if folder is None:
            return
        if not folder.evaluation_files():
            first = "press v to evaluate it" if folder.has_policy() else "press t to train it"
            self.notify(
                f"{folder.name} has no evaluation to coach yet; {first} first.",
                severity="warning",
                markup=False,
            )
            return

        load = partial(coach_model, folder)
        self.app.push_screen(CoachScreen(folder.name, "latest evaluation", load))

    def action_race_model(self) -> None:
        folder = self._highlighted_folder("race")
        if folder is None:
            return
        if not folder.has_policy():
            self.notify(
                f"{folder.name} has not been trained yet, so it cannot drive; train it first.",
                severity="warning",
            )
            return
        try:
            track = folder.track()
        except ModelError as error:
            self.notify(error_message(error), severity="error", markup=False)
            return
        setup = RaceSetup(
            track=track,
            rules=DEFAULT_RULES,
            racer=folder.name,
            driver=partial(model_driver, folder),
            title=f"{folder.name} on {track.name}",
        )
        # Kept with the app's races, so the Races section can replay or submit it.
        self.app.push_screen(RaceScreen(setup), partial(keep_race, self.app))

    def action_submit_model(self) -> None:
        """What `racer-tui submit MODEL --racer NAME` does, for the highlighted model."""
        folder = self._highlighted_folder("submit")
        if folder is None:
            return
        if not folder.evaluation_files():
            self.notify(
                f"{folder.name} has no evaluation to submit yet; press v to evaluate it first.",
                severity="warning",
                markup=False,
            )
            return
        stale = folder.stale_evaluation(folder.evaluation_files()[-1])
        if stale is None:
            submit_model_from(self, self.racer_prompt, folder.name)
            return

        def confirmed(answer: bool | None) -> None:
            if answer:
                submit_model_from(self, self.racer_prompt, folder.name, allow_stale=True)

        ask(
            self.app,
            "Submit an old evaluation?",
            f"{stale}. Press v to evaluate it again, or submit this evaluation anyway.",
            confirmed,
            confirm_label="Submit anyway",
        )


def best_eval_cell(row: dict[str, Any]) -> Text:
    """The best evaluation lap; "old" after it when the model trained since its latest
    evaluation (the lap is not its policy's any more: v evaluates it again)."""
    if row["best_lap_s"] is None:
        return Text("-")
    cell = Text(seconds_text(row["best_lap_s"]))
    if row.get("evaluated_before_training"):
        cell.append(" old", style="yellow")
    return cell
