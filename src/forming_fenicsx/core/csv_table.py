"""Numeric CSV tables a scene names (a die profile, a strain profile): a header row, then rows of
finite numbers; every refusal names the scene key and the row."""
from __future__ import annotations

import csv
import math
from pathlib import Path

from forming_fenicsx.core.errors import SceneError

WORDS = {2: "two", 3: "three"}


def column_name(header: str) -> str:
    """A column header without its unit, lower case: ``y [mm]`` -> ``y``."""
    return header.split("[", 1)[0].strip().lower()


def read_rows(path: str | Path, key: str, header: tuple[str, ...]
              ) -> list[tuple[int, list[float]]]:
    """(row number, values) of every non-blank row after the header, which must be ``header``
    (units in brackets allowed). Refused, naming ``key``: a missing file, another header, a row that
    is not len(header) finite numbers."""
    path = Path(path)
    names = ",".join(header)
    if not path.is_file():
        raise SceneError(key, f"must name an existing CSV file of {names} rows; got {str(path)!r}")
    with path.open(newline="") as stream:
        rows = list(csv.reader(stream))
    if not rows or tuple(column_name(c) for c in rows[0]) != header:
        raise SceneError(key, f"{path.name}: the first row must be the header {names}")
    found = []
    for number, row in enumerate(rows[1:], start=2):
        if not row or all(not c.strip() for c in row):
            continue
        try:
            values = [float(c) for c in row]
        except ValueError:
            raise SceneError(key, f"{path.name} row {number}: not "
                                  f"{WORDS.get(len(header), len(header))} numbers: {row}") from None
        if len(values) != len(header) or not all(math.isfinite(v) for v in values):
            raise SceneError(key, f"{path.name} row {number}: need "
                                  f"{WORDS.get(len(header), len(header))} finite "
                                  f"numbers; got {row}")
        found.append((number, values))
    return found
