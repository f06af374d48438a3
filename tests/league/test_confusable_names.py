"""Racer names are compared as Unicode's confusable detection compares them (the UTS #39
skeleton, case folded): a look-alike of an existing racer in any script is refused with
the name it looks like, and names a reader can tell apart stay allowed."""

from __future__ import annotations

import pytest

from league.errors import LeagueError
from league.racers import add_racer, ensure_racer
from league.store import League
from sim.foundation.plain_names import look_alike_key

ARMENIAN_VO = "\u0578"  # ո, drawn as n
GREEK_ETA = "\u03b7"  # η, drawn as n with a longer right leg
CYRILLIC_A = "\u0430"  # а


@pytest.mark.parametrize(
    "poser",
    [
        f"{CYRILLIC_A}{ARMENIAN_VO}{CYRILLIC_A}",  # the "аոа"
        f"{CYRILLIC_A}{GREEK_ETA}{CYRILLIC_A}",  # the "аηа"
        f"a{ARMENIAN_VO}a",
    ],
)
def test_a_look_alike_of_ana_in_another_script_is_refused(league: League, poser: str) -> None:
    add_racer(league, "ana")
    assert look_alike_key(poser) == look_alike_key("ana")
    with pytest.raises(LeagueError, match="looks like the racer 'ana'"), league.transaction():
        ensure_racer(league, poser)
    with pytest.raises(LeagueError, match="looks like the racer 'ana'"):
        add_racer(league, poser)


@pytest.mark.parametrize(
    ("first", "second"),
    [
        ("ana", "anna"),
        ("ana", "ann"),
        ("José", "Jose"),
        ("Zoë", "Zoe"),
        ("Анна", "Ана"),  # Cyrillic names of their own
        ("李娜", "李明"),
        ("ana", "ana 2"),
    ],
)
def test_names_a_reader_can_tell_apart_are_two_racers(
    league: League, first: str, second: str
) -> None:
    add_racer(league, first)
    assert add_racer(league, second).name == second


def test_digits_and_capitals_that_pose_as_letters_are_caught(league: League) -> None:
    assert look_alike_key("b0b") == look_alike_key("bob")
    assert look_alike_key("Ian") == look_alike_key("lan") == look_alike_key("1an")
    add_racer(league, "aha")
    with pytest.raises(LeagueError, match="looks like the racer 'aha'"):
        add_racer(league, f"A{GREEK_ETA.upper()}A")  # Greek capital eta is an H
