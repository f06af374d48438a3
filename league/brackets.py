"""Knock-out brackets for a head-to-head night: entrants seeded by qualifying race each
other two at a time, single or double elimination, as AWS's Virtual Circuit head-to-head
brackets ran after their qualifying.

- **Seeding:** the bracket's size is the next power of two. Seeds are placed so that the
  best two can meet only in the final, the best four only in the semi-finals, and so on
  (1 v 8, 4 v 5, 2 v 7, 3 v 6 for eight). Places beyond the entrants are byes: a seed
  drawn against a bye goes through without racing.
- **Single elimination:** the winner of each match goes on, the loser is out.
- **Double elimination:** a first loss drops the entrant into the losers' bracket, a second
  puts it out. Losers' rounds alternate between the losers' bracket's own winners racing
  each other and racing the losers dropping from the next winners' round (those drop in
  reverse order, so two entrants do not race again at once where it can be helped). The
  grand final is the winners' bracket winner against the losers' bracket winner; if the
  losers' bracket winner wins it, both have lost once and a deciding race follows.
- **The final order** (for a night's standings and season points): the champion, the
  last one beaten, then the others by how late they were knocked out; entrants knocked out
  in the same round are ordered by seed.

A bracket is a fixed plan of matches; what has happened is a mapping from match to winner.
Everything here is pure: the same seeds and results give the same bracket on every
machine.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from enum import Enum
from functools import cached_property

from league.errors import LeagueError

MIN_ENTRANTS = 2
MAX_ENTRANTS = 64


class Format(Enum):
    SINGLE = "single"
    DOUBLE = "double"


class BracketError(LeagueError):
    """A bracket that cannot be drawn, or a result that does not fit it."""


@dataclass(frozen=True)
class Source:
    """Where one side of a match comes from: a seed (1-based), or the winner or loser of
    an earlier match."""

    kind: str  # "seed", "winner" or "loser"
    seed: int = 0
    match: str = ""

    def __str__(self) -> str:
        return f"seed {self.seed}" if self.kind == "seed" else f"{self.kind} of {self.match}"


@dataclass(frozen=True)
class Match:
    id: str  # "W1-1": winners' round 1, match 1; "L2-1"; "GF"; "GF2" (the deciding race)
    bracket: str  # "winners", "losers" or "final"
    round: int
    a: Source
    b: Source


# Every match id a bracket draws (`Match.id`), and no other: what a recorded race may name.
MATCH_ID_PATTERN = re.compile(r"[WL][1-9][0-9]?-[1-9][0-9]{0,2}|GF2?")

BYE = ""  # a side with nobody: its other side goes through without racing


@dataclass(frozen=True)
class Bracket:
    format: Format
    seeds: tuple[str, ...]  # entrants, best seed first
    matches: tuple[Match, ...]  # in the order they can be raced

    @property
    def size(self) -> int:
        return _size(len(self.seeds))

    @cached_property
    def _by_id(self) -> dict[str, Match]:
        return {match.id: match for match in self.matches}

    def match(self, match_id: str) -> Match:
        match = self._by_id.get(match_id)
        if match is None:
            raise BracketError(f"there is no match {match_id!r} in this bracket.")
        return match

    # --- where things stand ---------------------------------------------------------------

    def sides(self, match: Match, winners: Mapping[str, str]) -> tuple[str | None, str | None]:
        """Who races `match` given the winners so far: an entrant, BYE, or None (not
        known yet)."""
        return self._side(match.a, winners), self._side(match.b, winners)

    def _side(self, source: Source, winners: Mapping[str, str]) -> str | None:
        if source.kind == "seed":
            return self.seeds[source.seed - 1] if source.seed <= len(self.seeds) else BYE
        earlier = self.match(source.match)
        outcome = self.outcome(earlier, winners)
        if outcome is None:
            return None
        winner, loser = outcome
        return winner if source.kind == "winner" else loser

    def outcome(self, match: Match, winners: Mapping[str, str]) -> tuple[str, str] | None:
        """(winner, loser) of `match` once decided: by a race, by a bye (the loser is BYE),
        or, for the deciding race, by not being needed (both BYE). None until then."""
        if match.id == DECIDER and not self._decider_needed(winners):
            return (BYE, BYE) if self._decider_known(winners) else None
        a, b = self.sides(match, winners)
        if a is None or b is None:
            return None
        if BYE in (a, b):
            return (b, a) if a == BYE else (a, b)
        winner = winners.get(match.id)
        if winner is None:
            return None
        if winner not in (a, b):
            raise BracketError(f"{winner} did not race in {match.id}: {a} and {b} did.")
        return (winner, b if winner == a else a)

    def _decider_known(self, winners: Mapping[str, str]) -> bool:
        final = self.match(GRAND_FINAL)
        return self.outcome(final, winners) is not None

    def _decider_needed(self, winners: Mapping[str, str]) -> bool:
        """The losers' bracket's winner won the grand final: both have lost once."""
        final = self.match(GRAND_FINAL)
        outcome = self.outcome(final, winners)
        if outcome is None:
            return False
        from_losers = self._side(final.b, winners)
        return outcome[0] == from_losers and from_losers != BYE

    def ready(self, winners: Mapping[str, str]) -> list[Match]:
        """The matches to race now: both sides known, neither a bye, no winner yet."""
        ready = []
        for match in self.matches:
            if match.id in winners:
                continue
            if match.id == DECIDER and not self._decider_needed(winners):
                continue
            a, b = self.sides(match, winners)
            if a and b:
                ready.append(match)
        return ready

    def check_result(self, match_id: str, winner: str, winners: Mapping[str, str]) -> None:
        """Raise BracketError unless `winner` can be recorded as the winner of
        `match_id` now."""
        match = self.match(match_id)
        if match_id in winners:
            raise BracketError(f"{match_id} already has a winner: {winners[match_id]}.")
        if match not in self.ready(winners):
            raise BracketError(f"{match_id} cannot be raced yet: who races in it is not known.")
        a, b = self.sides(match, winners)
        if winner not in (a, b):
            raise BracketError(f"{winner} does not race in {match_id}: {a} and {b} do.")

    def champion(self, winners: Mapping[str, str]) -> str | None:
        last = self.match(DECIDER) if self.format is Format.DOUBLE else self.matches[-1]
        if self.format is Format.DOUBLE:
            decider = self.outcome(last, winners)
            if decider is None:
                return None
            if decider[0] != BYE:
                return decider[0]
            final = self.outcome(self.match(GRAND_FINAL), winners)
            return None if final is None else final[0]
        outcome = self.outcome(last, winners)
        return None if outcome is None else outcome[0]

    def final_order(self, winners: Mapping[str, str]) -> list[str] | None:
        """Every entrant, champion first, once the bracket is decided (None before): the
        later an entrant was knocked out, the higher; the same round, by seed."""
        champion = self.champion(winners)
        if champion is None:
            return None
        out_at: dict[str, int] = {}  # entrant -> how late it was put out
        losses: dict[str, int] = {}
        needed = 2 if self.format is Format.DOUBLE else 1
        for match in self.matches:
            outcome = self.outcome(match, winners)
            assert outcome is not None  # decided brackets have every match decided
            loser = outcome[1]
            if loser == BYE:
                continue
            losses[loser] = losses.get(loser, 0) + 1
            if losses[loser] >= needed or match.bracket == "final":
                # One figure per round, the finals after every other round.
                out_at[loser] = match.round + (FINALS if match.bracket == "final" else 0)
        seed = {entrant: k for k, entrant in enumerate(self.seeds)}
        others = sorted(
            (entrant for entrant in self.seeds if entrant != champion),
            key=lambda entrant: (-out_at.get(entrant, -1), seed[entrant]),
        )
        return [champion, *others]


GRAND_FINAL = "GF"
DECIDER = "GF2"
FINALS = 1000  # above any round number: how late the grand final and decider come


def _size(entrants: int) -> int:
    size = 1
    while size < entrants:
        size *= 2
    return size


def seeding_order(size: int) -> list[int]:
    """Seeds in bracket order for a power-of-two size: neighbours race in round 1, and
    the best two are in opposite halves (1, 8, 4, 5, 2, 7, 3, 6 for eight)."""
    order = [1]
    while len(order) < size:
        span = 2 * len(order) + 1
        order = [seed for top in order for seed in (top, span - top)]
    return order


def _winners_rounds(size: int) -> list[list[Match]]:
    rounds: list[list[Match]] = []
    order = seeding_order(size)
    first = [
        Match(f"W1-{k + 1}", "winners", 1, Source("seed", seed=a), Source("seed", seed=b))
        for k, (a, b) in enumerate(zip(order[::2], order[1::2], strict=True))
    ]
    rounds.append(first)
    while len(rounds[-1]) > 1:
        previous, number = rounds[-1], len(rounds) + 1
        rounds.append(
            [
                Match(
                    f"W{number}-{k + 1}",
                    "winners",
                    number,
                    Source("winner", match=previous[2 * k].id),
                    Source("winner", match=previous[2 * k + 1].id),
                )
                for k in range(len(previous) // 2)
            ]
        )
    return rounds


def _losers_rounds(winners_rounds: list[list[Match]]) -> list[list[Match]]:
    """The losers' bracket: its first round pairs the first winners' round's losers; then
    each winners' round's losers meet the losers' bracket's survivors (in reverse order),
    and between those drops the survivors race each other."""
    rounds: list[list[Match]] = []
    first_losers = [Source("loser", match=match.id) for match in winners_rounds[0]]
    if len(first_losers) < 2:
        return rounds
    number = 1
    survivors = [
        Match(f"L{number}-{k + 1}", "losers", number, first_losers[2 * k], first_losers[2 * k + 1])
        for k in range(len(first_losers) // 2)
    ]
    rounds.append(survivors)
    for dropping_round in winners_rounds[1:]:
        # Drop-in round: the survivors against this winners' round's losers.
        number += 1
        drops = [Source("loser", match=match.id) for match in reversed(dropping_round)]
        survivors = [
            Match(
                f"L{number}-{k + 1}",
                "losers",
                number,
                Source("winner", match=previous.id),
                drop,
            )
            for k, (previous, drop) in enumerate(zip(rounds[-1], drops, strict=True))
        ]
        rounds.append(survivors)
        if len(survivors) > 1:  # the survivors race each other down to the next drop
            number += 1
            rounds.append(
                [
                    Match(
                        f"L{number}-{k + 1}",
                        "losers",
                        number,
                        Source("winner", match=survivors[2 * k].id),
                        Source("winner", match=survivors[2 * k + 1].id),
                    )
                    for k in range(len(survivors) // 2)
                ]
            )
    return rounds


def draw_bracket(seeds: Sequence[str], format: Format = Format.SINGLE) -> Bracket:
    """The bracket of `seeds` (entrants, best first) in `format`."""
    if not MIN_ENTRANTS <= len(seeds) <= MAX_ENTRANTS:
        raise BracketError(
            f"a bracket takes {MIN_ENTRANTS} to {MAX_ENTRANTS} entrants, not {len(seeds)}."
        )
    if len(set(seeds)) != len(seeds) or BYE in seeds:
        raise BracketError("each entrant of a bracket must be named once.")
    winners_rounds = _winners_rounds(_size(len(seeds)))
    matches = [match for round_ in winners_rounds for match in round_]
    if format is Format.DOUBLE:
        losers_rounds = _losers_rounds(winners_rounds)
        matches += [match for round_ in losers_rounds for match in round_]
        final = winners_rounds[-1][0]
        from_losers = (
            Source("winner", match=losers_rounds[-1][0].id)
            if losers_rounds
            else Source("loser", match=final.id)
        )
        last = len(winners_rounds) + 1
        matches.append(
            Match(GRAND_FINAL, "final", last, Source("winner", match=final.id), from_losers)
        )
        matches.append(
            Match(
                DECIDER,
                "final",
                last + 1,
                Source("winner", match=GRAND_FINAL),
                Source("loser", match=GRAND_FINAL),
            )
        )
    return Bracket(format, tuple(seeds), tuple(matches))
