"""The leaderboard's row detail: what one entry is made of.

A submission is summarised from its five source files as the league stored them (model
metadata: action space and sensor; hyperparameters; training: time and episodes;
evaluation: trials and laps); a race by its laps. The league reads them
(league.entries.entry_breakdown, in a worker); `render_entry` turns them into text and
`EntryDetail` only shows it. Every stored value is user data, so it goes into `Text` as
plain text, never markup.
"""

from __future__ import annotations

from typing import Any

from rich.text import Text
from textual.widgets import Static

from league.entries import EntryBreakdown, SubmissionFiles, entry_breakdown
from league.leaderboard import LeaderboardRow
from league.store import League
from sim.foundation.plural import counted

# The hyperparameters a racer tunes most, in the console's order; the rest follow.
MAIN_HYPERPARAMETERS = (
    "batch_size",
    "lr",
    "discount_factor",
    "beta_entropy",
    "num_epochs",
    "num_episodes_between_training",
    "loss_type",
)


def _seconds(value: float | None) -> str:
    return "-" if value is None else f"{value:.3f} s"


def _heading(text: Text, title: str) -> None:
    text.append(f"\n{title}\n", style="bold")


def _line(text: Text, label: str, value: str) -> None:
    text.append(f"  {label}: ", style="dim")
    text.append(value + "\n")


def _action_space(summary: Any) -> str:
    if not isinstance(summary, dict):
        return "not in the files"
    speed = summary.get("speed") or ["?", "?"]
    steering = summary.get("steering") or ["?", "?"]
    ranges = f"speed {speed[0]}..{speed[1]} m/s, steering {steering[0]}..{steering[1]}°"
    if summary.get("type") == "discrete":
        return f"discrete, {summary.get('actions', '?')} actions, {ranges}"
    return f"continuous, {ranges}"


def _submission(files: SubmissionFiles, text: Text) -> None:
    _heading(text, "Model metadata")
    _line(text, "action space", _action_space(files.action_space))
    _line(text, "sensor", ", ".join(map(str, files.sensors)) if files.sensors else "-")
    _line(text, "network", files.neural_network or "-")
    _line(text, "algorithm", files.training_algorithm or "-")

    _heading(text, "Hyperparameters")
    hyper = files.hyperparameters
    if hyper:
        keys = [key for key in MAIN_HYPERPARAMETERS if key in hyper]
        keys += sorted(key for key in hyper if key not in MAIN_HYPERPARAMETERS)
        text.append("  " + ", ".join(f"{key} {hyper[key]}" for key in keys) + "\n")
    else:
        text.append("  not in the files\n", style="dim")

    _heading(text, "Training")
    training = files.training
    if training:
        if "minutes" in training:
            _line(text, "time", f"{training['minutes']} min")
        if "episodes" in training:
            _line(text, "episodes", str(training["episodes"]))
        if "best_completion" in training:
            _line(text, "best progress", f"{training['best_completion']:g}%")
        if "world_name" in training:
            _line(text, "trained on", str(training["world_name"]))
    else:
        text.append("  not in the files\n", style="dim")

    trials = files.trials
    completed = sum(1 for trial in trials if trial.completed)
    _heading(text, "Evaluation")
    _line(text, "file", files.evaluation_file)
    _line(text, "trials", f"{len(trials)}, {counted(completed, 'lap')} completed")
    for trial in trials:
        time = _seconds(trial.time_seconds) if trial.completed else f"{trial.completion:g}%"
        text.append(f"  trial {trial.number:>2}  {time:>10}  off {trial.offtracks}  ")
        text.append(trial.status + "\n", style="green" if trial.completed else "yellow")


def _race(breakdown: EntryBreakdown, text: Text) -> None:
    laps = breakdown.race_laps
    _heading(text, f"Laps ({len(laps)})")
    if not laps:
        text.append("  no lap completed\n", style="dim")
    for lap in laps:
        text.append(f"  lap {lap.number:>2}  {_seconds(lap.time_seconds):>10}")
        text.append(f"  pen {lap.penalty_seconds:g}  off {lap.offtracks}  ")
        text.append("✓\n" if lap.valid else "✗ too many off-tracks\n")


# What each standing here (league.trust.standing) means, in the detail of a row.
STANDING_WORDS: dict[str, str] = {
    "replayed": "replayed here: re-run from its model, its laps came out the same",
    "verifiable": "verifiable: its model is here, not replayed yet (racer-tui sync verify)",
    "unverifiable": "unverifiable here: nothing here can re-run it (no model, a DeepRacer "
    "evaluation, or laps timed by hand)",
}


def render_entry(row: LeaderboardRow, breakdown: EntryBreakdown) -> Text:
    """The detail text of one leaderboard row from what the league says it is made of."""
    text = Text()
    text.append(row.display_name, style="bold")
    text.append(f"  {row.model}\n")
    text.append(f"{row.track_name} · {row.kind} · {row.recorded_at[:16].replace('T', ' ')}\n")
    text.append(
        f"best {_seconds(row.best_lap)} · average {_seconds(row.average_lap)} · "
        f"{counted(row.valid_laps, 'lap')} · {counted(row.offtracks, 'off-track')}\n",
        style="dim",
    )
    standing = STANDING_WORDS.get(row.verification)
    if standing is not None:
        text.append(f"{standing}\n", style="dim")
    if row.runtime:  # its policy's numerics (sim.training.runtimes)
        text.append(f"policy runtime {row.runtime}\n", style="dim")
    if breakdown.has_trace:
        text.append("v replays this race\n", style="italic")
    if not breakdown.found:
        text.append(f"\nThis {row.kind} is no longer in the league.\n", style="yellow")
    elif breakdown.submission is not None:
        _submission(breakdown.submission, text)
    else:
        _race(breakdown, text)
    return text


def describe_entry(league: League, row: LeaderboardRow) -> Text:
    """The detail of one leaderboard row (reads the database: call it in a worker)."""
    return render_entry(row, entry_breakdown(league, row.kind, row.record_id))


class EntryDetail(Static):
    """Shows the text `describe_entry` built, or a message."""

    DEFAULT_CSS = """
    EntryDetail { padding: 0 1; height: auto; }
    """

    def show_message(self, message: str) -> None:
        self.update(Text(message, style="dim"))
