"""A bracket's rounds as racers name them, in the one form every screen draws them: the
app's bracket view, the night's projector, the web's night page and the night's JSON.

A single elimination counts back from its end (Final, Semi-finals, Quarter-finals, then
"Round 1" and so on); a double elimination has winners' and losers' rounds, then its
grand final, and its deciding race only once it is needed (the losers' bracket's winner
took the grand final) or raced: before that it would read as a match still to come.
"""

from __future__ import annotations

from dataclasses import dataclass

from league.bracket_records import NightBracket
from league.brackets import DECIDER, GRAND_FINAL, Format, Match

# Winners' rounds from the last one back, in a single elimination.
ROUNDS_FROM_THE_END = ("Final", "Semi-finals", "Quarter-finals")


@dataclass(frozen=True)
class BracketRound:
    title: str  # "Semi-finals", "Losers' round 2", "Grand final"
    part: str  # the bracket its matches are in: "winners", "losers" or "final"
    matches: tuple[Match, ...]


def round_title(match: Match, rounds: int, form: Format) -> str:
    """What `match`'s round is called; `rounds`: how many winners' rounds the bracket has."""
    if match.bracket == "final":
        return "Grand final" if match.id == GRAND_FINAL else "Deciding race"
    if match.bracket == "losers":
        return f"Losers' round {match.round}"
    if form is Format.DOUBLE:
        return f"Winners' round {match.round}"
    from_the_end = rounds - match.round
    if from_the_end < len(ROUNDS_FROM_THE_END):
        return ROUNDS_FROM_THE_END[from_the_end]
    return f"Round {match.round}"


def match_title(drawn: NightBracket, match: Match) -> str:
    """What the round of one of `drawn`'s matches is called."""
    rounds = max((m.round for m in drawn.bracket.matches if m.bracket == "winners"), default=1)
    return round_title(match, rounds, drawn.bracket.format)


def bracket_rounds(drawn: NightBracket) -> list[BracketRound]:
    """The rounds to draw as the bracket stands, in the order they are raced: the winners'
    rounds, a double elimination's losers' rounds, then its finals."""
    matches = drawn.bracket.matches
    rounds = max((m.round for m in matches if m.bracket == "winners"), default=1)
    grouped: dict[str, list[Match]] = {}
    for match in matches:
        if _shown(drawn, match):
            grouped.setdefault(round_title(match, rounds, drawn.bracket.format), []).append(match)
    return [BracketRound(title, found[0].bracket, tuple(found)) for title, found in grouped.items()]


def _shown(drawn: NightBracket, match: Match) -> bool:
    if match.id != DECIDER:
        return True
    return match in drawn.bracket.ready(drawn.winners) or match.id in drawn.winners
