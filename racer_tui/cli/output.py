"""Headless output helpers shared by the CLI commands."""

from __future__ import annotations

import json
import sys
from typing import Any

from rich import box
from rich.console import Console
from rich.table import Table
from rich.text import Text


def print_json(document: Any) -> None:
    sys.stdout.write(json.dumps(document, indent=2, sort_keys=False) + "\n")


def print_table(table: Table) -> None:
    Console().print(table)


def plain_table(title: str) -> Table:
    """A table without vertical rules (a leaderboard's eight columns fit 80 characters).
    Titles carry night and season names, so they are plain Text, never markup."""
    return Table(
        title=Text(title, style="table.title"),
        box=box.SIMPLE_HEAD,
        pad_edge=False,
        collapse_padding=True,
    )
