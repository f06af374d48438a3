"""Racers' names are plain text a person can tell apart: no invisible or direction-changing
characters, one spelling for look-alike letters, and no name that poses as another."""

from __future__ import annotations

import pytest

from league.errors import LeagueError
from league.racers import add_racer, check_name, ensure_racer
from league.store import League
from sim.foundation.plain_names import is_plain_name, look_alike_key
from sim.race.result import RaceResult, ResultError
from tests.league.helpers import race_result

RIGHT_TO_LEFT_OVERRIDE = "\u202e"
ZERO_WIDTH_SPACE = "\u200b"


def test_names_are_kept_in_one_compatible_form() -> None:
    assert check_name("  Ａｄａ  ") == "Ada"  # full-width letters are the plain ones
    assert check_name("ﬁona") == "fiona"  # a ligature is its letters


@pytest.mark.parametrize(
    "name",
    [
        f"ada{RIGHT_TO_LEFT_OVERRIDE}reb",  # shows as "adaber"
        f"a{ZERO_WIDTH_SPACE}da",  # shows as "ada"
        "ada\u2066",  # a bidirectional isolate
        "ada\x1b[31m",  # a terminal escape sequence
        "two\nlines",
    ],
)
def test_invisible_and_direction_changing_characters_are_refused(name: str) -> None:
    with pytest.raises(LeagueError, match="invisible characters"):
        check_name(name)
    assert not is_plain_name(name)


def test_an_emoji_joined_from_two_stays_allowed() -> None:
    assert check_name("Ana 👩\u200d💻") == "Ana 👩\u200d💻"
    assert not is_plain_name("a\u200db")  # but not between letters, where it hides


def test_a_look_alike_of_an_existing_racer_is_refused(league: League) -> None:
    add_racer(league, "ada")
    for poser in ("аda", "adа", "ΑDA"):  # Cyrillic а, Greek Α
        assert look_alike_key(poser) == look_alike_key("ada")
        with pytest.raises(LeagueError, match="looks like the racer 'ada'"), league.transaction():
            ensure_racer(league, poser)
    with league.transaction():
        assert ensure_racer(league, "ADA") == "ada"  # the same racer, any case
        assert ensure_racer(league, "adam") == "adam"  # a different name is fine


def test_a_pulled_result_whose_racer_hides_characters_is_not_read() -> None:
    result = race_result("bob", [12.0])
    data = result.to_json()
    data["racer"] = f"bob{RIGHT_TO_LEFT_OVERRIDE}"
    with pytest.raises(ResultError, match="invisible characters"):
        RaceResult.from_json(data)


def test_capital_i_of_any_script_and_blank_letters_are_caught() -> None:
    assert look_alike_key("Іan") == look_alike_key("Ian") == look_alike_key("lan")
    for hidden in ("ada\u034f", "ada\ufe0f", "\u3164ada", "ada\u2800"):
        assert not is_plain_name(hidden), repr(hidden)
    assert is_plain_name("❤️ ada")  # an emoji's own presentation selector stays
