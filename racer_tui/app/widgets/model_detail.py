"""The garage's detail panel: everything about the highlighted model, in one scroll.

It draws `sim.garage.overview.model_details(folder)` (the same facts `racer-tui model show`
prints), so the wording of a model's state lives in the garage library. Every value that
comes from a file is put in a `Text` as plain text, never parsed as markup.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from rich.console import Group, RenderableType
from rich.table import Table
from rich.text import Text
from textual.app import ComposeResult
from textual.containers import Horizontal, VerticalScroll
from textual.widgets import Static

from racer_tui.app.widgets.action_space_plot import ActionSpacePlot
from racer_tui.app.words import said_in_app
from sim.deepracer.action_space import ActionSpace
from sim.deepracer.files import HYPERPARAMETER_SPECS
from sim.foundation.remedies import fix_named
from sim.garage.overview import network_words

STATUS_STYLES = {
    "untrained": "dim",
    "training": "bold yellow",
    "trained": "green",
    "evaluated": "bold green",
    "damaged": "bold red",
}


def seconds_text(value: float | None) -> str:
    if value is None:
        return "-"
    minutes, seconds = divmod(value, 60.0)
    return f"{int(minutes)}:{seconds:06.3f}" if minutes else f"{seconds:.3f} s"


def status_text(status: str) -> Text:
    return Text(status, style=STATUS_STYLES.get(status, ""))


def _facts_table() -> Table:
    table = Table.grid(padding=(0, 2))
    table.add_column(style="dim", no_wrap=True)
    table.add_column()
    return table


def _plain(value: object) -> Text:
    return Text("-" if value is None else str(value))


class ModelDetail(VerticalScroll):
    """Shows one model's details, or a one-line message when there is no model to show."""

    DEFAULT_CSS = """
    ModelDetail { padding: 0 1; }
    ModelDetail > .detail-heading { margin-top: 1; text-style: bold; color: $accent; }
    ModelDetail > #detail-title { text-style: bold; }
    ModelDetail > #detail-actions { height: auto; }
    ModelDetail #detail-plot { width: 1fr; max-width: 48; }
    ModelDetail #detail-action-table { width: auto; padding-left: 2; }
    """

    def compose(self) -> ComposeResult:
        yield Static(id="detail-title")
        yield Static(id="detail-facts")
        yield Static("Action space", classes="detail-heading")
        with Horizontal(id="detail-actions"):
            yield ActionSpacePlot(id="detail-plot")
            yield Static(id="detail-action-table")
        yield Static("Hyperparameters", classes="detail-heading")
        yield Static(id="detail-hyperparameters")
        yield Static("Training", classes="detail-heading")
        yield Static(id="detail-training")
        yield Static("Evaluations", classes="detail-heading")
        yield Static(id="detail-evaluations")

    def on_mount(self) -> None:
        self.show_message("No model highlighted.")

    _shown: tuple[dict[str, Any], ActionSpace] | None = None  # the details on screen

    def show_message(self, message: str) -> None:
        """A sentence instead of details (no models yet, a damaged folder...)."""
        self._shown = None
        self._set_sections_visible(False)
        self.query_one("#detail-title", Static).update(Text(message))
        self.query_one("#detail-facts", Static).update("")

    def _set_sections_visible(self, visible: bool) -> None:
        for widget in self.children:
            if widget.id not in ("detail-title", "detail-facts"):
                widget.display = visible

    def show_details(self, details: Mapping[str, Any], space: ActionSpace) -> None:
        """A model's details; the Garage reloads them each time it is shown, and details
        that are already on screen are not drawn again."""
        shown = (dict(details), space)
        if shown == self._shown:
            return
        self._shown = shown
        self._set_sections_visible(True)
        title = Text(str(details["name"]), style="bold")
        title.append("  ")
        title.append_text(status_text(str(details["status"])))
        self.query_one("#detail-title", Static).update(title)
        self.query_one("#detail-facts", Static).update(self._facts(details))
        self.query_one("#detail-plot", ActionSpacePlot).space = space
        self.query_one("#detail-action-table", Static).update(self._action_table(details))
        self.query_one("#detail-hyperparameters", Static).update(
            self._hyperparameters(details["hyperparameters"])
        )
        self.query_one("#detail-training", Static).update(self._training(details["training"]))
        self.query_one("#detail-evaluations", Static).update(
            self._evaluations(details["evaluations"])
        )

    @staticmethod
    def _facts(details: Mapping[str, Any]) -> Table:
        table = _facts_table()
        metadata = details["metadata"]
        table.add_row("track", _plain(details["track"]))
        table.add_row("sensor", _plain(details["sensor"]))
        table.add_row("actions", _plain(details["actions_summary"]))
        if details.get("car_archive"):
            # Its weights are a DeepRacer graph: no reward function or training applies.
            table.add_row("drives with", _plain("a DeepRacer car archive, never trained here"))
        else:
            table.add_row("reward function", _plain(details["reward_function"]))
            table.add_row(
                "training",
                _plain(f"{metadata['training_algorithm']}, at most {details['max_minutes']:g} min"),
            )
        if details.get("car_look"):
            table.add_row("car", _plain(details["car_look"]))
        table.add_row("network", _plain(network_words(metadata)))
        table.add_row("car hash", _plain(str(details["content_hash"])[:16]))
        table.add_row("folder", _plain(details["path"]))
        for key, value in details["notes"].items():
            table.add_row(Text(key.lower().replace("_", " ")), _plain(value))
        if details.get("physics_note"):
            table.add_row(Text("physics", style="bold yellow"), _plain(details["physics_note"]))
        return table

    @staticmethod
    def _action_table(details: Mapping[str, Any]) -> RenderableType:
        actions = details["actions"]
        if not actions:
            space = details["metadata"]["action_space"]
            steer, speed = space["steering_angle"], space["speed"]
            return Text(
                f"continuous\nsteering {steer['low']:g}..{steer['high']:g}°\n"
                f"speed {speed['low']:g}..{speed['high']:g} m/s"
            )
        table = Table(box=None, padding=(0, 1), show_edge=False, header_style="dim")
        table.add_column("#", justify="right")
        table.add_column("steer°", justify="right")
        table.add_column("m/s", justify="right")
        for row in actions:
            table.add_row(
                str(row["index"]), f"{row['steering_angle']:g}", f"{round(row['speed'], 2):g}"
            )
        return table

    @staticmethod
    def _hyperparameters(values: Mapping[str, Any]) -> Table:
        table = _facts_table()
        for name, value in values.items():
            spec = HYPERPARAMETER_SPECS.get(name)
            if spec is not None and spec.tunable:
                table.add_row(Text(name), _plain(value))
        return table

    @staticmethod
    def _training(summary: Mapping[str, Any]) -> RenderableType:
        if not summary.get("episodes") and summary.get("state") is None:
            return Text("Not trained yet.", style="dim")
        table = _facts_table()
        table.add_row("episodes", _plain(summary.get("episodes")))
        table.add_row("laps completed", _plain(summary.get("laps_completed")))
        best = summary.get("best_progress")
        table.add_row("best progress", _plain(f"{best:.1f} %" if best is not None else None))
        recent = summary.get("recent_progress")
        if recent is not None:
            table.add_row("recent progress", _plain(f"{recent:.1f} %"))
        table.add_row("time trained", _plain(seconds_text(summary.get("training_seconds"))))
        if summary.get("steps") is not None:
            table.add_row("steps", _plain(summary["steps"]))
        if summary.get("numerics"):  # float32, or bfloat16 convolutions (model show's too)
            table.add_row("trained in", _plain(summary["numerics"]))
        if summary.get("state"):
            table.add_row("last run", _plain(summary["state"]))
        if summary.get("message"):
            problem, fix = summary.get("problem"), fix_named(summary.get("fix"))
            said = said_in_app(
                str(summary["message"]), problem if isinstance(problem, str) else "", fix
            )
            table.add_row("message", _plain(said))
        return table

    @staticmethod
    def _evaluations(evaluations: list[Mapping[str, Any]]) -> RenderableType:
        if not evaluations:
            return Text("Not evaluated yet.", style="dim")
        table = Table(box=None, padding=(0, 1), show_edge=False, header_style="dim")
        table.add_column("file")
        table.add_column("laps", justify="right")
        table.add_column("best", justify="right")
        for evaluation in evaluations[-5:]:
            if "problem" in evaluation:
                table.add_row(Text(evaluation["file"]), Text(evaluation["problem"], style="red"))
                continue
            name = Text(evaluation["file"])
            if evaluation.get("before_last_training"):
                name.append(" (before the last training)", style="yellow")
            table.add_row(
                name,
                f"{evaluation['laps_completed']}/{evaluation['trials_run']}",
                seconds_text(evaluation["best_lap_s"]),
            )
        latest = evaluations[-1]
        listed: RenderableType = table
        if latest.get("before_last_training"):
            retrained = Text(
                "The model trained after its latest evaluation: press v to evaluate it again.",
                style="yellow",
            )
            listed = Group(table, retrained)
        trials = Table(box=None, padding=(0, 1), show_edge=False, header_style="dim")
        for column in ("trial", "time", "% done", "status"):
            trials.add_column(column, justify="left" if column == "status" else "right")
        for trial in latest.get("trials", []):
            trials.add_row(
                str(trial.get("trial", "")),
                seconds_text(trial.get("elapsed_time_in_milliseconds", 0) / 1000.0),
                f"{trial.get('completion_percentage', 0):g}",
                Text(str(trial.get("episode_status", ""))),
            )
        return Group(listed, Text(""), Text("latest trials", style="dim"), trials)
