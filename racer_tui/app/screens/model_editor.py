"""Create or edit a model, following the AWS DeepRacer console's steps.

Four tabs: the car (name, track with a preview, sensor, training time limit), its action
space (the console's discrete generator with a per-action table, or continuous ranges, and
a picture of it), the hyperparameters (each with its allowed range beside it, from
`sim.deepracer.files.HYPERPARAMETER_SPECS`) and the reward function (a Python editor with
the four templates and a Check that runs it on sample params, maps what it pays on the
model's track beside the code, and says whether it pays for speed; all in a child process
with time limits, `sim.reward.probe`).

Problems are shown under the field they belong to and never clear the form; nothing is
written until every field checks out (see `racer_tui.app.model_form`). The screen returns the
saved model's name, or None when cancelled.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

from rich.text import Text
from textual import on, work
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal, ScrollableContainer, Vertical, VerticalScroll
from textual.message import Message
from textual.widget import Widget
from textual.widgets import (
    Button,
    DataTable,
    Input,
    Label,
    Select,
    Static,
    TabbedContent,
    TabPane,
    TextArea,
)

from racer_tui.app.model_form import (
    CONTINUOUS,
    DISCRETE,
    KEPT,
    RACE_TYPE_CHOICES,
    REWARD_FILE_NAME,
    SENSOR_CHOICES,
    SENSOR_HINTS,
    TUNABLE,
    FieldProblem,
    FormError,
    FormValues,
    action_space_of,
    create_from_form,
    field_message,
    save_edit,
    spec_of_form,
    taken_names,
    values_of,
)
from racer_tui.app.screens.base import RacerScreen
from racer_tui.app.screens.dialogs import NameInput, ask
from racer_tui.app.screens.form_select import FormSelect
from racer_tui.app.widgets.action_space_plot import ActionSpacePlot
from racer_tui.app.widgets.footer import RacerFooter
from racer_tui.app.widgets.table_fill import FittedTable, fill_table
from racer_tui.app.widgets.track_label import track_options
from racer_tui.app.widgets.track_map import TrackMap
from racer_tui.app.words import in_app_words
from racer_tui.text.reward_map import map_text
from sim.coach.reward_line import template_source
from sim.deepracer.action_space import ActionSpace
from sim.deepracer.vocabulary import MAX_SPEED, MAX_STEERING, MIN_SPEED
from sim.garage.folder import MAX_MINUTES, MIN_MINUTES, ModelError, ModelFolder
from sim.garage.options import SPEED_LEVELS, STEERING_LEVELS, ModelSpec, default_model_spec, spec_of
from sim.reward.droa_check import DroaVerdict, droa_verdict
from sim.reward.errors import RewardFunctionError
from sim.reward.lap import LapPay, verdict
from sim.reward.map import MapOptions, RewardMap
from sim.reward.probe import check_reward_source, editor_check
from sim.reward.template_files import TEMPLATES, template_name
from sim.tracks.catalog import DEFAULT_TRACK, resolve_track
from sim.tracks.track import Track, TrackError

ACTION_COLUMNS = ("#", "steering °", "speed m/s", "turn")
EDITOR_MAP_SPACING = 0.15  # metres: fine enough for a map 40 characters wide
MAP_BESIDE_CODE_COLUMNS = 110  # narrower, and the code keeps the whole width
TABS = ("tab-car", "tab-actions", "tab-training", "tab-reward")
FIELD_TABS = {
    "name": "tab-car",
    "track": "tab-car",
    "sensor": "tab-car",
    "max-minutes": "tab-car",
    "camera-randomisation": "tab-car",
    "reward": "tab-reward",
}
ACTION_FIELDS = (
    "action-kind",
    "max-steering",
    "steering-levels",
    "max-speed",
    "speed-levels",
    "steering-low",
    "steering-high",
    "speed-low",
    "speed-high",
)


def tab_of(field_id: str) -> str:
    if field_id in ACTION_FIELDS:
        return "tab-actions"
    if field_id.startswith("hp-"):
        return "tab-training"
    return FIELD_TABS.get(field_id, "tab-car")


# --- messages from the workers -------------------------------------------------------------


@dataclass
class ModelSaved(Message):
    name: str
    created: bool


@dataclass
class FormRejected(Message):
    problems: tuple[FieldProblem, ...]


class RewardChecked(Message):
    """The reward function ran on sample params: its value, or the error (with its line);
    with the map of what it pays on the model's track and its laps at two speeds."""

    def __init__(
        self,
        value: float | None,
        error: RewardFunctionError | None,
        reward_map: RewardMap | None = None,
        laps: tuple[LapPay, ...] = (),
        droa: DroaVerdict | None = None,
    ) -> None:
        super().__init__()
        self.value = value
        self.error = error
        self.reward_map = reward_map
        self.laps = laps
        self.droa = droa  # DeepRacer on AWS's verdict, once racer-tui's own check passed
        self.number = 0  # which Check this answers (a thread worker cannot be cancelled)


