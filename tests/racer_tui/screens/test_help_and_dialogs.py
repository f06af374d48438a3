"""Help rows come from BINDINGS; the path field completes like a shell."""

from __future__ import annotations

from pathlib import Path
from typing import ClassVar

from textual.binding import Binding, BindingType
from textual.screen import Screen

from racer_tui.screens.dialogs import PathSuggester
from racer_tui.screens.help import binding_topics, declared_bindings, key_rows, topic_table


class Base(Screen[None]):
    BINDINGS: ClassVar[list[BindingType]] = [Binding("b", "base_thing", "Base thing")]


class Child(Base):
    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("n,insert", "new", "New", tooltip="make one"),
        Binding("x", "internal", show=False),  # no description: not for the help screen
    ]


class Silent(Screen[None]):
    """Declares no keys of its own."""


def test_bindings_are_collected_with_their_own_bases_and_grouped_by_action() -> None:
    # The bases here are test classes, not racer_tui ones: only racer_tui bases are walked.
    assert [b.action for b in declared_bindings(Child)] == ["new", "new", "internal"]
    rows = key_rows(declared_bindings(Child), lambda binding: binding.key)
    assert [(row.keys, row.description, row.tooltip) for row in rows] == [
        (("n", "insert"), "New", "make one")
    ]


def test_topics_skip_screens_without_described_keys_and_filter_by_words() -> None:
    topics = binding_topics(
        [("Child", Child), ("Silent", Silent)],
        lambda binding: binding.key,
        extra=[("Child", Binding("ctrl+p", "command_palette", "Command palette"))],
    )
    assert [topic.title for topic in topics] == ["Child"]
    assert topic_table(topics[0], ["palette"]) is not None
    assert topic_table(topics[0], ["nothing", "matches"]) is None


async def test_path_suggester_completes_the_last_part(tmp_path: Path) -> None:
    (tmp_path / "drfc-model").mkdir()
    (tmp_path / "notes.txt").write_text("x")
    suggester = PathSuggester()
    assert await suggester.get_suggestion(str(tmp_path / "drf")) == f"{tmp_path}/drfc-model/"
    assert await suggester.get_suggestion(str(tmp_path / "no")) == f"{tmp_path}/notes.txt"
    assert await suggester.get_suggestion(str(tmp_path / "zzz")) is None
    assert await suggester.get_suggestion(str(tmp_path / "missing" / "x")) is None
