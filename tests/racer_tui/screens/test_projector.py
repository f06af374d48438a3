"""The League's projector table: a board's name is never cut so that two boards look like
one (a physical car's board beside the simulated one), and names keep their room."""

from __future__ import annotations

import pytest
from rich.console import Console

from league.leaderboard import LeaderboardRow
from racer_tui.app.screens.projector import projector_table


def _row(racer: str, board: str, physics: str, score: float) -> LeaderboardRow:
    return LeaderboardRow(
        record_id=f"id-{racer}",
        kind="race",
        racer=racer,
        display_name=racer,
        model="m",
        track_hash="h",
        track_name=board,
        night_id=None,
        score=score,
        scoring_offtracks=0,
        valid_laps=3,
        recorded_at="2026-11-29T20:00:00+00:00",
        best_lap=score,
        average_lap=score,
        offtracks=0,
        laps_driven=3,
        physics=physics,
        race_type="time_trial",
        rank=1,
    )


@pytest.mark.parametrize("width", [60, 80, 120])
def test_a_physical_board_keeps_its_name_on_the_projector(width: int) -> None:
    rows = [
        _row("carolina", "reinvent_base (physical)", "physical", 6.2),
        _row("bo", "reinvent_base", "pymunk-1", 2.508),
    ]
    console = Console(width=width, record=True, color_system=None)
    console.print(projector_table(rows, show_track=True, narrow=width < 70))
    shown = console.export_text()
    assert "(physical)" in shown and "reinvent_base" in shown, shown
    assert "carolina" in shown, shown
    assert "…" not in shown, shown
