"""A Select for forms: what it holds is readable from the moment it is built.

Textual's Select sets its value when it mounts; until then `value` is `Select.NULL`, even
with `allow_blank=False`. A form read by a key pressed in the same burst that opened it (Esc
right after Enter, in one terminal read) saw NULL where a choice was expected, and
`int("Select.NULL")` crashed the model editor (issue 42). `chosen` is the choice: the
value once mounted, the value it was built with before.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from rich.console import RenderableType
from textual.widgets import Select
from textual.widgets.select import NoSelection  # the type of Select.NULL


class FormSelect(Select[Any]):
    """A Select that always has a choice (`allow_blank=False`), readable before it mounts."""

    def __init__(
        self, options: Iterable[tuple[RenderableType, Any]], *, value: Any, **kwargs: Any
    ) -> None:
        super().__init__(options, value=value, allow_blank=False, **kwargs)
        self._built_with = value

    @property
    def chosen(self) -> Any:
        """The value chosen, or the one the form was built with while Textual has none."""
        value = self.value
        return self._built_with if isinstance(value, NoSelection) else value


def choice_of(select: Select[Any], default: Any) -> Any:
    """Any Select's value, or `default` while it has none (not mounted yet, or cleared)."""
    if isinstance(select, FormSelect):
        return select.chosen
    value = select.value
    return default if isinstance(value, NoSelection) else value
