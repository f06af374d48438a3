"""One parse of each stylesheet per test process, not one per app.

Every app a test starts parses the CSS of every widget class it mounts again: Textual keeps
its parsed rules per stylesheet, that is per app. In a test process that starts hundreds
of apps that was about a fifth of each start-up (140 ms of 690, profiled). Here the rules
are kept for the process, keyed on everything Textual's own cache is keyed on and on the
app's CSS variables (its theme), which the parse substitutes. Textual treats parsed rules
as read-only (an app's own re-parse hands the same ones out again), so sharing them
between apps changes nothing an app does. CSS that fails to parse raises in every app as
before (an exception is never kept; rules with errors are checked after this cache).
"""

from __future__ import annotations

from typing import Any

from textual.css.model import RuleSet
from textual.css.stylesheet import Stylesheet

_RULES: dict[tuple[Any, ...], list[RuleSet]] = {}


def install() -> None:
    parse_rules = Stylesheet._parse_rules
    if getattr(parse_rules, "shared_by_the_process", False):
        return

    def shared_parse_rules(
        self: Stylesheet,
        css: str,
        *,  # Textual's one call names them
        read_from: Any,
        is_default_rules: bool = False,
        tie_breaker: int = 0,
        scope: str = "",
    ) -> list[RuleSet]:
        variables = tuple(sorted(self._variables.items()))
        key = (css, read_from, is_default_rules, tie_breaker, scope, variables)
        rules = _RULES.get(key)
        if rules is None:
            rules = parse_rules(
                self,
                css,
                read_from=read_from,
                is_default_rules=is_default_rules,
                tie_breaker=tie_breaker,
                scope=scope,
            )
            _RULES[key] = rules
        return rules

    shared_parse_rules.shared_by_the_process = True  # type: ignore[attr-defined]
    Stylesheet._parse_rules = shared_parse_rules  # type: ignore[method-assign, assignment]
