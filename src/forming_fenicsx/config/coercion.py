"""TOML tables to section dataclasses: every value checked against its field's type hint.

Integers are accepted where numbers are, non-finite numbers and unknown keys are rejected, and a
table value is merged over the field's default table key by key; each error is a
:class:`SceneError` naming the key and what is allowed.
"""
from __future__ import annotations

import dataclasses
import json
import math
import types
from types import NoneType
import typing
from typing import Any

from forming_fenicsx.core.errors import SceneError


def _typename(tp: Any) -> str:
    """A field type as messages name it ("a number or a string")."""
    names = {float: "a number", int: "an integer", str: "a string", bool: "true or false",
             dict: "a table"}
    args = [a for a in typing.get_args(tp) if a is not NoneType]
    if args:
        return " or ".join(_typename(a) for a in args)
    return names.get(typing.get_origin(tp) or tp, str(tp))


def _coerce(key: str, value: Any, tp: Any) -> Any:
    """Check a TOML value against a field type; integers are accepted where numbers are."""
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        errors = []
        for option in typing.get_args(tp):
            if option is NoneType:
                continue
            try:
                return _coerce(key, value, option)
            except SceneError as error:
                errors.append(error)
        if len(errors) == 1:  # e.g. float | None: the float's own message (finite, a number)
            raise errors[0]
        raise SceneError(key, f"must be {_typename(tp)}; got {value!r}")
    base = origin or tp
    ok = {float: isinstance(value, (int, float)) and not isinstance(value, bool),
          int: isinstance(value, int) and not isinstance(value, bool),
          bool: isinstance(value, bool), str: isinstance(value, str),
          dict: isinstance(value, dict)}[base]
    if not ok:
        raise SceneError(key, f"must be {_typename(tp)}; got {value!r}")
    if base is float:
        if not math.isfinite(value):
            raise SceneError(key, f"must be a finite number; got {value!r}")
        return float(value)
    if base is dict:
        return dict(value)
    return value


def build_section(cls: type, table: dict[str, Any], section: str,
                  defaults: dict[str, Any] | None = None) -> Any:
    """The dataclass ``cls`` of the TOML table of [section], ``defaults`` over the class's own."""
    hints = typing.get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls)}
    unknown = sorted(set(table) - set(fields))
    if unknown:
        raise SceneError(f"{section}.{key_name(unknown[0])}",
                         f"unknown key; allowed keys in [{section}]: {', '.join(fields)}")
    values = dict(defaults or {})
    for key, value in table.items():
        value = _coerce(f"{section}.{key}", value, hints[key])
        if isinstance(value, dict):  # a table is merged over the default one, key by key
            default = values.get(key, fields[key].default_factory())
            value = {**default, **value}
        values[key] = value
    return cls(**values)


def key_name(name: Any) -> str:
    """A key as it appears in messages: plain names as they are, anything else quoted."""
    return name if isinstance(name, str) and name.isidentifier() else json.dumps(str(name))
