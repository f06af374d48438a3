"""The tests' process-wide cache of parsed CSS: shared by stylesheets with the same
variables (an app's theme), never by two themes."""

from __future__ import annotations

import pytest
from textual.css.stylesheet import Stylesheet, StylesheetParseError

from tests import textual_css

CSS = "Screen { background: $primary; }"


def _parsed(variables: dict[str, str], css: str = CSS) -> Stylesheet:
    sheet = Stylesheet(variables=variables)
    sheet.add_source(css, read_from=("test_textual_css", "CSS"))
    sheet.parse()
    return sheet


def test_the_same_css_and_theme_give_the_same_rules_another_theme_its_own() -> None:
    textual_css.install()  # as conftest does: a second install changes nothing
    dark = _parsed({"primary": "#004578"})
    assert _parsed({"primary": "#004578"}).rules[0] is dark.rules[0]
    light = _parsed({"primary": "#0178D4"})
    assert light.rules[0] is not dark.rules[0]
    assert light.rules[0].styles.background != dark.rules[0].styles.background


def test_css_with_an_error_raises_every_time() -> None:
    textual_css.install()
    for _ in range(2):
        with pytest.raises(StylesheetParseError):
            _parsed({"primary": "#004578"}, "Screen { colour: red; }")