@dataclass
class TrackPreviewLoaded(Message):
    track: Track


def check_reward(source: str, track: str | None = None, top_speed: float = 2.0) -> RewardChecked:
    """Call the function with DeepRacer-complete sample params and, given the model's
    track, map what it pays there at its top speed and compare a slow and a fast lap: in
    a child process with a time limit (the racer's code never runs in the app's process)."""

    try:
        if track is None:
            report = check_reward_source(source, REWARD_FILE_NAME)
            droa = _droa_verdict(source, DEFAULT_TRACK)
            return RewardChecked(report.sample_reward, None, droa=droa)
        checked = editor_check(
            source,
            REWARD_FILE_NAME,
            track,
            MapOptions(spacing=EDITOR_MAP_SPACING, speed=top_speed),
            (1.0, top_speed) if top_speed > 1.0 else (top_speed, 4.0),
        )
    except RewardFunctionError as error:
        return RewardChecked(None, error)
    droa = _droa_verdict(source, track)
    return RewardChecked(checked.sample_reward, None, checked.reward_map, checked.laps, droa)


def _droa_verdict(source: str, track: str) -> DroaVerdict | None:
    """DeepRacer on AWS's validator too, since a racer may take this function there; None
    where it could not be run (racer-tui's own check has passed: that result stands)."""
    try:
        return droa_verdict(source, REWARD_FILE_NAME, track)
    except RewardFunctionError:
        return None


def droa_words(verdict: DroaVerdict) -> Text:
    """One line: whether DeepRacer on AWS would take the function, and if not its first
    reason with its line (and how many more)."""
    if verdict.accepted:
        return Text("DeepRacer on AWS would accept it too", style="dim")
    first = verdict.reasons[0]
    where = f"line {first.line}: " if first.line is not None else ""
    text = Text("DeepRacer on AWS would refuse it: ", style="yellow")
    text.append(f"{where}{first.message.strip()}")
    more = len(verdict.reasons) - 1
    if more:
        text.append(f" (and {more} more: racer-tui reward check lists them)", style="dim")
    return text


def field(
    label: str, widget: Widget, allowed: str = "", field_id: str = "", hint_id: str | None = None
) -> Vertical:
    """A labelled input with its allowed range beside it and a problem line under it
    (`hint_id` names the range's Static, for a field whose hint follows its value)."""
    key = field_id or str(widget.id)
    hint = Static(allowed, classes="field-allowed", id=hint_id)
    row = [widget, hint] if allowed else [widget]
    return Vertical(
        Label(label, classes="field-label"),
        Horizontal(*row, classes="field-row"),
        Static("", id=f"{key}-problem", classes="field-problem"),
        classes="field",
    )


def sensor_hint(sensor: str) -> str:
    return SENSOR_HINTS.get(sensor, "kept from its files")


OUTDATED_MAP = Text("changed since the last map: ctrl+r maps what it pays now", style="dim")


