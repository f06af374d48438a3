"""What a name shown to other people may contain: racers, and the models and tracks in race
results. One home for the rule, used by race results (sim.race.result) and the league's
racers (league.racers).

A name is plain text a person can read and tell apart from others: 1 to MAX_NAME_LENGTH
printable characters, in Unicode's compatibility form (NFKC, so a full-width "Ａｄａ" is
"Ada"), without line breaks, control characters, or invisible and direction-changing
format characters (a right-to-left override or a zero-width space lets one name pose as
another). `look_alike_key` folds the letters that look the same in Latin, Cyrillic and
Greek, so "аda" with a Cyrillic "а" can be told to look like "ada".
"""

from __future__ import annotations

import unicodedata

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


# Letters that look like Latin ones (Cyrillic and Greek), and digits that look like letters.
_LOOK_ALIKES = str.maketrans(
    {
        **dict(zip("аеорсухіјѕԁһԛԝӏвмнтк", "aeopcyxijsdhqwlbmhtk", strict=True)),
        # Capital I of every script looks like l, as Latin "I" does (mapped below).
        **dict(zip("АВЕЗІЈКМНОРСТУХ", "ABE3lJKMHOPCTYX", strict=True)),
        **dict(zip("οανρτικυχ", "oavptikux", strict=True)),
        **dict(zip("ΑΒΕΖΗΙΚΜΝΟΡΤΥΧ", "ABEZHlKMNOPTYX", strict=True)),
        "0": "o",
        "1": "l",
        "I": "l",
    }
)


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
    """Equal for names a reader cannot tell apart: "аda" (Cyrillic а) and "ADA" give the
    key of "ada"."""
    return normalised(text).translate(_LOOK_ALIKES).casefold()
