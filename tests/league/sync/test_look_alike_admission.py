"""A key proposed under a look-alike of an admitted racer's name, in Armenian or Greek
letters, is not admitted: the organiser is told which racer it looks like."""

from __future__ import annotations

from pathlib import Path

import pytest

from league.errors import LeagueError
from league.trust import membership
from tests.league.sync.test_signed_results import (  # the league of machines these tests share
    Machine,
    machines,  # noqa: F401 (a fixture)
)


@pytest.mark.parametrize("poser_name", ["\u0430\u0578\u0430", "\u0430\u03b7\u0430"])
def test_a_key_proposed_as_a_look_alike_of_ana_is_not_admitted(
    machines: dict[str, Machine],  # noqa: F811
    store_url: str,
    tmp_path: Path,
    poser_name: str,
) -> None:
    organiser = machines["organiser"]
    poser = Machine(tmp_path, poser_name, store_url)
    poser.sync()  # proposes its key under its racer's name
    organiser.sync()

    with pytest.raises(LeagueError, match="cannot be told apart from racer 'ana'"):
        membership.admit(organiser.league, organiser.key, poser_name)
    poser.league.close()