class ModelEditorScreen(RacerScreen[str | None]):
    """`folder` None creates a model (from the defaults, on `track` if given); otherwise it
    edits that model in place."""

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("ctrl+s", "save", "Save", tooltip="Check every field, then save", priority=True),
        Binding("ctrl+r", "check_reward", "Check reward", tooltip="Run it on sample params"),
        Binding("f2", "tab('tab-car')", "Car tab", show=False),
        Binding("f3", "tab('tab-actions')", "Action space tab", show=False),
        Binding("f4", "tab('tab-training')", "Hyperparameters tab", show=False),
        Binding("f5", "tab('tab-reward')", "Reward function tab", show=False),
        Binding("escape", "cancel", "Cancel", tooltip="Close the editor (asks if changed)"),
    ]

    def __init__(self, folder: ModelFolder | None = None, *, track: str | None = None) -> None:
        super().__init__()
        self.folder = folder
        self._preset_track = track
        self.base: ModelSpec = default_model_spec()
        self.kept: ActionSpace | None = None  # an imported action list the form cannot build
        self.trained = False
        self.archive = False  # drives with a DeepRacer car archive: its space is the graph's
        self.initial: FormValues | None = None
        self.saving = False
        self.last_check: RewardChecked | None = None
        self._checks = 0  # Checks asked for; only the newest one's answer is shown
        self._load_error = ""
        self._by_id: dict[str, Widget] = {}
        self._actions_pending = False

    # --- building the form -------------------------------------------------------------------

    def _load_base(self) -> FormValues:
        folder = self.folder
        if folder is None:
            if self._preset_track is not None:
                self.base = ModelSpec(
                    track=self._preset_track,
                    metadata=self.base.metadata,
                    hyperparameters=self.base.hyperparameters,
                    reward_source=self.base.reward_source,
                    reward_origin=self.base.reward_origin,
                    max_minutes=self.base.max_minutes,
                )
            return values_of(self.base)
        self.base = spec_of(folder)
        self.trained = folder.has_policy()
        self.archive = folder.drives_with_car_archive()
        values = values_of(self.base, folder.name)
        if values.action_kind == KEPT:
            self.kept = self.base.metadata.action_space
        return values

    def compose(self) -> ComposeResult:
        try:
            values = self._load_base()
        except ModelError as error:
            self._load_error = str(error)
            values = values_of(default_model_spec())
        self.initial = values
        title = "New model" if self.folder is None else f"Edit {self.folder.name}"
        with Horizontal(id="editor-title"):
            yield Static(Text(f"Garage › {title}"), id="editor-name")
            yield Static("F2-F5 switch tabs", id="editor-keys")
        with TabbedContent(id="editor-tabs"):
            with TabPane("Car", id="tab-car"):
                yield from self._car_tab(values)
            with TabPane("Action space", id="tab-actions"):
                yield from self._actions_tab(values)
            with TabPane("Hyperparameters", id="tab-training"):
                yield from self._training_tab(values)
            with TabPane("Reward function", id="tab-reward"):
                yield from self._reward_tab(values)
        yield RacerFooter()

    def _car_tab(self, values: FormValues) -> ComposeResult:
        tracks = track_options()
        if values.track not in {name for _, name in tracks}:
            tracks.append((Text(values.track), values.track))
        sensors = list(SENSOR_CHOICES)
        if values.sensor not in {key for key, _ in sensors}:
            sensors.append((values.sensor, values.sensor))
        with Horizontal(classes="editor-columns"):
            with VerticalScroll(classes="editor-form"):
                name = NameInput(  # keeps U+202E typed, for the name check to refuse
                    values.name,
                    placeholder="e.g. fast-lap-1",
                    id="name",
                    disabled=self.folder is not None,
                )
                yield field("Model name", name, "" if self.folder is None else "clone to rename")
                yield field(
                    "Track",
                    FormSelect(tracks, value=values.track, id="track"),
                )
                yield field(
                    "Sensor",
                    FormSelect(
                        [(label, key) for key, label in sensors],
                        value=values.sensor,
                        id="sensor",
                    ),
                    sensor_hint(values.sensor),
                    hint_id="sensor-hint",
                )
                yield field(
                    "Training time limit (minutes)",
                    Input(values.max_minutes, id="max-minutes"),
                    f"{MIN_MINUTES:g} to {MAX_MINUTES:g}",
                )
                with Vertical(id="camera-randomisation-field"):
                    randomisation = Input(values.camera_randomisation, id="camera-randomisation")
                    randomisation.tooltip = (
                        "Train for a real car's camera: off, on, or some of light, noise, "
                        "blur, pose, colours, each with a strength 0-2 (light,noise=0.5)"
                    )
                    yield field("Camera randomisation", randomisation, "on, off, noise=0.5")
                yield field(
                    "Race type",
                    FormSelect(RACE_TYPE_CHOICES, value=values.race_type, id="race-type"),
                )
                with Vertical(id="race-fields"):
                    yield field(
                        "Boxes or bot cars",
                        Input(values.race_objects, id="race-objects"),
                        "1-10 boxes, 1-6 bots",
                    )
                    with Vertical(id="bot-speed-field"):
                        yield field(
                            "Bot cars' speed (m/s)",
                            Input(values.bot_speed, id="bot-speed"),
                            "0.1 to 4",
                        )
                    yield field(
                        "Shuffle the boxes / bots change lanes",
                        FormSelect(
                            [("no", False), ("yes", True)],
                            value=values.race_shuffle,
                            id="race-shuffle",
                        ),
                        "boxes: every episode; bots: every 3-5 s",
                    )
            yield TrackMap(id="track-preview")

    def _actions_tab(self, values: FormValues) -> ComposeResult:
        kinds = [("discrete", DISCRETE), ("continuous", CONTINUOUS)]
        if self.kept is not None:
            kinds.insert(0, (f"as imported ({len(self.kept.actions)} actions)", KEPT))
        with Horizontal(classes="editor-columns"):
            with VerticalScroll(classes="editor-form"):
                if self.archive:
                    yield Static(
                        "This model drives with a DeepRacer car archive: its sensor and action "
                        "space are the archive's, and stay as they are.",
                        classes="editor-note",
                    )
                elif self.trained:
                    yield Static(
                        "This model is trained: keep its sensor, action type and number of "
                        "actions, or clone it to change them.",
                        classes="editor-note",
                    )
                yield field(
                    "Action space",
                    FormSelect(kinds, value=values.action_kind, id="action-kind"),
                )
                with Vertical(id="discrete-fields"):
                    yield field(
                        "Maximum steering angle (degrees)",
                        Input(values.max_steering, id="max-steering"),
                        f"1 to {MAX_STEERING:g}",
                    )
                    yield field(
                        "Steering angle granularity",
                        FormSelect(
                            [(str(n), n) for n in STEERING_LEVELS],
                            value=values.steering_levels,
                            id="steering-levels",
                        ),
                    )
                    yield field(
                        "Maximum speed (m/s)",
                        Input(values.max_speed, id="max-speed"),
                        f"{MIN_SPEED:g} to {MAX_SPEED:g}",
                    )
                    yield field(
                        "Speed granularity",
                        FormSelect(
                            [(str(n), n) for n in SPEED_LEVELS],
                            value=values.speed_levels,
                            id="speed-levels",
                        ),
                    )
                with Vertical(id="continuous-fields"):
                    steering = f"-{MAX_STEERING:g} to {MAX_STEERING:g}"
                    speed = f"{MIN_SPEED:g} to {MAX_SPEED:g}"
                    yield field(
                        "Lowest steering angle (degrees, right)",
                        Input(values.steering_low, id="steering-low"),
                        steering,
                    )
                    yield field(
                        "Highest steering angle (degrees, left)",
                        Input(values.steering_high, id="steering-high"),
                        steering,
                    )
                    yield field(
                        "Lowest speed (m/s)", Input(values.speed_low, id="speed-low"), speed
                    )
                    yield field(
                        "Highest speed (m/s)", Input(values.speed_high, id="speed-high"), speed
                    )
            with Vertical(id="action-view"):
                yield Static("speed (m/s) ↑   steering →", classes="field-label")
                yield ActionSpacePlot(id="action-plot")
                yield FittedTable(id="action-table", cursor_type="row", zebra_stripes=True)

    def _training_tab(self, values: FormValues) -> ComposeResult:
        with VerticalScroll(classes="editor-form"):
            yield Static(
                "DeepRacer's PPO hyperparameters; the allowed range is beside each one.",
                classes="editor-note",
            )
            for spec in TUNABLE:
                widget_id = f"hp-{spec.name}"
                text = values.hyperparameters.get(spec.name, str(spec.default))
                widget: Widget
                if spec.choices:
                    widget = FormSelect(
                        [(choice, choice) for choice in spec.choices],
                        value=text,
                        id=widget_id,
                    )
                else:
                    widget = Input(text, id=widget_id)
                label = spec.name + (f"  ({spec.help})" if spec.help else "")
                yield field(label, widget, spec.allowed())

    def _reward_tab(self, values: FormValues) -> ComposeResult:
        with Horizontal(id="reward-toolbar"):
            yield Select(
                [(name.replace("_", " "), name) for name in TEMPLATES],
                prompt="Load a template…",
                id="reward-template",
            )
            yield Button("Check (ctrl+r)", id="check-reward", variant="primary")
        with Horizontal(id="reward-body"):
            yield TextArea.code_editor(
                values.reward_source, language="python", id="reward", soft_wrap=False
            )
            yield Static(
                Text("ctrl+r maps what it pays on the model's track", style="dim"),
                id="reward-map",
            )
        yield Static("", id="reward-problem", classes="field-problem")

    def on_resize(self) -> None:
        self.set_class(self.size.width < MAP_BESIDE_CODE_COLUMNS, "-narrow")

    def on_mount(self) -> None:
        if self._load_error:
            self.notify(self._load_error, severity="error", markup=False)
            if self.folder is not None:
                # Never offer to save defaults over a model that could not be read.
                self.dismiss(None)
                return
        self._show_kind()
        self._show_race()
        self._show_camera_randomisation()
        self._refresh_actions()
        if self.initial is not None:
            self._load_preview(self.initial.track)
        if self.folder is None:
            self.query_one("#name", Input).focus()
        else:
            self.query_one("#track", Select).focus()

    # --- reading the form -----------------------------------------------------------------

    def _input(self, widget_id: str) -> str:
        widget = self._widget(widget_id)
        assert isinstance(widget, Input), widget_id
        return widget.value

    def _select(self, widget_id: str) -> object:
        """A choice of the form: the one it was built with until the Select has mounted
        (a key in the burst that opened the editor may read the form before that)."""
        widget = self._widget(widget_id)
        assert isinstance(widget, FormSelect), widget_id
        return widget.chosen

    def values(self) -> FormValues:
        hyperparameters: dict[str, str] = {}
        for spec in TUNABLE:
            widget_id = f"hp-{spec.name}"
            hyperparameters[spec.name] = (
                str(self._select(widget_id)) if spec.choices else self._input(widget_id)
            )
        return FormValues(
            name=self._input("name").strip(),
            track=str(self._select("track")),
            sensor=str(self._select("sensor")),
            action_kind=str(self._select("action-kind")),
            max_steering=self._input("max-steering"),
            steering_levels=int(str(self._select("steering-levels"))),
            max_speed=self._input("max-speed"),
            speed_levels=int(str(self._select("speed-levels"))),
            steering_low=self._input("steering-low"),
            steering_high=self._input("steering-high"),
            speed_low=self._input("speed-low"),
            speed_high=self._input("speed-high"),
            max_minutes=self._input("max-minutes"),
            reward_source=self.query_one("#reward", TextArea).text,
            hyperparameters=hyperparameters,
            race_type=str(self._select("race-type")),
            race_objects=self._input("race-objects"),
            bot_speed=self._input("bot-speed"),
            race_shuffle=self._select("race-shuffle") is True,
            camera_randomisation=self._input("camera-randomisation"),
        )

    # --- live feedback ------------------------------------------------------------------------

    def _show_kind(self) -> None:
        kind = self._select("action-kind")
        self.query_one("#discrete-fields").display = kind == DISCRETE
        self.query_one("#continuous-fields").display = kind == CONTINUOUS

    def _refresh_actions(self) -> None:
        """Redraw the action space after the current burst of changes (mounting the form
        sends a Changed event per field)."""
        if not self._actions_pending:
            self._actions_pending = True
            self.call_after_refresh(self._redraw_actions)

    def _redraw_actions(self) -> None:
        self._actions_pending = False
        for field_id in ACTION_FIELDS:
            self._set_problem(field_id, "")
        try:
            space = action_space_of(self.values(), self.kept)
        except FormError as error:
            for problem in error.problems:
                self._set_problem(problem.field, problem.message)
            return
        self.query_one("#action-plot", ActionSpacePlot).space = space
        rows: list[tuple[str, ...]]
        if space.kind == CONTINUOUS:
            (steer_low, steer_high), (speed_low, speed_high) = (
                space.steering_range,
                space.speed_range,
            )
            rows = [("-", f"{steer_low:g}..{steer_high:g}", f"{speed_low:g}..{speed_high:g}", "")]
        else:
            rows = []
            for index, action in enumerate(space.actions):
                steer = action.steering_angle
                turn = "left" if steer > 0 else "right" if steer < 0 else "straight"
                rows.append((str(index), f"{steer:g}", f"{round(action.speed, 2):g}", turn))
        fill_table(self.query_one("#action-table", DataTable), ACTION_COLUMNS, rows)

    def _show_race(self) -> None:
        """A race type's own fields, shown only for it: none for a time trial, no speed for
        boxes."""
        race = self._select("race-type")
        self.query_one("#race-fields").display = race != "time-trial"
        self.query_one("#bot-speed-field").display = race == "head-to-bot"

    def _show_camera_randomisation(self) -> None:
        """Camera randomisation is a camera model's: hidden for any other sensor."""
        sensor = str(self._select("sensor"))
        self.query_one("#camera-randomisation-field").display = "camera" in sensor.split("+")

    @on(Select.Changed, "#sensor")
    def _sensor_changed(self) -> None:
        self.query_one("#sensor-hint", Static).update(sensor_hint(str(self._select("sensor"))))
        self._show_camera_randomisation()
        self._set_problem("camera-randomisation", "")
        if "camera" not in str(self._select("sensor")).split("+"):
            # Hidden now: a setting left in it would refuse the save from out of sight.
            self.query_one("#camera-randomisation", Input).value = "off"

    @on(Select.Changed, "#race-type")
    def _race_changed(self) -> None:
        self._show_race()
        for field_id in ("race-objects", "bot-speed", "sensor"):
            self._set_problem(field_id, "")

    @on(Select.Changed, "#action-kind")
    def _kind_changed(self) -> None:
        self._show_kind()
        self._refresh_actions()

    @on(Select.Changed, "#steering-levels, #speed-levels")
    def _levels_changed(self) -> None:
        self._refresh_actions()

    @on(Input.Changed)
    def _input_changed(self, event: Input.Changed) -> None:
        field_id = str(event.input.id)
        if field_id in ACTION_FIELDS:
            self._refresh_actions()
        elif field_id.startswith("hp-") or field_id in (
            "max-minutes",
            "name",
            "race-objects",
            "bot-speed",
            "camera-randomisation",
        ):
            self._set_problem(field_id, "")

    @on(TextArea.Changed, "#reward")
    def _reward_changed(self) -> None:
        self._set_problem("reward", "")
        self._outdate_map()

    @on(Select.Changed, "#track")
    def _track_changed(self, event: Select.Changed) -> None:
        if isinstance(event.value, str):
            self._load_preview(event.value)
            self._outdate_map()

    def _outdate_map(self) -> None:
        """A map of what the function paid is of the code and track it was made for: once
        either changes it is taken down, not left to speak for the new ones."""
        if self.last_check is not None:
            self.last_check = None
            self.query_one("#reward-map", Static).update(OUTDATED_MAP)

    @work(thread=True, exclusive=True, group="editor-preview", exit_on_error=False)
    def _load_preview(self, name: str) -> None:
        try:
            self.post_message(TrackPreviewLoaded(resolve_track(name)))
        except TrackError as error:
            self.post_message(FormRejected((FieldProblem("track", field_message(error)),)))

    def on_track_preview_loaded(self, message: TrackPreviewLoaded) -> None:
        self.query_one("#track-preview", TrackMap).track = message.track

    def _widget(self, widget_id: str) -> Widget | None:
        """A form widget by id, from a map built once (a DOM query per keystroke is slow)."""
        if not self._by_id:
            self._by_id = {str(w.id): w for w in self.query("*") if w.id is not None}
        return self._by_id.get(widget_id)

    def _set_problem(self, field_id: str, message: str) -> None:
        problem = self._widget(f"{field_id}-problem")
        if isinstance(problem, Static):
            if message or problem.has_class("-shown"):
                problem.update(Text(message))
            problem.set_class(bool(message), "-shown")
        widget = self._widget(field_id)
        if widget is not None:
            widget.set_class(bool(message), "-problem")

    # --- reward function -----------------------------------------------------------------------

    @on(Select.Changed, "#reward-template")
    def _template_chosen(self, event: Select.Changed) -> None:
        if not isinstance(event.value, str):
            return  # cleared back to its prompt
        name = event.value
        event.select.clear()
        values = self.values()
        try:
            space: ActionSpace | None = action_space_of(values, self.kept)
        except FormError:
            space = None  # fields being typed: the line for any action
        self._write_template(name, values.track or None, space)

    @work(thread=True, exclusive=True, group="editor-template", exit_on_error=False)
    def _write_template(self, name: str, track: str | None, space: ActionSpace | None) -> None:
        """The template's text, off the screen's thread: racing_line's holds the limit lap's
        line of the form's track, which takes a second or two to work out the first time."""
        source = template_source(name, track, space)
        self.app.call_from_thread(self._offer_template, name, source)

    def _offer_template(self, name: str, source: str) -> None:
        editor = self.query_one("#reward", TextArea)
        if editor.text == source:
            return
        if editor.text.strip() and template_name(editor.text) is None:
            ask(
                self.app,
                "Replace the reward function?",
                f"The editor holds your own reward function; loading the {name} template "
                "replaces it.",
                lambda yes: self._load_template(source) if yes else None,
                confirm_label="Replace",
            )
            return
        self._load_template(source)

    def _load_template(self, source: str) -> None:
        self.query_one("#reward", TextArea).load_text(source)
        self._set_problem("reward", "")

    def action_check_reward(self) -> None:
        self.query_one(TabbedContent).active = "tab-reward"
        self._show_reward_result(Text("Checking…", style="dim"))
        track, speed = self._map_setting()
        self._checks += 1
        self._check_reward(self.query_one("#reward", TextArea).text, track, speed, self._checks)

    @on(Button.Pressed, "#check-reward")
    def _check_pressed(self) -> None:
        self.action_check_reward()

    @work(thread=True, exclusive=True, group="editor-reward", exit_on_error=False)
    def _check_reward(self, source: str, track: str | None, top_speed: float, number: int) -> None:
        checked = check_reward(source, track, top_speed)
        checked.number = number
        self.post_message(checked)

    def _map_setting(self) -> tuple[str | None, float]:
        """The model's track and top speed as the form holds them (2 m/s if unreadable)."""
        values = self.values()
        try:
            speed = float(
                values.max_speed if values.action_kind != "CONTINUOUS" else values.speed_high
            )
        except ValueError:
            speed = 2.0
        speed = min(max(speed, 0.1), 4.0) if math.isfinite(speed) else 2.0
        return (values.track or None), speed

    def on_reward_checked(self, message: RewardChecked) -> None:
        if message.number != self._checks:
            return  # an earlier Check that finished late: the newer one's answer stands
        self.last_check = message
        editor = self.query_one("#reward", TextArea)
        shown_map = self.query_one("#reward-map", Static)
        if message.error is None:
            text = Text("✓ ", style="bold green")
            text.append(f"reward {message.value:.4g} on the sample params ")
            text.append("(a car on a straight at 2 m/s, near the centre line)", style="dim")
            if message.laps:
                text.append(f"\n{verdict(list(message.laps))}")
            if message.droa is not None:
                text.append("\n")
                text.append_text(droa_words(message.droa))
            self._show_reward_result(text)
            editor.set_class(False, "-problem")
            if message.reward_map is not None:
                width = max(20, shown_map.size.width or 40)
                previewed = self.query_one("#track-preview", TrackMap).track
                on = previewed if previewed and previewed.name == message.reward_map.track else None
                shown_map.update(map_text(message.reward_map, width, track=on))
            else:
                shown_map.update(Text("no map: choose a track on the Car tab", style="dim"))
            return
        shown_map.update(Text("no map: the function failed", style="dim"))
        self._show_reward_result(Text(f"✗ {message.error}", style="bold red"))
        editor.set_class(True, "-problem")
        if message.error.line is not None:
            editor.cursor_location = (message.error.line - 1, 0)
            editor.focus()

    def _show_reward_result(self, text: Text) -> None:
        result = self.query_one("#reward-problem", Static)
        result.update(text)
        result.set_class(bool(text.plain), "-shown")

    # --- saving --------------------------------------------------------------------------------

    def action_tab(self, tab: str) -> None:
        self.query_one(TabbedContent).active = tab
        # At once, before the hidden pane's focus moves on inside that pane (which would
        # switch the tabs back): keys then go to the pane the racer asked for.
        self._focus_first_in(self.query_one(f"#{tab}", TabPane))

    def _focus_first_in(self, pane: TabPane) -> None:
        focused = self.app.focused
        if focused is not None and pane in focused.ancestors:
            return
        # A form field, not the scrolling container around the fields.
        fields = [
            widget
            for widget in pane.query("*")
            if widget.focusable and not isinstance(widget, ScrollableContainer)
        ]
        if fields:
            fields[0].focus()

    def action_save(self) -> None:
        if self.saving:
            return
        self.saving = True
        for field_id in ("name", "track", "sensor", "max-minutes", "reward", *ACTION_FIELDS):
            self._set_problem(field_id, "")
        for spec in TUNABLE:
            self._set_problem(f"hp-{spec.name}", "")
        self._save(self.values())

    @work(thread=True, exclusive=True, group="editor-save", exit_on_error=False)
    def _save(self, values: FormValues) -> None:
        try:
            try:
                taken = taken_names() if self.folder is None else None
                spec = spec_of_form(values, base=self.base, new_name_taken=taken, kept=self.kept)
            except FormError as error:
                self.post_message(FormRejected(error.problems))
                return
            if self.folder is None:
                folder = create_from_form(values.name, spec)
                self.post_message(ModelSaved(folder.name, created=True))
            else:
                save_edit(self.folder, spec)
                self.post_message(ModelSaved(self.folder.name, created=False))
        finally:
            self.saving = False

    def on_form_rejected(self, message: FormRejected) -> None:
        for problem in message.problems:
            self._set_problem(problem.field, in_app_words(problem.message))
        first = message.problems[0]
        self.query_one(TabbedContent).active = tab_of(first.field)
        widgets = self.query(f"#{first.field}")
        if widgets and widgets.first().focusable:
            widgets.first().focus()
        count = len(message.problems)
        more = f" (and {count - 1} more)" if count > 1 else ""
        said = in_app_words(first.message)
        self.notify(f"Not saved: {said}{more}", severity="error", timeout=8, markup=False)

    def on_model_saved(self, message: ModelSaved) -> None:
        verb = "Created" if message.created else "Saved"
        self.notify(f"{verb} {message.name}.")
        self.dismiss(message.name)

    def action_cancel(self) -> None:
        if self.initial is not None and self.values() != self.initial:
            ask(
                self.app,
                "Discard your changes?",
                "The form has changes that are not saved.",
                self._discard_confirmed,
                confirm_label="Discard",
            )
            return
        self.dismiss(None)

    def _discard_confirmed(self, yes: bool | None) -> None:
        if yes:
            self.dismiss(None)
