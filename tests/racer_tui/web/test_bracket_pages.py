"""A bracket night and head-to-head races on the web, served as a host serves them: the
night page draws the knock-out as it advances (its rounds named as the app names them,
byes, winners and margins, the next race, the champion), the leaderboard shows the
head-to-head board the command line shows, names stay text, and no page or JSON names a
file's path on the host's disk."""

from __future__ import annotations

import json
from collections.abc import Iterator
from dataclasses import dataclass, field
from html.parser import HTMLParser
from pathlib import Path

import pytest

from league import nights
from league.bracket_nights import draw_night_bracket, next_match
from league.brackets import Format
from league.head_to_heads import record_head_to_head
from league.opening import open_league
from league.store import League
from sim.tracks.catalog import resolve_track
from tests.league.helpers import TRACK
from tests.league.sync.leagues import head_to_head
from tests.league.test_bracket_nights import MATCH_RULES, race_next
from tests.league.test_nights import FakeEngine, _resolve
from tests.racer_tui.test_head_to_head_cli import run_cli
from tests.racer_tui.web.conftest import IMAGE, LONG, SCRIPT, Served, get, serving
from tests.racer_tui.web.test_in_chromium import CHROMIUM, _rendered

# Qualifying laps, best first: the order the bracket seeds them.
SINGLE = {SCRIPT: [10.0], IMAGE: [10.5], "cy": [11.0], "dee": [11.5], LONG: [12.0]}
DOUBLE = {"ana": [10.0], "bob": [10.5], "cy": [11.0], "dee": [11.5]}
HIDDEN = "private-folder-of-ana"  # where a racer keeps their bundle: no page may say it
BUNDLE = "ana-car.racer-bundle"
HEAD_TO_HEAD_JSON = ("leaderboard", "--race-type", "head-to-head", "--format", "json")
# The command line's own names for a head-to-head board's row: the web's are the same.
ROW_FIELDS = [
    "rank",
    "racer",
    "cars",
    "starts",
    "wins",
    "losses",
    "rivals_beaten",
    "beaten_by",
    "replayed_starts",
    "hand_timed_starts",
]


@dataclass
class Shown:
    """A night page's bracket as a visitor reads it."""

    rounds: list[str] = field(default_factory=list)
    parts: list[str] = field(default_factory=list)  # a double elimination's headings
    matches: dict[str, dict[str, object]] = field(default_factory=dict)  # by match id
    champion: str = ""
    next_up: str = ""

    @property
    def next(self) -> list[str]:
        return [id_ for id_, match in self.matches.items() if match["next"]]


class BracketReader(HTMLParser):
    """Reads the bracket section of a night page: its headings, its sentences (the champion,
    the next race), and each match's sides (their class and text), margin and whether it
    is the next race."""

    def __init__(self, page: str) -> None:
        super().__init__()
        self.shown = Shown()
        self._open: list[tuple[str, list[str]]] = []  # the elements the parser is inside
        self._match: dict[str, object] | None = None
        self.feed(page)
        self.shown.champion = " ".join(self.shown.champion.split())
        self.shown.next_up = " ".join(self.shown.next_up.split())

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        classes = (dict(attrs).get("class") or "").split()
        self._open.append((tag, classes))
        if tag == "li" and "match" in classes:
            self._match = {"next": "next" in classes, "sides": [], "margin": ""}

    def handle_endtag(self, tag: str) -> None:
        while self._open and self._open.pop()[0] != tag:
            pass

    def _inside(self, tag: str, kind: str = "") -> bool:
        return any(t == tag and (not kind or kind in c) for t, c in self._open)

    def handle_data(self, data: str) -> None:
        if not self._inside("section", "bracket") or not self._open:
            return
        shown, match = self.shown, self._match
        tag, classes = self._open[-1]
        text = data.strip()
        if self._inside("p", "champion"):
            shown.champion += data
        elif self._inside("p", "next-up"):
            shown.next_up += data
        elif not text:
            return
        elif tag == "h4":
            shown.rounds.append(text)
        elif tag == "h3":
            shown.parts.append(text)
        elif match is not None and "match-id" in classes:
            shown.matches[text.split(" ")[0]] = match
        elif match is not None and "side" in classes:
            sides = match["sides"]
            assert isinstance(sides, list)
            sides.append((classes[-1], text))
        elif match is not None and "margin" in classes:
            match["margin"] = text


def bracket_shown(served: Served, night: str) -> Shown:
    status, _, page = get(f"{served.url}/night?id={night}")
    assert status == 200
    return BracketReader(page).shown


def qualified(league: League, name: str, laps: dict[str, list[float]]) -> nights.Night:
    night = nights.new_night(league, resolve_track(TRACK), name=name)
    for racer in laps:
        nights.add_entrant(league, night, racer, "reference")
    nights.draw_heats(league, night, seed=3)
    nights.run_heats(league, night, resolve_track(TRACK), _resolve, run_race=FakeEngine(laps))
    return night


