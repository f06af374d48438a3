"""Issue 42, point 13: `tracks list` names its second column for what it holds: the
console's name for AWS's tracks, a description for racer-tui's own and imported ones."""

from __future__ import annotations

import pytest

from tests.racer_tui.test_cli import run_cli


def test_built_in_tracks_have_a_description_column_not_a_console_name(
    capsys: pytest.CaptureFixture[str],
) -> None:
    code, out, _ = run_cli(capsys, "tracks", "list")
    assert code == 0
    built_in, official = out.split("Official:", 1)
    assert "description" in built_in and "console name" not in built_in
    assert "console name" in official
