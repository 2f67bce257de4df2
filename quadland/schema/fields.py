"""One key of a scenario: its type, unit, meaning and physical range, and the checks.

A scenario's sections and keys are fixed by its model's schema
(:data:`quadland.schema.SCHEMAS`): every key a :class:`Field` with its type,
unit, one line of meaning and physical range. :func:`check_value` checks one
value against its field, with one line naming the key when it does not fit.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
import re
from collections.abc import Callable
from typing import Any

import numpy as np

from quadland.constants import TILT_MIN
from quadland.exceptions import ScenarioError

__all__ = ["Field", "MAX_RATE_HZ", "MAX_DURATION_S", "check_value", "show", "safe_name",
           "one_line", "tilt_below_90", "tilt_within"]


@dataclasses.dataclass(frozen=True)
class Field:
    """One key of a scenario section.

    Attributes
    ----------
    kind : type
        ``float``, ``int``, ``bool`` or ``str``.
    unit, doc : str
    length : int, optional
        None for a scalar, n for a list of n values (of ``min_length`` to n
        values when ``min_length`` is given).
    min_length : int, optional
        Shortest list accepted; None: exactly ``length``.
    lo, hi : float, optional
        The physical range of every value: ``lo <= v <= hi`` (``lo < v``
        with ``lo_open``).
    lo_open : bool
    zero_ok : bool
        0 is also accepted (a switch, e.g. ``controller.rate_hz = 0``:
        continuous time).
    check : callable, optional
        Extra test of the whole value; returns a complaint or None.
    choices : tuple of str, optional
    default : optional
        The value a scenario that leaves the key out takes (None: the key is
        required). A key added after the shipped scenarios, whose default is the
        behaviour of before, so that they fly as they did.
    """

    kind: type
    unit: str
    doc: str
    length: int | None = None
    min_length: int | None = None
    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    zero_ok: bool = False
    check: Callable[[Any], str | None] | None = None
    choices: tuple[str, ...] | None = None
    default: Any = None

    def range_text(self) -> str:
        """The accepted range, e.g. ``(0, 1e+04] kg`` (empty without one)."""
        if self.choices:
            return "one of " + ", ".join(self.choices)
        if self.lo is None and self.hi is None:
            return ""
        left = "(" if self.lo_open else "["
        text = f"{left}{self.lo:g}, {self.hi:g}]"
        unit = f" {self.unit}" if self.unit not in ("-", "") else ""
        return ("0 or " if self.zero_ok else "") + text + unit

    def complaint(self, v) -> str | None:
        """Why the scalar ``v`` is out of range, or None."""
        if self.zero_ok and v == 0:
            return None
        low_bad = self.lo is not None and (v <= self.lo if self.lo_open else v < self.lo)
        if low_bad or (self.hi is not None and v > self.hi):
            return f"must be in {self.range_text()}"
        return None


def tilt_below_90(v):
    tilt = math.cos(math.radians(v[0])) * math.cos(math.radians(v[1]))
    return None if abs(v[0]) < 90 and abs(v[1]) < 90 and tilt >= TILT_MIN else \
        f"|roll| and |pitch| must be below 90 deg with cos(roll) cos(pitch) >= {TILT_MIN:g} " \
        "(the thrust map is singular there)"


_NAME_RE = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]{0,63}")


def safe_name(v):
    return None if _NAME_RE.fullmatch(v) else \
        "must be 1 to 64 letters, digits, '.', '_' or '-', starting with a letter or digit " \
        "(it names the output folder)"


def one_line(v):
    return None if len(v) <= 200 and v.isprintable() else \
        "must be one line of at most 200 printable characters"


#: Largest rate, in Hz, of any clock of a run (output, control, disturbance).
MAX_RATE_HZ = 1e5
#: Largest duration of a run, s.
MAX_DURATION_S = 1e5


def tilt_within(limit_deg):
    def check(v):
        return None if abs(v[0]) < limit_deg and abs(v[1]) < limit_deg else \
            f"|roll| and |pitch| must be below {limit_deg:g} deg"
    return check


def show(value, limit: int = 40) -> str:
    """A value as one short line for an error message.

    Whitespace runs become one space and any other control character is
    escaped (``\\x1b``): a message never carries a terminal's escape sequence.
    """
    text = value if isinstance(value, str) else repr(value)
    text = "".join(c if not (ord(c) < 0x20 or 0x7f <= ord(c) < 0xa0)
                   else c.encode("unicode_escape").decode("ascii")
                   for c in " ".join(text.split()))
    return text if len(text) <= limit else text[:limit - 3] + "..."


def type_name(kind: type) -> str:
    return {float: "a number", int: "an integer", bool: "true or false", str: "a string"}[kind]


def check_scalar(dotted: str, value, field: Field):
    kind = field.kind
    if kind is bool:
        if not isinstance(value, bool | np.bool_):
            raise ScenarioError(f"{dotted}: expected true or false, got {show(value)}")
        return bool(value)
    if kind is str:
        if not isinstance(value, str):
            raise ScenarioError(f"{dotted}: expected a string, got {show(value)}")
        if field.choices and value not in field.choices:
            raise ScenarioError(f"{dotted}: must be one of {', '.join(field.choices)}, "
                                f"got {show(value)}")
        return value
    if isinstance(value, bool | np.bool_) or not isinstance(value, numbers.Real):
        raise ScenarioError(f"{dotted}: expected {type_name(kind)}, got {show(value)}")
    if kind is int and isinstance(value, numbers.Integral):
        value = int(value)                          # exact, however many digits
        complaint = field.complaint(value)
        if complaint:
            raise ScenarioError(f"{dotted}: {complaint}, got {show(value)}")
        return value
    try:
        number = float(value)
    except OverflowError:
        number = math.inf
    if not math.isfinite(number):
        raise ScenarioError(f"{dotted}: must be finite and {field.range_text() or 'finite'}, "
                            f"got {show(value)}")
    if kind is int:
        if not float(number).is_integer():
            raise ScenarioError(f"{dotted}: expected an integer, got {show(value)}")
        value = int(value)
    complaint = field.complaint(value if kind is int else number)
    if complaint:
        raise ScenarioError(f"{dotted}: {complaint}, got {show(value)}")
    return value if kind is int else number


def check_value(dotted: str, value, field: Field):
    if field.length is None:
        if isinstance(value, list | tuple | dict):
            raise ScenarioError(f"{dotted}: expected {type_name(field.kind)}, "
                                f"got {show(value)}")
        checked = check_scalar(dotted, value, field)
    else:
        shortest = field.length if field.min_length is None else field.min_length
        if not isinstance(value, list | tuple) or not shortest <= len(value) <= field.length:
            count = field.length if shortest == field.length else \
                f"{shortest} to {field.length}"
            raise ScenarioError(f"{dotted}: expected a list of {count} numbers "
                                f"({field.unit}), got {show(value)}")
        checked = tuple(check_scalar(dotted, v, field) for v in value)
    if field.check is not None:
        complaint = field.check(checked)
        if complaint:
            raise ScenarioError(f"{dotted}: {complaint}, got {show(value)}")
    return checked
