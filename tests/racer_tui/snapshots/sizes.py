"""The four terminal sizes every screen and dialog is drawn at: 80x24 first (the size the
app is designed for), 60x20 (a terminal split beside another, where it must stay
legible), a common laptop terminal, and a large monitor."""

from __future__ import annotations

import pytest

SMALL = (80, 24)
TINY = (60, 20)
LARGE = (120, 40)
HUGE = (200, 60)
SIZES = pytest.mark.parametrize(
    "size", [SMALL, TINY, LARGE, HUGE], ids=["80x24", "60x20", "120x40", "200x60"]
)
