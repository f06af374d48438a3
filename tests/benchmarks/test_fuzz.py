"""The fuzz script, at a small scale: every family of untrusted input is tried, nothing
ends in a traceback, nothing is executed, and the league it pulled into stays whole."""

from __future__ import annotations

import json

import pytest

from benchmarks.league.fuzz import FAMILIES, main


def test_fuzzed_inputs_are_refused_cleanly_and_leave_the_league_whole(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["--cases", "250", "--seed", "7", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["tracebacks"] == 0, report["families"]
    assert report["executed"] is False
    assert report["integrity_check"] == "ok"
    assert report["rows_not_matching_their_hash"] == 0
    assert report["quarantine_texts_with_control_characters"] == 0
    for family in FAMILIES:
        tally = report["families"][family]
        assert tally["cases"] == 50
        assert tally["refused"] > 0  # each family's mutations do reach its checks
