"""Knock-out brackets: seeding, byes, single and double elimination played to the end
whoever wins each match, and the final order a night's standings take."""

from __future__ import annotations

import random

import pytest

from league.brackets import (
    BYE,
    DECIDER,
    GRAND_FINAL,
    Bracket,
    BracketError,
    Format,
    draw_bracket,
    seeding_order,
)


def _play(bracket: Bracket, pick: random.Random | None = None) -> dict[str, str]:
    """Race every match as it becomes ready: the better seed wins, or a random side."""
    seed = {entrant: k for k, entrant in enumerate(bracket.seeds)}
    winners: dict[str, str] = {}
    while ready := bracket.ready(winners):
        for match in ready:
            a, b = bracket.sides(match, winners)
            assert a and b and a != b
            winner = min((a, b), key=seed.__getitem__) if pick is None else pick.choice((a, b))
            bracket.check_result(match.id, winner, winners)
            winners[match.id] = winner
    return winners


def _names(count: int) -> list[str]:
    return [f"r{k + 1}" for k in range(count)]


def test_seeds_are_placed_so_the_best_meet_last() -> None:
    assert seeding_order(2) == [1, 2]
    assert seeding_order(4) == [1, 4, 2, 3]
    assert seeding_order(8) == [1, 8, 4, 5, 2, 7, 3, 6]
    for size in (2, 4, 8, 16, 32, 64):
        order = seeding_order(size)
        assert sorted(order) == list(range(1, size + 1))
        # Every first-round pair adds up to size + 1; seeds 1 and 2 are in opposite halves.
        assert {a + b for a, b in zip(order[::2], order[1::2], strict=True)} == {size + 1}
        assert (order.index(1) < size // 2) != (order.index(2) < size // 2)


def test_single_elimination_of_eight_goes_by_seed_when_the_better_seed_wins() -> None:
    bracket = draw_bracket(_names(8))
    assert [match.id for match in bracket.matches] == [
        "W1-1", "W1-2", "W1-3", "W1-4", "W2-1", "W2-2", "W3-1",
    ]  # fmt: skip
    first = [bracket.sides(match, {}) for match in bracket.ready({})]
    assert first == [("r1", "r8"), ("r4", "r5"), ("r2", "r7"), ("r3", "r6")]
    winners = _play(bracket)
    assert len(winners) == 7
    assert bracket.champion(winners) == "r1"
    # The final's loser, the semi-finals' losers by seed, then the quarter-finals'.
    assert bracket.final_order(winners) == _names(8)


def test_byes_go_through_without_a_race() -> None:
    bracket = draw_bracket(_names(5))
    assert bracket.size == 8
    ready = [bracket.sides(match, {}) for match in bracket.ready({})]
    # r1, r2 and r3 are drawn against byes: r2 and r3 meet in round 2 at once.
    assert ready == [("r4", "r5"), ("r2", "r3")]
    w11 = bracket.match("W1-1")
    assert bracket.outcome(w11, {}) == ("r1", BYE)
    winners = _play(bracket)
    assert len(winners) == 4  # n - 1 races for n entrants
    assert bracket.final_order(winners) == _names(5)


@pytest.mark.parametrize("format", list(Format))
@pytest.mark.parametrize("count", [2, 3, 4, 5, 6, 7, 8, 9, 13, 16, 17])
def test_any_results_play_to_one_champion_and_a_full_order(format: Format, count: int) -> None:
    names = _names(count)
    for trial in range(8):
        bracket = draw_bracket(names, format)
        winners = _play(bracket, random.Random(trial * 100 + count))
        champion = bracket.champion(winners)
        order = bracket.final_order(winners)
        assert order is not None and champion == order[0]
        assert sorted(order) == sorted(names)
        losses = {name: 0 for name in names}
        for match in bracket.matches:
            outcome = bracket.outcome(match, winners)
            assert outcome is not None
            if outcome[1] != BYE:
                losses[outcome[1]] += 1
        allowed = 1 if format is Format.SINGLE else 2
        # Everyone but the champion is out: lost once (single) or twice (double); the
        # champion of a double bracket may have lost once, in its grand final.
        assert all(losses[name] == allowed for name in names if name != champion)
        assert losses[champion] <= allowed - 1
        races = len(winners)
        if format is Format.SINGLE:
            assert races == count - 1
        else:
            assert 2 * count - 2 <= races <= 2 * count - 1


def test_double_elimination_drops_first_losers_and_decides_a_won_grand_final() -> None:
    names = _names(4)
    bracket = draw_bracket(names, Format.DOUBLE)
    ids = [match.id for match in bracket.matches]
    assert ids == ["W1-1", "W1-2", "W2-1", "L1-1", "L2-1", GRAND_FINAL, DECIDER]
    winners = {"W1-1": "r1", "W1-2": "r2", "W2-1": "r1"}
    # The first round's losers race in the losers' bracket; the winners' final's loser
    # drops in against its winner.
    assert bracket.sides(bracket.match("L1-1"), winners) == ("r4", "r3")
    winners["L1-1"] = "r3"
    assert bracket.sides(bracket.match("L2-1"), winners) == ("r3", "r2")
    winners["L2-1"] = "r3"
    assert bracket.sides(bracket.match(GRAND_FINAL), winners) == ("r1", "r3")
    # The winners' bracket's winner wins the grand final: no deciding race.
    done = {**winners, GRAND_FINAL: "r1"}
    assert bracket.ready(done) == []
    assert bracket.final_order(done) == ["r1", "r3", "r2", "r4"]
    # The losers' bracket's winner wins it: both have lost once, and they race again.
    again = {**winners, GRAND_FINAL: "r3"}
    assert [match.id for match in bracket.ready(again)] == [DECIDER]
    assert bracket.champion(again) is None
    again[DECIDER] = "r3"
    assert bracket.final_order(again) == ["r3", "r1", "r2", "r4"]
    # Eight, the better seed winning every race: the order is the seeding.
    eight = draw_bracket(_names(8), Format.DOUBLE)
    assert eight.final_order(_play(eight)) == _names(8)


def test_results_that_do_not_fit_are_refused_in_one_sentence() -> None:
    bracket = draw_bracket(_names(4))
    with pytest.raises(BracketError, match="r3 does not race in W1-1: r1 and r4 do"):
        bracket.check_result("W1-1", "r3", {})
    with pytest.raises(BracketError, match="W2-1 cannot be raced yet"):
        bracket.check_result("W2-1", "r1", {})
    with pytest.raises(BracketError, match="already has a winner"):
        bracket.check_result("W1-1", "r1", {"W1-1": "r1"})
    with pytest.raises(BracketError, match="no match 'X9'"):
        bracket.match("X9")
    with pytest.raises(BracketError, match="did not race in W1-1"):
        bracket.outcome(bracket.match("W1-1"), {"W1-1": "r2"})
    for bad in ([], ["solo"], ["a", "a"], ["a", BYE], _names(65)):
        with pytest.raises(BracketError):
            draw_bracket(bad)


@pytest.mark.parametrize("count", [8, 11, 16])
def test_how_often_two_entrants_can_meet(count: int) -> None:
    """Single elimination: once at most. Double: once in each bracket at most, and the
    grand final's pair a third time in the deciding race."""
    for format in Format:
        bracket = draw_bracket(_names(count), format)
        winners = _play(bracket, random.Random(count))
        met: dict[frozenset[str], int] = {}
        for match in bracket.matches:
            a, b = bracket.sides(match, winners)
            if a and b:
                met[frozenset((a, b))] = met.get(frozenset((a, b)), 0) + 1
        if format is Format.SINGLE:
            assert set(met.values()) == {1}
            continue
        final = frozenset(x for x in bracket.sides(bracket.match(GRAND_FINAL), winners) if x)
        assert all(times <= (3 if pair == final else 2) for pair, times in met.items())


def test_the_same_seeds_give_the_same_bracket() -> None:
    names = _names(11)
    assert draw_bracket(names, Format.DOUBLE) == draw_bracket(list(names), Format.DOUBLE)
    # Every source names a seed or an earlier match: the plan can be raced in its order.
    bracket = draw_bracket(names, Format.DOUBLE)
    seen: set[str] = set()
    for match in bracket.matches:
        for source in (match.a, match.b):
            assert source.kind == "seed" or source.match in seen
        seen.add(match.id)
    assert len(seen) == len(bracket.matches)