@dataclass(frozen=True)
class Nights:
    served: Served
    single: str
    double: str
    bundled: str
    home: Path


@pytest.fixture(scope="module")
def league_nights(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Nights]:
    """A single elimination of five (three byes) with its first race run, a double
    elimination of four just drawn, a head-to-head race of the hostile names, and a night
    whose entrant races a bundle file from a folder of theirs."""
    home = tmp_path_factory.mktemp("bracket-home")
    db = home / "league.db"
    bundle = home / HIDDEN / BUNDLE
    bundle.parent.mkdir()
    bundle.write_bytes(b"")  # entering a bundle checks only that the file is there
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("RACER_TUI_HOME", str(home))
        with open_league(db) as league:
            single = qualified(league, "Single", SINGLE)
            draw_night_bracket(league, single, rules=MATCH_RULES)
            assert race_next(league, single, "higher") == "W1-2"  # dee beats the long name
            double = qualified(league, "Double", DOUBLE)
            draw_night_bracket(league, double, format=Format.DOUBLE, rules=MATCH_RULES)
            record_head_to_head(league, head_to_head(SCRIPT, IMAGE))
            bundled = nights.new_night(league, resolve_track(TRACK), name="Bundles")
            nights.add_entrant(league, bundled, "ana", str(bundle))
            nights.draw_heats(league, bundled, seed=1)
            league.conn.commit()
    with serving(db, home) as server:
        yield Nights(server, single.id, double.id, bundled.id, home)


def race_on(served: Served, night_id: str, *winners: str) -> None:
    """Race the night's next matches, the higher or the lower seed winning each."""
    with open_league(served.db) as league:
        night = nights.get_night(league, night_id)
        for winner in winners:
            race_next(league, night, winner)
        league.conn.commit()


def test_a_single_elimination_is_drawn_with_its_byes_winners_and_next_race(
    league_nights: Nights,
) -> None:
    served, night = league_nights.served, league_nights.single
    shown = bracket_shown(served, night)
    # Named as the app's bracket view names them; a single elimination has no parts.
    assert shown.rounds == ["Quarter-finals", "Semi-finals", "Final"] and shown.parts == []
    assert shown.matches["W1-1"]["sides"] == [("side", SCRIPT), ("open", "bye")]
    sides = [side for match in shown.matches.values() for side in match["sides"]]
    assert sides.count(("open", "bye")) == 3  # five in a bracket of eight
    assert shown.matches["W1-2"]["sides"] == [("won", "✓ dee"), ("lost", LONG)]
    assert str(shown.matches["W1-2"]["margin"]).startswith("won by ")
    assert shown.matches["W3-1"]["sides"] == [("open", "to be decided")] * 2
    # The first seed against the winner of W1-2: ready to race, and the page says so.
    assert shown.next == ["W2-1"]
    assert shown.matches["W2-1"]["sides"] == [("side", SCRIPT), ("side", "dee")]
    assert shown.next_up == f"Next race: {SCRIPT} v dee (Semi-finals, W2-1)"
    assert shown.champion == ""

    document = json.loads(get(f"{served.url}/api/night?id={night}")[2])["bracket"]
    assert document["next_match"] == "W2-1"
    assert [one["name"] for one in document["rounds"]] == shown.rounds
    assert document["rounds"][1]["matches"] == ["W2-1", "W2-2"]
    [raced] = [match for match in document["matches"] if match["race_id"]]
    assert raced["id"] == "W1-2" and raced["margin_seconds"] > 0

    race_on(served, night, "higher", "higher", "higher")  # W2-1, W2-2, the final
    shown = bracket_shown(served, night)
    assert shown.champion == f"Champion: {SCRIPT}" and shown.next == []
    assert shown.matches["W3-1"]["sides"] == [("won", f"✓ {SCRIPT}"), ("lost", IMAGE)]


def test_a_double_elimination_draws_its_losers_rounds_and_the_decider_once_needed(
    league_nights: Nights,
) -> None:
    served, night = league_nights.served, league_nights.double
    shown = bracket_shown(served, night)
    assert shown.parts == ["Winners' bracket", "Losers' bracket", "Finals"]
    assert shown.rounds == [
        "Winners' round 1",
        "Winners' round 2",
        "Losers' round 1",
        "Losers' round 2",
        "Grand final",  # the deciding race is not drawn: it may never be needed
    ]
    assert shown.next == ["W1-1"]
    assert shown.matches["L1-1"]["sides"] == [("open", "to be decided")] * 2

    # The winners' bracket and the losers' to their ends (ana through the winners', dee
    # through the losers'), then dee beats ana in the grand final: both have lost once.
    race_on(served, night, "higher", "higher", "higher", "lower", "lower", "lower")
    shown = bracket_shown(served, night)
    assert shown.rounds[-2:] == ["Grand final", "Deciding race"]
    assert shown.matches["GF"]["sides"] == [("lost", "ana"), ("won", "✓ dee")]
    assert shown.next == ["GF2"] and shown.champion == ""
    assert shown.next_up == "Next race: dee v ana (Deciding race, GF2)"

    race_on(served, night, "lower")  # dee, the fourth seed, again
    shown = bracket_shown(served, night)
    assert shown.champion == "Champion: dee" and shown.next == []
    assert shown.matches["GF2"]["sides"] == [("won", "✓ dee"), ("lost", "ana")]
    with open_league(served.db) as league:
        assert next_match(league, nights.get_night(league, night)) is None


