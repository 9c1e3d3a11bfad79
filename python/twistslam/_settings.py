"""Typed conversion of setting values, shared by :class:`twistslam.Config` and the
simulator's :class:`twistslam.sim.SimConfig`: a value from Python, YAML or the command line
(``--set key=value`` gives strings) becomes the field's annotated type, or a ``ValueError``
names the key and what was expected."""

from __future__ import annotations

import functools
import types
import typing
from dataclasses import field
from typing import Any, Union

_TRUE = {"true", "yes", "on", "1"}
_FALSE = {"false", "no", "off", "0"}


@functools.cache
def type_hints(cls: type) -> dict[str, Any]:
    """``typing.get_type_hints(cls)``, resolved once per class: the string annotations
    (``from __future__ import annotations``) are evaluated by ``compile`` / ``eval`` on every
    call, and building and overriding a config asked ~1100 times (0.8 s of a run's start)."""
    return typing.get_type_hints(cls)


def _type_name(tp: Any) -> str:
    return getattr(tp, "__name__", None) or str(tp).replace("typing.", "")


def coerce(value: Any, tp: Any, key: str) -> Any:
    """``value`` (typed, or a string from the command line or YAML) as type ``tp``: bool, int,
    float, str, ``list[T]``, ``tuple[T, ...]`` / ``tuple[T1, T2]`` and ``T | None``. Raises
    ``ValueError`` naming ``key`` when the value does not fit."""
    origin = typing.get_origin(tp)
    if origin in (Union, types.UnionType):
        args = [a for a in typing.get_args(tp) if a is not type(None)]
        if value is None or (isinstance(value, str) and value.strip().lower() in ("none", "null", "")):
            return None
        return coerce(value, args[0], key)
    if origin is tuple:
        item_types = typing.get_args(tp)
        items = coerce(value, list[typing.Any], key) if isinstance(value, str) else value
        if not isinstance(items, (list, tuple)):
            raise ValueError(f"{key}: expected {_type_name(tp)}, got {value!r}")
        if len(item_types) == 2 and item_types[1] is Ellipsis:
            item_types = (item_types[0],) * len(items)
        if len(items) != len(item_types):
            raise ValueError(f"{key}: expected {len(item_types)} values, got {value!r}")
        return tuple(coerce(v, t, f"{key}[{i}]") for i, (v, t) in enumerate(zip(items, item_types)))
    if tp is typing.Any:
        return value
    if origin is list:
        (item_type,) = typing.get_args(tp)
        if isinstance(value, str):
            text = value.strip().strip("[]").strip()
            value = [v.strip() for v in text.split(",")] if text else []
        elif not isinstance(value, (list, tuple)):
            value = [value]
        return [coerce(v, item_type, f"{key}[{i}]") for i, v in enumerate(value)]
    bad = ValueError(f"{key}: expected {_type_name(tp)}, got {value!r}")
    if tp is bool:
        if isinstance(value, bool):
            return value
        if isinstance(value, str) and value.strip().lower() in _TRUE | _FALSE:
            return value.strip().lower() in _TRUE
        if isinstance(value, int) and value in (0, 1):
            return bool(value)
        raise bad
    if isinstance(value, bool) or value is None:
        raise bad  # True is an int in Python; never a count or a threshold here
    if tp is int:
        if isinstance(value, str):
            try:
                value = float(value.strip()) if any(c in value for c in ".eE") else int(value)
            except ValueError:
                raise bad from None
        if isinstance(value, float) and value.is_integer():
            return int(value)
        if isinstance(value, int):
            return value
        raise bad
    if tp is float:
        try:
            return float(value)
        except (TypeError, ValueError):
            raise bad from None
    if tp is str:
        if isinstance(value, (str, int, float)):
            return str(value)
        raise bad
    raise TypeError(f"{key}: unsupported config type {tp!r}")  # a bug in this module


def param(default: Any, why: str, unit: str = "", *, lo: float | None = None,
          hi: float | None = None) -> Any:
    """A config field: ``default``, the one-line reason for it, its unit and its valid range."""
    meta = {"why": why, "unit": unit, "lo": lo, "hi": hi}
    if isinstance(default, list):
        return field(default_factory=lambda: list(default), metadata=meta)
    return field(default=default, metadata=meta)
