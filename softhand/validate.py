"""Input checks shared by every stage: one ``ValueError`` per bad value, naming it.

Every message starts with the key path as the user wrote it and the value, then says what is
allowed, e.g. ``sil.mu_MPa = 'abc': expected a list of 2 numbers`` or
``representations.soft-contact.params.solimp[0] = nan: expected a finite number in [0.0001, 0.3]``.
Callers add where the input came from (a file, a command-line flag) in front.

This module imports nothing from the stages (fem, laws, skin, hands, envs, viz), so each of them
may use it.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np

__all__ = ["check_keys", "check_mapping", "check_number", "check_numbers", "check_path", "join",
           "range_text", "show"]

_MAX_SHOWN = 80  # characters of a value's repr quoted in a message


def show(value: Any) -> str:
    """Short ``repr`` of ``value`` for a message (numpy scalars as Python numbers, long values cut)."""
    if isinstance(value, np.generic):
        value = value.item()
    text = repr(value)
    return text if len(text) <= _MAX_SHOWN else text[:_MAX_SHOWN - 5] + " ...]"


def join(key: str, name: str | int) -> str:
    """Key path of a member: ``join("law", "prony")`` = ``law.prony``; an int indexes: ``g[0]``."""
    if isinstance(name, int):
        return f"{key}[{name}]"
    return f"{key}.{name}" if key else str(name)


def range_text(lo: float | None = None, hi: float | None = None, *, lo_open: bool = False,
               hi_open: bool = False) -> str:
    """The allowed range in words: ``> 0``, ``<= 1``, ``in (0, 0.5)``, ``in [0, 1)``, or ``""``."""
    if lo is None and hi is None:
        return ""
    if hi is None:
        return f"{'>' if lo_open else '>='} {lo:g}"
    if lo is None:
        return f"{'<' if hi_open else '<='} {hi:g}"
    return f"in {'(' if lo_open else '['}{lo:g}, {hi:g}{')' if hi_open else ']'}"


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(
        value, (bool, np.bool_))


def check_number(key: str, value: Any, *, lo: float | None = None, hi: float | None = None,
                 lo_open: bool = False, hi_open: bool = False, integer: bool = False,
                 why: str = "") -> float:
    """Return ``value`` as a float if it is a finite real number in the range, else raise.

    Args:
        key: key path of the value, as the user wrote it (starts the message).
        value: the value to check; ``bool``, strings, lists and complex numbers are not numbers.
        lo, hi: bounds (None: unbounded on that side).
        lo_open, hi_open: exclude the bound itself.
        integer: the value must also be a whole number (returned as a float all the same).
        why: a reason appended to the message, e.g. ``"(the pocket must fit under the roof)"``.

    Raises:
        ValueError: ``"{key} = {value}: expected a finite number {range}"`` (or ``an integer``).
    """
    kind = "an integer" if integer else "a finite number"
    rng = range_text(lo, hi, lo_open=lo_open, hi_open=hi_open)
    tail = f" {rng}" if rng else ""
    tail += f" {why}" if why else ""
    if not _is_number(value):
        raise ValueError(f"{key} = {show(value)}: expected {kind}{tail}")
    v = float(value)
    ok = math.isfinite(v) and not (integer and not v.is_integer())
    if ok and lo is not None:
        ok = v > lo if lo_open else v >= lo
    if ok and hi is not None:
        ok = v < hi if hi_open else v <= hi
    if not ok:
        raise ValueError(f"{key} = {show(value)}: expected {kind}{tail}")
    return v


def check_numbers(key: str, value: Any, *, length: int | None = None, min_length: int = 0,
                  lo: float | None = None, hi: float | None = None, lo_open: bool = False,
                  hi_open: bool = False, why: str = "") -> tuple[float, ...]:
    """Return ``value`` as a tuple of floats if it is a list of numbers in the range, else raise.

    Args:
        key: key path of the list; an entry is named ``key[i]``.
        value: a list or tuple (a 1-D numpy array is accepted too; a string is not).
        length: exact number of entries (None: any number >= ``min_length``).
        min_length: fewest entries when ``length`` is None.
        lo, hi, lo_open, hi_open: range of every entry, as in `check_number`.
        why: reason appended to a wrong-length message, e.g. ``"(as many as sil.alpha)"``.

    Raises:
        ValueError: ``"{key} = {value}: expected a list of N numbers"`` or the entry's message.
    """
    if isinstance(value, np.ndarray) and value.ndim == 1:
        value = value.tolist()
    if length is not None:
        want = f"a list of {length} number{'s' if length != 1 else ''}"
    else:
        want = f"a list of at least {min_length} numbers" if min_length else "a list of numbers"
    ok = isinstance(value, (list, tuple)) and (
        len(value) == length if length is not None else len(value) >= min_length)
    if not ok:
        got = f" (got {len(value)})" if isinstance(value, (list, tuple)) else ""
        raise ValueError(f"{key} = {show(value)}: expected {want}{got}{' ' + why if why else ''}")
    return tuple(check_number(join(key, i), v, lo=lo, hi=hi, lo_open=lo_open, hi_open=hi_open)
                 for i, v in enumerate(value))


def check_mapping(key: str, value: Any, *, required: Iterable[str] = (),
                  optional: Iterable[str] | None = ()) -> Mapping[str, Any]:
    """Return ``value`` if it is a mapping with every ``required`` key and no unknown key.

    Args:
        key: key path of the mapping (``""`` for a file's top level).
        value: the value to check.
        required: keys that must be present.
        optional: further allowed keys; None allows any other key.

    Raises:
        ValueError: not a mapping, a missing key or an unknown key, naming it.
    """
    required = tuple(required)
    what = key or "top level"
    if not isinstance(value, Mapping):
        names = (*required, *(optional or ()))
        keys = f" with keys {', '.join(names)}" if names else ""
        raise ValueError(f"{what} = {show(value)}: expected an object{keys}")
    for name in value:
        if not isinstance(name, str):
            raise ValueError(f"{what}: key {show(name)} is not a string")
    if optional is not None:
        check_keys(key, value, (*required, *optional))
    for name in required:
        if name not in value:
            raise ValueError(f"{join(key, name)}: missing (required: {', '.join(required)})")
    return value


def check_path(key: str, value: Any, *, what: str = "folder") -> str:
    """Return ``value`` as a string if it is a path (a ``str`` or ``os.PathLike``) that is not
    empty or blank, else raise; whether it exists is the reader's to say.

    Raises:
        ValueError: ``"{key} = '': expected a {what} path, got an empty string"`` or
            ``"{key} = 5: expected a {what} path (a str or os.PathLike)"``.
    """
    if isinstance(value, os.PathLike):
        value = os.fspath(value)
    if not isinstance(value, str):
        raise ValueError(f"{key} = {show(value)}: expected a {what} path (a str or os.PathLike)")
    if not value.strip():
        raise ValueError(f"{key} = {show(value)}: expected a {what} path, got an empty string")
    return value


def check_keys(key: str, value: Mapping[str, Any], allowed: Iterable[str]) -> None:
    """Raise a ValueError naming the first key of ``value`` that is not in ``allowed``."""
    allowed = tuple(allowed)
    for name in value:
        if name not in allowed:
            raise ValueError(f"{join(key, name)} = {show(value[name])}: unknown key; allowed: "
                             f"{', '.join(allowed)}")
