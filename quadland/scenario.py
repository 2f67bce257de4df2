"""Scenario files: schema, loading, overrides and validation.

A scenario is a TOML file whose sections and keys are fixed by ``SCHEMA``.
It is validated once, here; everything downstream trusts it.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import tomllib
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from quadland.exceptions import ScenarioError

__all__ = ["Field", "SCHEMA", "Scenario", "load_scenario", "scenario_names", "SCENARIO_DIR"]

#: Folder of the scenarios shipped with quadland.
SCENARIO_DIR = Path(__file__).parent / "scenarios"


@dataclasses.dataclass(frozen=True)
class Field:
    """One key of a scenario section."""

    kind: type                      # float, int, bool or str
    unit: str
    doc: str
    length: int | None = None       # None: a scalar; n: a list of n values
    check: Callable[[Any], str | None] | None = None   # returns a complaint or None
    choices: tuple[str, ...] | None = None


def _positive(v):
    return None if np.all(np.asarray(v) > 0) else "must be > 0"


def _nonnegative(v):
    return None if np.all(np.asarray(v) >= 0) else "must be >= 0"


def _unit_interval(v):
    return None if 0 <= v <= 1 else "must be in [0, 1]"


def _at_least_one(v):
    return None if v >= 1 else "must be >= 1"


def _tilt_below_90(v):
    return None if abs(v[0]) < 90 and abs(v[1]) < 90 else \
        "|roll| and |pitch| must be below 90 deg (the thrust map is singular there)"


F, I, B, S = float, int, bool, str
#: The scenario schema: section -> key -> Field.
SCHEMA: Mapping[str, Mapping[str, Field]] = MappingProxyType({
    "scenario": {
        "name": Field(S, "-", "short name, used for the output folder"),
        "description": Field(S, "-", "one line describing the scenario"),
    },
    "simulation": {
        "duration": Field(F, "s", "simulated time", check=_positive),
        "output_rate_hz": Field(F, "Hz", "rows per second of trajectory.csv", check=_positive),
        "integrator": Field(S, "-", "CasADi integrator plugin", choices=("cvodes", "rk")),
        "reltol": Field(F, "-", "cvodes relative tolerance", check=_positive),
        "abstol": Field(F, "-", "cvodes absolute tolerance", check=_positive),
        "rk_steps_per_interval": Field(I, "-", "RK4 steps per hold interval (rk)",
                                       check=_at_least_one),
        "seed": Field(I, "-", "seed of every random draw", check=_nonnegative),
    },
    "quadrotor": {
        "mass": Field(F, "kg", "m1", check=_positive),
        "inertia": Field(F, "kg m^2", "Ix, Iy, Iz", 3, _positive),
        "drag_translational": Field(F, "N s/m", "Kt1..Kt3", 3, _nonnegative),
        "drag_rotational": Field(F, "N m s/rad", "Kr1..Kr3", 3, _nonnegative),
        "gravity": Field(F, "m/s^2", "g_s", check=_positive),
        "arm_length": Field(F, "m", "d, centre to rotor axis", check=_positive),
        "rotor_drag_factor": Field(F, "m", "c, yaw moment per unit thrust", check=_positive),
        "rotor_force_min": Field(F, "N", "lower rotor-force limit (C step)"),
        "rotor_force_max": Field(F, "N", "upper rotor-force limit (C step)", check=_positive),
    },
    "vehicle": {
        "m11": Field(F, "kg", "surge mass", check=_positive),
        "m22": Field(F, "kg", "sway mass", check=_positive),
        "m33": Field(F, "kg m^2", "yaw inertia", check=_positive),
        "d11": Field(F, "kg/s", "surge damping", check=_nonnegative),
        "d22": Field(F, "kg/s", "sway damping", check=_nonnegative),
        "d33": Field(F, "kg m^2/s", "yaw damping", check=_nonnegative),
        "tau": Field(F, "N, N, N m", "tau_x, tau_y, tau_z", 3),
        "deck_altitude": Field(F, "m", "z2"),
    },
    "initial": {
        "z1": Field(F, "m", "quadrotor altitude"),
        "eta1_deg": Field(F, "deg", "roll, pitch, yaw", 3, _tilt_below_90),
        "omega1_deg_s": Field(F, "deg/s", "body rates p, q, r", 3),
        "velocity1": Field(F, "m/s", "body velocity u, v, w", 3),
        "psi2_deg": Field(F, "deg", "vehicle heading"),
        "r2_deg_s": Field(F, "deg/s", "vehicle yaw rate"),
        "velocity2": Field(F, "m/s", "vehicle surge, sway", 2),
        "position2": Field(F, "m", "vehicle x2, y2", 2),
    },
    "reference": {
        "e1d": Field(F, "m, rad, rad, rad", "constant desired e1", 4),
    },
    "controller": {
        "k1": Field(F, "1/s", "diagonal of k1", 4, _positive),
        "k2": Field(F, "1/s", "diagonal of k2", 4, _positive),
        "gamma1": Field(F, "-", "Gamma1 = gamma1 I", check=_positive),
        "gamma2": Field(F, "-", "Gamma2 = gamma2 I", check=_positive),
        "k_w": Field(F, "-", "W_hat leakage", check=_positive),
        "k_zeta": Field(F, "-", "zeta_hat leakage", check=_positive),
        "rho": Field(F, "-", "tanh width varrho", check=_positive),
        "nominal_model": Field(B, "-", "feed forward the quadrotor's known dynamics"),
        "rate_hz": Field(F, "Hz", "control rate, 0 = continuous", check=_nonnegative),
        "backend": Field(S, "-", "control step implementation", choices=("casadi", "c")),
        "hold_compensation": Field(F, "periods", "extrapolation of the held command",
                                   check=_unit_interval),
    },
    "rbf": {
        "nodes": Field(I, "-", "l, the number of nodes", check=_at_least_one),
        "center_min": Field(F, "-", "first centre coordinate"),
        "center_max": Field(F, "-", "last centre coordinate"),
        "width": Field(F, "-", "common spread epsilon", check=_positive),
    },
    "disturbance": {
        "noise": Field(B, "-", "include the random part"),
        "sample_rate_hz": Field(F, "Hz", "hold interval of the disturbance", check=_positive),
        "force_bias": Field(F, "N", "constant part of d_F", 3),
        "force_amplitude": Field(F, "N", "sine amplitude of d_F"),
        "force_frequency": Field(F, "rad/s", "sine frequency of d_F", check=_nonnegative),
        "force_noise_std": Field(F, "N", "std of the noise on d_F", check=_nonnegative),
        "moment_bias": Field(F, "N m", "constant part of d_M", 3),
        "moment_amplitude": Field(F, "N m", "sine amplitude of d_M"),
        "moment_frequency": Field(F, "rad/s", "sine frequency of d_M", check=_nonnegative),
        "moment_noise_std": Field(F, "N m", "std of the noise on d_M", check=_nonnegative),
    },
})
del F, I, B, S


@dataclasses.dataclass(frozen=True)
class Scenario:
    """A validated scenario.

    Attributes
    ----------
    name : str
        The scenario's name.
    source : str
        Where it was read from.
    data : mapping
        section -> key -> value, complete and validated (lists as tuples).
    overrides : tuple of str
        The ``section.key=value`` overrides applied on top of the file.
    """

    name: str
    source: str
    data: Mapping[str, Mapping[str, Any]]
    overrides: tuple[str, ...] = ()

    def __getitem__(self, dotted: str):
        section, key = dotted.split(".", 1)
        return self.data[section][key]

    def to_dict(self) -> dict:
        """Plain nested dict (lists, not tuples) for JSON output."""
        return {s: {k: list(v) if isinstance(v, tuple) else v for k, v in kv.items()}
                for s, kv in self.data.items()}

    def replace(self, **changes) -> "Scenario":
        """A new validated scenario with ``{"section.key": value}`` changes."""
        raw = self.to_dict()
        for dotted, value in changes.items():
            section, key = _split_key(dotted)
            raw.setdefault(section, {})[key] = value
        return Scenario(self.name, self.source, _validate(raw, self.source), self.overrides)


def scenario_names() -> list[str]:
    """Names of the scenarios shipped with quadland."""
    return sorted(p.stem for p in SCENARIO_DIR.glob("*.toml"))


def load_scenario(name_or_path: str | Path = "paper",
                  overrides: Iterable[str] | Mapping[str, Any] | None = None) -> Scenario:
    """Load, override and validate a scenario.

    Parameters
    ----------
    name_or_path : str or Path
        A shipped scenario's name (``"paper"``) or the path of a TOML file.
    overrides : iterable of str or mapping, optional
        ``"section.key=value"`` strings (the value is read as TOML, or as a
        bare string when it is not valid TOML), or a mapping
        ``{"section.key": value}``.

    Returns
    -------
    Scenario

    Raises
    ------
    ScenarioError
        With a one-line message naming the file or key at fault.

    Examples
    --------
    >>> sc = load_scenario("paper", ["simulation.duration=2"])
    >>> sc["simulation.duration"]
    2.0
    """
    path = _resolve(name_or_path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise ScenarioError(f"{path}: cannot read: {exc.strerror or exc}") from None
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioError(f"{path}: malformed TOML: {exc}") from None
    pairs = _parse_overrides(overrides)
    for dotted, value in pairs:
        section, key = _split_key(dotted)
        if section not in SCHEMA:
            raise ScenarioError(f"--set {dotted}: {_unknown('section', section, SCHEMA)}")
        raw.setdefault(section, {})
        if not isinstance(raw[section], dict):
            raise ScenarioError(f"{path}: [{section}] must be a table")
        raw[section][key] = value
    data = _validate(raw, str(path))
    name = data["scenario"]["name"] if "name" in raw.get("scenario", {}) else path.stem
    return Scenario(name, str(path), data, tuple(f"{k}={v}" for k, v in pairs))


def _resolve(name_or_path) -> Path:
    candidate = Path(name_or_path)
    text = str(name_or_path)
    if candidate.suffix == ".toml" or "/" in text or "\\" in text:
        if not candidate.is_file():
            raise ScenarioError(f"{text}: scenario file not found")
        return candidate
    shipped = SCENARIO_DIR / f"{text}.toml"
    if shipped.is_file():
        return shipped
    if candidate.is_file():
        return candidate
    names = scenario_names()
    hint = difflib.get_close_matches(text, names, n=1)
    msg = f"unknown scenario '{text}'"
    msg += f" (did you mean '{hint[0]}'?)" if hint else f" (shipped: {', '.join(names)})"
    raise ScenarioError(msg)


def _split_key(dotted: str) -> tuple[str, str]:
    section, dot, key = dotted.partition(".")
    if not dot or not section or not key:
        raise ScenarioError(f"--set {dotted}: expected section.key=value")
    return section, key


def _parse_overrides(overrides) -> list[tuple[str, Any]]:
    if overrides is None:
        return []
    if isinstance(overrides, Mapping):
        return list(overrides.items())
    pairs = []
    for item in overrides:
        dotted, eq, text = str(item).partition("=")
        if not eq or not dotted.strip():
            raise ScenarioError(f"--set {item}: expected section.key=value")
        dotted, text = dotted.strip(), text.strip()
        try:
            value = tomllib.loads(f"v = {text}")["v"]
        except tomllib.TOMLDecodeError:
            value = text
        pairs.append((dotted, value))
    return pairs


def _unknown(what: str, name: str, known: Iterable[str]) -> str:
    hint = difflib.get_close_matches(name, list(known), n=1)
    return f"unknown {what} '{name}'" + (f" (did you mean '{hint[0]}'?)" if hint else "")


def _validate(raw: Mapping, source: str) -> dict:
    """Check every section and key of ``raw`` against SCHEMA; fill nothing."""
    out: dict[str, dict] = {}
    for section, table in raw.items():
        if section not in SCHEMA:
            raise ScenarioError(f"{source}: {_unknown('section', section, SCHEMA)}")
        if not isinstance(table, Mapping):
            raise ScenarioError(f"{source}: [{section}] must be a table")
        for key in table:
            if key not in SCHEMA[section]:
                raise ScenarioError(
                    f"{source}: {_unknown('key', f'{section}.{key}', _dotted(section))}")
    for section, fields in SCHEMA.items():
        table = raw.get(section, {})
        out[section] = {}
        for key, field in fields.items():
            dotted = f"{section}.{key}"
            if key not in table:
                if section == "scenario":
                    out[section][key] = "" if key == "description" else Path(source).stem
                    continue
                raise ScenarioError(f"{source}: missing key {dotted} ({field.doc}, {field.unit})")
            out[section][key] = _check_value(dotted, table[key], field)
    nodes = out["rbf"]
    if nodes["center_max"] < nodes["center_min"]:
        raise ScenarioError("rbf.center_max: must be >= rbf.center_min")
    q = out["quadrotor"]
    if q["rotor_force_max"] <= q["rotor_force_min"]:
        raise ScenarioError("quadrotor.rotor_force_max: must be > quadrotor.rotor_force_min")
    return out


def _dotted(section: str) -> list[str]:
    return [f"{section}.{k}" for k in SCHEMA[section]]


def _type_name(kind: type) -> str:
    return {float: "a number", int: "an integer", bool: "true or false", str: "a string"}[kind]


def _check_scalar(dotted: str, value, field: Field):
    kind = field.kind
    if kind is bool:
        if not isinstance(value, bool):
            raise ScenarioError(f"{dotted}: expected true or false, got {value!r}")
        return value
    if kind is str:
        if not isinstance(value, str):
            raise ScenarioError(f"{dotted}: expected a string, got {value!r}")
        if field.choices and value not in field.choices:
            raise ScenarioError(f"{dotted}: must be one of {', '.join(field.choices)}, "
                                f"got '{value}'")
        return value
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ScenarioError(f"{dotted}: expected {_type_name(kind)}, got {value!r}")
    if kind is int:
        if isinstance(value, float) and not value.is_integer():
            raise ScenarioError(f"{dotted}: expected an integer, got {value!r}")
        return int(value)
    if not math.isfinite(value):
        raise ScenarioError(f"{dotted}: must be finite, got {value}")
    return float(value)


def _check_value(dotted: str, value, field: Field):
    if field.length is None:
        if isinstance(value, list | dict):
            raise ScenarioError(f"{dotted}: expected {_type_name(field.kind)}, got {value!r}")
        checked = _check_scalar(dotted, value, field)
    else:
        if not isinstance(value, list) or len(value) != field.length:
            raise ScenarioError(f"{dotted}: expected a list of {field.length} numbers "
                                f"({field.unit}), got {value!r}")
        checked = tuple(_check_scalar(dotted, v, field) for v in value)
    if field.check is not None:
        complaint = field.check(checked)
        if complaint:
            raise ScenarioError(f"{dotted}: {complaint}, got {value!r}")
    return checked
