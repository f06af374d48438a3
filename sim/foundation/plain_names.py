"""What a name shown to other people may contain: racers, and the models and tracks in race
results. One home for the rule, used by race results (sim.race.result) and the league's
racers (league.racers).

A name is plain text a person can read and tell apart from others: 1 to MAX_NAME_LENGTH
printable characters, in Unicode's compatibility form (NFKC, so a full-width "Ａｄａ" is
"Ada"), without line breaks, control characters, or invisible and direction-changing
format characters (a right-to-left override or a zero-width space lets one name pose as
another). `look_alike_key` compares names as Unicode's confusable detection does (the
skeleton of UTS #39), so "аda" with a Cyrillic "а", or "аոа" with an Armenian "ո", can be
told to look like "ada" and "ana".
"""

from __future__ import annotations

import unicodedata
from functools import cache

MAX_NAME_LENGTH = 100
# Control characters, surrogates, line and paragraph breaks, private-use and unassigned
# code points, and format characters (bidirectional controls, zero-width spaces and joins).
_NOT_PLAIN = frozenset({"Cc", "Cs", "Zl", "Zp", "Co", "Cn", "Cf"})
_ZERO_WIDTH_JOINER = "\u200d"
# Characters that draw nothing though Unicode calls them marks or letters: the combining
# grapheme joiner, Hangul fillers and the blank braille pattern.
_BLANK = frozenset("\u034f\u115f\u1160\u3164\uffa0\u2800")


def _is_variation_selector(char: str) -> bool:
    return "\ufe00" <= char <= "\ufe0f"


# Canonical combining classes of marks drawn under a letter. UTS #39 takes some letters for
# another letter with such a mark (Greek η for n with a line below): at a leaderboard's
# size a reader sees the letter, not the mark, so a mark the table adds there is dropped.
_BELOW: frozenset[int] = frozenset({202, 218, 220, 222, 233})
# The left-to-right marks the table wraps right-to-left letters in, for display only.
_DISPLAY_MARK = "\u200e"


def normalised(text: str) -> str:
    """The name as it is kept: NFKC, without surrounding spaces."""
    return unicodedata.normalize("NFKC", text).strip()


def is_plain_name(text: object) -> bool:
    """Whether `text` can name a racer, model or track: 1 to MAX_NAME_LENGTH printable
    characters, none of them invisible or a control (see the module docstring). A
    zero-width joiner is allowed between two symbols, where it makes one emoji."""
    if not isinstance(text, str) or not text.strip() or len(text) > MAX_NAME_LENGTH:
        return False
    for index, char in enumerate(text):
        if char in _BLANK:
            return False
        if _is_variation_selector(char):
            # An emoji's presentation selector; after a letter it only hides there.
            if not (index and unicodedata.category(text[index - 1]) == "So"):
                return False
            continue
        if unicodedata.category(char) not in _NOT_PLAIN:
            continue
        if char == _ZERO_WIDTH_JOINER and _joins_symbols(text, index):
            continue
        return False
    return True


def _joins_symbols(text: str, index: int) -> bool:
    before, after = text[index - 1 : index], text[index + 1 : index + 2]
    if _is_variation_selector(before) and index >= 2:
        before = text[index - 2]  # 👁️‍🗨️: the selector belongs to the emoji before it
    return bool(before and after) and all(
        unicodedata.category(char) == "So" for char in before + after
    )


def look_alike_key(text: str) -> str:
    """Equal for names a reader cannot tell apart: "аda" (Cyrillic а), "ΑDA" (Greek Α) and
    "ADA" give the key of "ada". The UTS #39 skeleton, taken again after folding case (the
    table tells capital I from l, a reader of "Ian" and "lan" may not)."""
    return _skeleton(_skeleton(normalised(text)).casefold())


def _skeleton(text: str) -> str:
    """UTS #39's skeleton: each character of the decomposed text replaced by its prototype,
    decomposed again."""
    table = _prototypes()
    return unicodedata.normalize(
        "NFD", "".join(table.get(char, char) for char in unicodedata.normalize("NFD", text))
    )


@cache
def _prototypes() -> dict[str, str]:
    """Each confusable character's prototype, from Unicode's confusables table as
    confusable_homoglyphs ships it. That package keeps the table both ways (a character
    beside each it is confusable with) and has no skeleton(), so the direction is read
    back: a character with one partner that has others is a source and its partner the
    prototype; a prototype of several characters or of a string is one itself; a pair
    that has only each other maps both to the smaller (either may stand for both)."""
    from confusable_homoglyphs import confusables  # type: ignore[import-untyped]  # noqa: PLC0415 (9,600 pairs: loaded on first use)

    partners: dict[str, list[str]] = {}
    for char, entries in confusables.confusables_data.items():
        key = char.replace(_DISPLAY_MARK, "")
        partners.setdefault(key, []).extend(
            entry["c"].replace(_DISPLAY_MARK, "") for entry in entries
        )
    table: dict[str, str] = {}
    for char, others in partners.items():
        if len(char) != 1 or len(others) != 1:
            continue
        (other,) = others
        if len(other) == 1 and len(partners.get(other, ())) == 1:
            other = min(char, other)
        if other != char:
            table[char] = _without_marks_below(other)
    return table


def _without_marks_below(prototype: str) -> str:
    decomposed = unicodedata.normalize("NFD", prototype)
    if len(decomposed) < 2:
        return decomposed
    kept = "".join(c for c in decomposed if unicodedata.combining(c) not in _BELOW)
    return kept or decomposed
