"""`--rules FILE|PRESET`: a rules YAML file, or the name of one of the rules presets
(league, physical, practice, object-avoidance, head-to-bot, droa), for `racer-tui --race`
and `racer-tui night new`; `--race` also takes head-to-head. A file of that name wins over a
preset: a racer who wrote one meant it."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from sim.race.rules import RACE_ONLY_PRESETS, RULE_PRESETS, RaceRules, RulesError, load_rules

PRESET_NAMES = tuple(name for name, _, _ in RULE_PRESETS)
RACE_PRESETS = (*RULE_PRESETS, *RACE_ONLY_PRESETS)
HELP = f"a rules YAML file (unset keys keep the defaults) or a preset: {', '.join(PRESET_NAMES)}"
RACE_HELP = (
    "a rules YAML file (unset keys keep the defaults) or a preset: "
    f"{', '.join(name for name, _, _ in RACE_PRESETS)}"
)


def rules_option(
    value: str | Path,
    presets: Sequence[tuple[str, str, RaceRules]] = RULE_PRESETS,
) -> RaceRules:
    """The rules `--rules` names; a RulesError (one sentence) when it is neither a readable
    rules file nor one of `presets`."""
    path = Path(value).expanduser()
    if path.exists():
        return load_rules(path)
    name = str(value).strip().lower()
    for preset, _, rules in presets:
        if preset == name:
            return rules
    if not path.suffix and len(path.parts) == 1:  # a name, not a file's path
        names = ", ".join(preset for preset, _, _ in presets)
        raise RulesError(
            f"there is no rules file or preset called {str(value).strip()!r}; give a rules "
            f"YAML file or one of the presets: {names}."
        )
    return load_rules(path)  # its own sentence: the file cannot be read
