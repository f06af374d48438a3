"""The one naming rule for things a racer names and racer-tui keeps as files (tracks, models).

Names become file and folder names, so they are limited to characters that are safe on
every platform and cannot climb out of their directory.
"""

from __future__ import annotations

import re

NAME_RULE = "letters, digits, '-' and '_', at most 64 characters"
NAME_PATTERN = re.compile(r"[A-Za-z0-9_-]{1,64}")


def is_valid_name(text: object) -> bool:
    """Whether `text` follows NAME_RULE (and so is safe as a file or folder name)."""
    return isinstance(text, str) and NAME_PATTERN.fullmatch(text) is not None
