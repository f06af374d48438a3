"""Rows read by column name: a query's columns (named with AS where they are expressions)
become a dataclass's fields of the same names, so a column added, moved or renamed in a
query cannot shift every value after it into the wrong field."""

from __future__ import annotations

import dataclasses
import sqlite3
from operator import itemgetter
from typing import TypeVar

T = TypeVar("T")


def rows_as(cls: type[T], cursor: sqlite3.Cursor) -> list[T]:
    """The cursor's rows as `cls` instances, each column to the field of its
    name; fields no column names keep their defaults. The names are matched once per
    query, then each row is built from its plain values: boards read thousands of rows."""
    names = [column[0] for column in cursor.description]
    fields = [field.name for field in dataclasses.fields(cls)]  # type: ignore[arg-type]
    unknown = sorted(set(names) - set(fields))
    if unknown or len(set(names)) != len(names):
        raise ValueError(f"{cls.__name__} has no field for the query's columns {unknown or names}")
    given = [name for name in fields if name in names]
    pick = itemgetter(*(names.index(name) for name in given))
    if len(given) == 1:
        return [cls(**{given[0]: pick(values)}) for values in cursor]
    if given == fields[: len(given)]:  # the leading fields: positional, the fastest
        return [cls(*pick(values)) for values in cursor]
    return [cls(**dict(zip(given, pick(values), strict=True))) for values in cursor]


def row_as(cls: type[T], row: sqlite3.Row) -> T:
    """One row as `cls`, each column to the field of its name."""
    return cls(**{name: row[name] for name in row.keys()})  # noqa: SIM118 (a Row is not a dict)
