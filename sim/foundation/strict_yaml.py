"""YAML that is data and nothing else, and says so when a key is given twice.

PyYAML's safe loader keeps the last of two equal keys without a word; in a rules file that
means the host's first `penalty_seconds` silently loses to a second one further down. This
loader refuses it, naming the line, like any other YAML error.
"""

from __future__ import annotations

from typing import Any

import yaml


class DuplicateKeyError(yaml.MarkedYAMLError):
    """A mapping with the same key twice."""


class _StrictLoader(yaml.SafeLoader):
    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict[Any, Any]:
        self.flatten_mapping(node)  # `<<: *anchor` merges, as the safe loader allows
        seen: set[Any] = set()
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=deep)
            try:
                repeated = key in seen
            except TypeError:  # an unhashable key: the base class reports it
                break
            if repeated:
                raise DuplicateKeyError(
                    problem=f"the key {key!r} is given twice", problem_mark=key_node.start_mark
                )
            seen.add(key)
        return super().construct_mapping(node, deep=deep)


def load_data(text: str) -> Any:
    """Plain data from YAML text (safe: never objects); `yaml.YAMLError` when it is not
    valid YAML or repeats a key."""
    return yaml.load(text, Loader=_StrictLoader)
