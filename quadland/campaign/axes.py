"""The axes of an envelope: two scenario keys, each swept over a grid of values.

An axis is ``KEY=LO:HI:N``: ``N`` values evenly spaced from ``LO`` to ``HI``
(both included; ``N = 1`` needs ``LO = HI``). ``KEY`` is a numeric key of the
scenario's schema (``vehicle.m11``), an element of a list key
(``wind.mean[1]``), or one of the two derived axes of the wind over the deck
(:data:`DERIVED`), which set ``wind.mean``'s horizontal components from the
vehicle's heading and velocity at the hand-over. :func:`parse_axis` checks
one in one line (``axis: ...``) before anything is flown or written.

In a cell, the axes' values replace what a run's draws gave those keys
(:func:`apply_cell`); a key the scenario's ``[campaign]`` disperses with
``also`` moves those keys with it, as its dispersion would (the drive force
that holds a vehicle's speed). docs/cli.md, "quadland envelope".
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from quadland.campaign.draws import apply_mode
from quadland.exceptions import CampaignError
from quadland.schema import SCHEMAS, did_you_mean, show, split_dotted

__all__ = ["Axis", "DERIVED", "OVER_DECK_SPEED", "OVER_DECK_DIRECTION", "MAX_POINTS",
           "parse_axis", "apply_cell", "over_deck_wind", "wind_over_deck"]

#: The wind over the deck's speed, m/s: the air's speed relative to the vehicle.
OVER_DECK_SPEED = "wind.over_deck_speed"
#: Where the wind over the deck blows from, deg from the bow, positive to starboard
#: (0: on the nose, 90: from starboard, -90 or 270: from port), as a ship's
#: operating limits diagram draws it.
OVER_DECK_DIRECTION = "wind.over_deck_direction_deg"
#: The derived axes: name -> (unit, what).
DERIVED: Mapping[str, tuple[str, str]] = {
    OVER_DECK_SPEED: ("m/s", "wind over the deck's speed"),
    OVER_DECK_DIRECTION: ("deg", "wind over the deck's direction from the bow, "
                                 "positive to starboard")}
#: Most values on one axis.
MAX_POINTS = 1000
_KEY_RE = re.compile(r"([A-Za-z0-9_.]+?)(?:\[(\d+)\])?")


@dataclasses.dataclass(frozen=True)
class Axis:
    """One axis of an envelope.

    Attributes
    ----------
    name : str
        As given: ``section.key``, ``section.key[i]`` or a derived axis.
    key : str
        The scenario key it sets (``wind.mean`` for the derived axes).
    element : int or None
        The list element it sets, None for a single-number key.
    values : tuple of float
        The grid's values, ``LO`` to ``HI``.
    unit : str
    integer : bool
        The key holds integers (its values are written as such).
    """

    name: str
    key: str
    element: int | None
    values: tuple[float, ...]
    unit: str
    integer: bool = False

    @property
    def derived(self) -> bool:
        """A derived axis (the wind over the deck), not a key of the scenario."""
        return self.name in DERIVED

    @property
    def angle(self) -> bool:
        """Its values are angles in degrees (a polar map's angle)."""
        return self.unit == "deg"

    def to_dict(self) -> dict:
        """The axis as envelope.json and campaign.json record it."""
        return {"name": self.name, "unit": self.unit,
                "values": [int(v) if self.integer else v for v in self.values]}


def _fail(text: str, why: str) -> CampaignError:
    return CampaignError(f"axis: {show(text, 60)}: {why}")


def _grid(text: str, spec: str) -> tuple[float, ...]:
    parts = spec.split(":")
    if len(parts) != 3:
        raise _fail(text, "expected KEY=LO:HI:N (N values from LO to HI)")
    try:
        lo, hi = float(parts[0]), float(parts[1])
    except ValueError:
        raise _fail(text, f"LO and HI must be numbers, got {show(parts[0])} and "
                          f"{show(parts[1])}") from None
    try:
        n = int(parts[2])
    except ValueError:
        raise _fail(text, f"N must be an integer, got {show(parts[2])}") from None
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise _fail(text, "LO and HI must be finite")
    if not 1 <= n <= MAX_POINTS:
        raise _fail(text, f"N must be in [1, {MAX_POINTS}], got {n}")
    if n == 1 and lo != hi:
        raise _fail(text, f"one value (N = 1) needs LO = HI, got {lo:g} and {hi:g}")
    if n > 1 and not lo < hi:
        raise _fail(text, f"LO must be below HI, got {lo:g} and {hi:g}")
    return tuple(float(v) for v in np.linspace(lo, hi, n))


def parse_axis(text: str, data: Mapping[str, Mapping[str, Any]], model: str) -> Axis:
    """One ``KEY=LO:HI:N``, checked against a scenario.

    Parameters
    ----------
    text : str
    data : mapping
        The scenario's validated values (``Scenario.data``).
    model : str
        Its model: its schema names the keys.

    Returns
    -------
    Axis

    Raises
    ------
    CampaignError
        ``axis: ...``: one line naming the axis and what is wrong with it
        (an unknown key, a key that does not hold numbers, a list key
        without its element, an element past its end, a bad range, a value
        outside the key's range).
    """
    name, eq, spec = str(text).partition("=")
    name = name.strip()
    if not eq or not name:
        raise _fail(text, "expected KEY=LO:HI:N (N values from LO to HI)")
    values = _grid(text, spec.strip())
    if name in DERIVED:
        if "wind" not in data or "velocity2" not in data.get("initial", {}):
            raise _fail(text, f"{name} needs a landing scenario (a deck that moves)")
        return Axis(name, "wind.mean", None, values, DERIVED[name][0])
    match = _KEY_RE.fullmatch(name)
    schema = SCHEMAS[model]
    section, key = split_dotted(match.group(1)) if match else ("", "")
    if match is None or section not in schema or key not in schema[section] \
            or section == "scenario":
        known = [f"{s}.{k}" for s in schema if s != "scenario" for k in schema[s]]
        hint = did_you_mean(match.group(1) if match else name, [*known, *DERIVED])
        raise _fail(text, f"{show(name)} is not a key of this scenario's schema"
                          + (f" (did you mean '{hint}'?)" if hint else ""))
    field, dotted = schema[section][key], f"{section}.{key}"
    if field.kind not in (float, int):
        kind = {bool: "true or false", str: "text"}[field.kind]
        raise _fail(text, f"{dotted} holds {kind}, not numbers")
    element = None if match.group(2) is None else int(match.group(2))
    current = data[section][key]
    if field.length is None and element is not None:
        raise _fail(text, f"{dotted} is a single number, not a list")
    if field.length is not None:
        if element is None:
            raise _fail(text, f"{dotted} is a list of {len(current)} numbers: name one "
                              f"element, e.g. {dotted}[0]")
        if element >= len(current):
            raise _fail(text, f"{dotted} has {len(current)} elements (0 to "
                              f"{len(current) - 1}), not [{element}]")
    for v in values:
        if field.kind is int and v != int(v):
            raise _fail(text, f"{dotted} holds integers; the grid gives {v:g}")
        complaint = field.complaint(v)
        if complaint:
            raise _fail(text, f"{name} = {v:g} is outside its range {field.range_text()}")
    units = field.unit.split(", ")             # "N, N, N m": one per element
    unit = units[element] if element is not None and len(units) == len(current) else field.unit
    return Axis(name, dotted, element, values, unit, field.kind is int)


def over_deck_wind(speed: float, direction_deg: float, velocity: Sequence[float],
                   heading_deg: float) -> tuple[float, float]:
    """The wind in E (x, y) that blows over a moving deck at ``speed`` from ``direction_deg``.

    The air moves relative to the deck at ``speed`` toward the stern when it
    comes from the bow (``direction_deg`` 0), toward port when from
    starboard (90); the deck moves at ``velocity`` (surge, sway) on
    ``heading_deg`` (E's x to y, y to port). In the deck's frame the air's
    velocity is ``speed (-cos b, sin b)`` and the wind that makes it is that
    plus the deck's own velocity, turned into E.

    Examples
    --------
    >>> over_deck_wind(5.0, 0.0, (5.0, 0.0), 0.0)     # a ship making 5 m/s in still air
    (0.0, 0.0)
    """
    b, psi = math.radians(direction_deg), math.radians(heading_deg)
    bx = velocity[0] - speed * math.cos(b)
    by = velocity[1] + speed * math.sin(b)
    return (math.cos(psi) * bx - math.sin(psi) * by, math.sin(psi) * bx + math.cos(psi) * by)


def wind_over_deck(wind: Sequence[float], velocity: Sequence[float], heading_deg: float
                   ) -> tuple[float, float]:
    """The inverse of :func:`over_deck_wind`: ``(speed, direction_deg)`` of a scenario's wind."""
    psi = math.radians(heading_deg)
    bx = math.cos(psi) * wind[0] + math.sin(psi) * wind[1] - velocity[0]
    by = -math.sin(psi) * wind[0] + math.cos(psi) * wind[1] - velocity[1]
    return math.hypot(bx, by), math.degrees(math.atan2(by, -bx))


def apply_cell(values: Mapping[str, Any], axes: Sequence[Axis], cell: Sequence[float],
               data: Mapping[str, Mapping[str, Any]], spec, hold: Sequence[str] = ()
               ) -> dict[str, Any]:
    """A run's values with a cell's: the axes' values in place of the draws'.

    Parameters
    ----------
    values : mapping
        The run's drawn values (``RunDraw.values``).
    axes : sequence of Axis
    cell : sequence of float
        The cell's value on each axis.
    data : mapping
        The scenario's values (what a key not drawn holds).
    spec : CampaignSpec
        Its dispersions: a key dispersed with ``also`` moves those keys too.
    hold : sequence of str
        Dispersed keys held at the scenario's value.

    Returns
    -------
    dict
        ``section.key`` -> value, as :meth:`quadland.Scenario.replace` takes it.
    """
    out = dict(values)

    def current(dotted):
        if dotted in out:
            return out[dotted]
        section, key = split_dotted(dotted)
        return data[section][key]

    for dotted in hold:
        section, key = split_dotted(dotted)
        value = data[section][key]
        out[dotted] = list(value) if isinstance(value, tuple) else value
    derived = {}
    for axis, v in zip(axes, cell, strict=True):
        if axis.derived:
            derived[axis.name] = v
            continue
        _follow(out, axis, v, spec)
        if axis.element is None:
            out[axis.key] = int(v) if axis.integer else v
        else:
            now = list(current(axis.key))
            now[axis.element] = int(v) if axis.integer else v
            out[axis.key] = now
    if derived:
        velocity, heading = current("initial.velocity2"), current("initial.psi2_deg")
        wind = list(current("wind.mean"))
        speed, direction = wind_over_deck(wind, velocity, heading)
        wind[:2] = over_deck_wind(derived.get(OVER_DECK_SPEED, speed),
                                  derived.get(OVER_DECK_DIRECTION, direction), velocity,
                                  heading)
        out["wind.mean"] = wind
    return out


def _follow(out: dict, axis: Axis, v: float, spec) -> None:
    """Move the ``also`` keys of ``axis.key``'s dispersion as its draw ``X`` would."""
    for disp in spec.dispersions:
        target = disp.targets[0]
        if target.key != axis.key or len(disp.targets) == 1:
            continue
        nominal = target.nominal[axis.element or 0]
        if disp.mode == "relative":
            if nominal == 0:
                raise CampaignError(f"axis: {axis.name}: its dispersion moves "
                                    f"{', '.join(t.key for t in disp.targets[1:])} in "
                                    "proportion, but its nominal is 0")
            x = v / nominal - 1.0
        else:
            x = v - nominal
        for t in disp.targets:
            per = [apply_mode(disp.mode, nom, x) for nom in t.nominal]
            out[t.key] = per[0] if t.scalar else per