def test_names_in_a_bracket_are_text(league_nights: Nights) -> None:
    page = get(f"{league_nights.served.url}/night?id={league_nights.single}")[2]
    bracket = page[page.index('<section class="bracket">') :]
    bracket = bracket[: bracket.index("</section>")]
    assert '<span class="side">&lt;script&gt;alert(1)&lt;/script&gt;</span>' in bracket
    assert '<span class="side">&#34;&gt;&lt;img src=x onerror=alert(1)&gt;</span>' in bracket
    assert "<script>alert" not in page and "<img" not in page
    assert BracketReader(page).shown.matches["W1-3"]["sides"] == [("side", IMAGE), ("open", "bye")]


def test_the_leaderboard_shows_the_head_to_head_board_as_the_command_line_does(
    league_nights: Nights, capsys: pytest.CaptureFixture[str]
) -> None:
    served = league_nights.served
    document = json.loads(get(served.url + "/api/leaderboard")[2])
    code, out, err = run_cli(capsys, *HEAD_TO_HEAD_JSON, "--db", str(served.db))
    assert code == 0, err
    board = document["head_to_head"]
    assert board == json.loads(out)  # one format, whichever a site asks
    assert board["board"] == "head-to-head" and board["races"] >= 2
    rows = {row["racer"]: row for row in board["rows"]}
    assert rows[SCRIPT]["wins"] >= 1 and rows[IMAGE]["losses"] >= 1
    assert list(rows[SCRIPT]) == ROW_FIELDS
    # The lap boards are as they were: head-to-head races rank no laps.
    assert {one["race_type"] for one in document["boards"]} == {"time_trial"}

    page = get(served.url + "/")[2]
    section = page[page.index('<section class="board head-to-head">') :]
    assert "<h2>Head-to-head</h2>" in section
    assert f"{board['races']} races, ranked by wins" in section
    # Each row: its rank, its racer as text, wins, losses, ahead of, behind, replayed.
    first = board["rows"][0]
    assert (
        f'<td class="num">1</td><td class="name">{_escaped(first["racer"])}</td>'
        f'<td class="num">{first["wins"]}</td><td class="num">{first["losses"]}</td>'
        f'<td class="num wide">{first["rivals_beaten"]}</td>'
        f'<td class="num wide">{first["beaten_by"]}</td>'
        f'<td class="num wide">{first["replayed_starts"]} of {first["starts"]}</td>'
    ) in section
    assert "&lt;script&gt;alert(1)&lt;/script&gt;" in section and "<script>alert" not in page


def _escaped(name: str) -> str:
    return (
        name.replace("&", "&amp;")
        .replace("<", "&lt;")
        .replace(">", "&gt;")
        .replace('"', "&#34;")
        .replace("'", "&#39;")
    )


def test_no_page_or_json_names_a_path_on_the_host_s_disk(league_nights: Nights) -> None:
    served, night = league_nights.served, league_nights.bundled
    paths = (
        f"/night?id={night}",
        f"/api/night?id={night}",
        f"/live?id={night}",
        f"/api/live?id={night}",
        f"/overlay?id={night}",
        "/",
        "/api/leaderboard",
    )
    for path in paths:
        status, _, body = get(served.url + path)
        assert status == 200, path
        assert HIDDEN not in body and str(league_nights.home) not in body, path
    document = json.loads(get(f"{served.url}/api/night?id={night}")[2])
    assert [entrant["model"] for entrant in document["entrants"]] == [BUNDLE]
    assert [heat["model"] for heat in document["heats"]] == [BUNDLE]
    assert BUNDLE in get(f"{served.url}/night?id={night}")[2]


@pytest.mark.skipif(CHROMIUM is None, reason="Chromium is not installed here")
def test_a_bracket_in_a_browser_is_text_and_needs_no_script(league_nights: Nights) -> None:
    page = _rendered(f"{league_nights.served.url}/night?id={league_nights.single}")
    # No element came from a name, and the page runs no script at all.
    assert not [tag for tag, _ in page.elements if tag in ("img", "iframe", "object", "script")]
    shown = "".join(page.text)
    assert "Quarter-finals" in shown and SCRIPT in shown and IMAGE in shown
