"""The three terminal sizes every screen and dialog is drawn at: 80x24 first (the size the
app is designed for), a common laptop terminal, and a large monitor."""

from __future__ import annotations

import pytest

SMALL = (80, 24)
LARGE = (120, 40)
HUGE = (200, 60)
SIZES = pytest.mark.parametrize("size", [SMALL, LARGE, HUGE], ids=["80x24", "120x40", "200x60"])
