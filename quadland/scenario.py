"""Scenario files: schema, loading, overrides and validation.

A scenario is a TOML file whose sections and keys are fixed by ``SCHEMA``.
It is validated once, here; everything downstream trusts it. Its
``[campaign]`` table is kept as written (``Scenario.campaign_table``): only a
campaign validates it (``quadland.campaign``), the commands that ignore it
never refuse a scenario for its sake.
"""

from __future__ import annotations

import dataclasses
import datetime
import difflib
import math
import numbers
import re
import tomllib
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from quadland.constants import TILT_MIN
from quadland.exceptions import ScenarioError

__all__ = ["Field", "SCHEMA", "LANDING_SCHEMA", "SCHEMAS", "MODELS", "Scenario", "load_scenario",
           "scenario_names", "require_model", "SCENARIO_DIR", "toml_value"]

#: Folder of the scenarios shipped with quadland.
SCENARIO_DIR = Path(__file__).parent / "scenarios"


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


def _tilt_below_90(v):
    tilt = math.cos(math.radians(v[0])) * math.cos(math.radians(v[1]))
    return None if abs(v[0]) < 90 and abs(v[1]) < 90 and tilt >= TILT_MIN else \
        f"|roll| and |pitch| must be below 90 deg with cos(roll) cos(pitch) >= {TILT_MIN:g} " \
        "(the thrust map is singular there)"


_NAME_RE = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]{0,63}")


def _safe_name(v):
    return None if _NAME_RE.fullmatch(v) else \
        "must be 1 to 64 letters, digits, '.', '_' or '-', starting with a letter or digit " \
        "(it names the output folder)"


def _one_line(v):
    return None if len(v) <= 200 and v.isprintable() else \
        "must be one line of at most 200 printable characters"


#: Largest rate, in Hz, of any clock of a run (output, control, disturbance).
MAX_RATE_HZ = 1e5
#: Largest duration of a run, s.
MAX_DURATION_S = 1e5

F, I, B, S = float, int, bool, str
_POS = dict(lo=0.0, lo_open=True)
#: The scenario schema: section -> key -> Field. Every number has a physical range.
SCHEMA: Mapping[str, Mapping[str, Field]] = MappingProxyType({
    "scenario": {
        "name": Field(S, "-", "short name, used for the output folder", check=_safe_name),
        "description": Field(S, "-", "one line describing the scenario", check=_one_line),
    },
    "simulation": {
        "duration": Field(F, "s", "simulated time", lo=1e-3, hi=MAX_DURATION_S),
        "output_rate_hz": Field(F, "Hz", "rows per second of trajectory.csv", lo=1e-3,
                                hi=MAX_RATE_HZ),
        "integrator": Field(S, "-", "rk: compiled RK4 on the exact grid; cvodes: CasADi's "
                            "variable-step reference (continuous loop)", choices=("cvodes", "rk")),
        "reltol": Field(F, "-", "cvodes relative tolerance", lo=1e-14, hi=1e-2),
        "abstol": Field(F, "-", "cvodes absolute tolerance", lo=1e-14, hi=1e-2),
        "rk_steps_per_interval": Field(I, "-", "RK4 steps per hold interval (rk)", lo=1,
                                       hi=1000),
        "seed": Field(I, "-", "seed of every random draw", lo=0, hi=2 ** 63 - 1),
    },
    "quadrotor": {
        "mass": Field(F, "kg", "m1", lo=1e-3, hi=1e4),
        "inertia": Field(F, "kg m^2", "Ix, Iy, Iz", 3, lo=1e-6, hi=1e4),
        "drag_translational": Field(F, "N s/m", "Kt1..Kt3", 3, lo=0.0, hi=1e3),
        "drag_rotational": Field(F, "N m s/rad", "Kr1..Kr3", 3, lo=0.0, hi=1e3),
        "gravity": Field(F, "m/s^2", "g_s", lo=0.1, hi=100.0),
        "arm_length": Field(F, "m", "d, centre to rotor axis", lo=1e-3, hi=10.0),
        "rotor_drag_factor": Field(F, "m", "c, yaw moment per unit thrust", lo=1e-4, hi=10.0),
        "rotor_force_min": Field(F, "N", "lower rotor-force limit (the sampled step clips)",
                                 lo=-1e6, hi=1e6),
        "rotor_force_max": Field(F, "N", "upper rotor-force limit (the sampled step clips)",
                                 lo=1e-3, hi=1e6),
    },
    "vehicle": {
        "m11": Field(F, "kg", "surge mass", lo=1e-3, hi=1e8),
        "m22": Field(F, "kg", "sway mass", lo=1e-3, hi=1e8),
        "m33": Field(F, "kg m^2", "yaw inertia", lo=1e-3, hi=1e10),
        "d11": Field(F, "kg/s", "surge damping", lo=0.0, hi=1e8),
        "d22": Field(F, "kg/s", "sway damping", lo=0.0, hi=1e8),
        "d33": Field(F, "kg m^2/s", "yaw damping", lo=0.0, hi=1e10),
        "tau": Field(F, "N, N, N m", "tau_x, tau_y, tau_z", 3, lo=-1e8, hi=1e8),
        "deck_altitude": Field(F, "m", "z2", lo=-1e4, hi=1e4),
    },
    "initial": {
        "z1": Field(F, "m", "quadrotor altitude", lo=-1e4, hi=1e4),
        "eta1_deg": Field(F, "deg", "roll, pitch, yaw", 3, lo=-3600.0, hi=3600.0,
                          check=_tilt_below_90),
        "omega1_deg_s": Field(F, "deg/s", "body rates p, q, r", 3, lo=-1e4, hi=1e4),
        "velocity1": Field(F, "m/s", "body velocity u, v, w", 3, lo=-1e3, hi=1e3),
        "psi2_deg": Field(F, "deg", "vehicle heading", lo=-3600.0, hi=3600.0),
        "r2_deg_s": Field(F, "deg/s", "vehicle yaw rate", lo=-1e4, hi=1e4),
        "velocity2": Field(F, "m/s", "vehicle surge, sway", 2, lo=-1e3, hi=1e3),
        "position2": Field(F, "m", "vehicle x2, y2", 2, lo=-1e7, hi=1e7),
    },
    "reference": {
        "e1d": Field(F, "m, rad, rad, rad", "constant desired e1", 4, lo=-1e4, hi=1e4),
    },
    "controller": {
        "k1": Field(F, "1/s", "diagonal of k1", 4, hi=1e6, **_POS),
        "k2": Field(F, "1/s", "diagonal of k2", 4, hi=1e6, **_POS),
        "gamma1": Field(F, "-", "Gamma1 = gamma1 I", hi=1e6, **_POS),
        "gamma2": Field(F, "-", "Gamma2 = gamma2 I", hi=1e6, **_POS),
        "k_w": Field(F, "-", "W_hat leakage", hi=1e6, **_POS),
        "k_zeta": Field(F, "-", "zeta_hat leakage", hi=1e6, **_POS),
        "rho": Field(F, "-", "tanh width varrho", lo=1e-9, hi=1e6),
        "nominal_model": Field(B, "-", "feed forward the quadrotor's known dynamics"),
        "rate_hz": Field(F, "Hz", "control rate, 0 = continuous", lo=1.0, hi=MAX_RATE_HZ,
                         zero_ok=True),
        "backend": Field(S, "-", "control step implementation", choices=("casadi", "c")),
        "hold_compensation": Field(F, "periods", "extrapolation of the held command",
                                   lo=0.0, hi=1.0),
    },
    "rbf": {
        "nodes": Field(I, "-", "l, the number of nodes", lo=1, hi=1000),
        "center_min": Field(F, "-", "first centre coordinate", lo=-1e6, hi=1e6),
        "center_max": Field(F, "-", "last centre coordinate", lo=-1e6, hi=1e6),
        "width": Field(F, "-", "common spread epsilon", lo=1e-6, hi=1e6),
    },
    "disturbance": {
        "noise": Field(B, "-", "include the random part"),
        "sample_rate_hz": Field(F, "Hz", "hold interval of the disturbance", lo=1e-3,
                                hi=MAX_RATE_HZ),
        "force_bias": Field(F, "N", "constant part of d_F", 3, lo=-1e4, hi=1e4),
        "force_amplitude": Field(F, "N", "sine amplitude of d_F", lo=-1e4, hi=1e4),
        "force_frequency": Field(F, "rad/s", "sine frequency of d_F", lo=0.0, hi=1e5),
        "force_noise_std": Field(F, "N", "std of the noise on d_F", lo=0.0, hi=1e4),
        "moment_bias": Field(F, "N m", "constant part of d_M", 3, lo=-1e4, hi=1e4),
        "moment_amplitude": Field(F, "N m", "sine amplitude of d_M", lo=-1e4, hi=1e4),
        "moment_frequency": Field(F, "rad/s", "sine frequency of d_M", lo=0.0, hi=1e5),
        "moment_noise_std": Field(F, "N m", "std of the noise on d_M", lo=0.0, hi=1e4),
    },
})
del F, I, B, S


#: The loops a scenario may select with ``scenario.model`` ("paper" when absent).
MODELS = ("paper", "landing")


def _tilt_within(limit_deg):
    def check(v):
        return None if abs(v[0]) < limit_deg and abs(v[1]) < limit_deg else \
            f"|roll| and |pitch| must be below {limit_deg:g} deg"
    return check


def _sines(name: str, unit: str, what: str, amp_hi: float) -> dict[str, Field]:
    """The three keys of one prescribed deck motion: up to three sinusoids."""
    amp = f"{name}_amplitude" + ("_deg" if unit == "deg" else "")
    return {
        amp: Field(float, unit, f"{what} amplitudes a_i of sum a_i sin(w_i t + phase_i)", 3,
                   min_length=1, lo=0.0, hi=amp_hi),
        f"{name}_frequency": Field(float, "rad/s", f"{what} frequencies w_i", 3, min_length=1,
                                   lo=0.0, hi=100.0),
        f"{name}_phase_deg": Field(float, "deg", f"{what} phases", 3, min_length=1, lo=-3600.0,
                                   hi=3600.0),
    }


F, I, B, S = float, int, bool, str
#: The landing scenario schema (``scenario.model = "landing"``): the 6-DOF
#: loop of ``quadland_symbolic.landing`` with guidance, motor lag, rotor limits, the
#: sampled step, a moving deck and wind (docs/landing.md).
LANDING_SCHEMA: Mapping[str, Mapping[str, Field]] = MappingProxyType({
    "scenario": {
        **SCHEMA["scenario"],
        "model": Field(S, "-", "the loop simulated", choices=("landing",)),
    },
    "simulation": {
        "duration": SCHEMA["simulation"]["duration"],
        "output_rate_hz": SCHEMA["simulation"]["output_rate_hz"],
        "rk_steps_per_interval": Field(I, "-", "RK4 steps per hold interval", lo=1, hi=1000),
        "seed": SCHEMA["simulation"]["seed"],
    },
    "quadrotor": {
        **{k: SCHEMA["quadrotor"][k] for k in ("mass", "inertia", "drag_translational",
                                               "drag_rotational", "gravity", "arm_length",
                                               "rotor_drag_factor")},
        "thrust_to_weight": Field(F, "-", "4 F_max / (m1 g): sets the rotor limit F_max",
                                  lo=1.0, hi=20.0, lo_open=True),
        "motor_time_constant": Field(F, "s", "first-order lag of each rotor force", lo=1e-3,
                                     hi=1.0),
        "gear_height": Field(F, "m", "landing gear's lowest point below the centre", lo=0.0,
                             hi=10.0),
    },
    "vehicle": {k: SCHEMA["vehicle"][k] for k in ("m11", "m22", "m33", "d11", "d22", "d33",
                                                  "tau")},
    "deck": {
        "height": Field(F, "m", "altitude of the vehicle's reference point (the centre of roll "
                        "and pitch) at zero heave", lo=-1e4, hi=1e4),
        "pad_offset": Field(F, "m", "pad centre from the reference point, deck frame (x "
                            "forward, z up)", 3, lo=-1e3, hi=1e3),
        **_sines("heave", "m", "heave", 100.0),
        **_sines("roll", "deg", "roll", 45.0),
        **_sines("pitch", "deg", "pitch", 45.0),
    },
    "initial": {
        "position1": Field(F, "m", "quadrotor x1, y1 in E", 2, lo=-1e7, hi=1e7),
        "z1": Field(F, "m", "quadrotor altitude in E", lo=-1e4, hi=1e4),
        "eta1_deg": Field(F, "deg", "roll, pitch, yaw", 3, lo=-3600.0, hi=3600.0,
                          check=_tilt_within(60.0)),
        "omega1_deg_s": SCHEMA["initial"]["omega1_deg_s"],
        "relative_velocity": Field(F, "m/s", "quadrotor velocity in E minus the pad's "
                                   "(0: moving with the pad)", 3, lo=-1e3, hi=1e3),
        "position2": SCHEMA["initial"]["position2"],
        "psi2_deg": SCHEMA["initial"]["psi2_deg"],
        "r2_deg_s": SCHEMA["initial"]["r2_deg_s"],
        "velocity2": SCHEMA["initial"]["velocity2"],
    },
    "controller": {
        "k1p": Field(F, "1/s", "outer k1: deck-frame x, y, z", 3, hi=1e3, **_POS),
        "k2p": Field(F, "1/s", "outer k2: deck-frame x, y, z", 3, hi=1e3, **_POS),
        "k1": Field(F, "1/s", "inner k1: roll, pitch, yaw", 3, hi=1e3, **_POS),
        "k2": Field(F, "1/s", "inner k2: roll, pitch, yaw", 3, hi=1e3, **_POS),
        **{k: SCHEMA["controller"][k] for k in ("gamma1", "gamma2", "k_w", "k_zeta", "rho",
                                                "nominal_model")},
        "filter_frequency": Field(F, "rad/s", "command filter w_f", hi=1e4, **_POS),
        "filter_damping": Field(F, "-", "command filter zeta_f", hi=10.0, **_POS),
        "tilt_max_deg": Field(F, "deg", "largest tilt the outer loop commands", lo=1.0,
                              hi=80.0),
        "rate_hz": Field(F, "Hz", "control rate of the sampled step", lo=1.0,
                         hi=MAX_RATE_HZ),
        "backend": SCHEMA["controller"]["backend"],
    },
    "rbf": SCHEMA["rbf"],
    "landing": {
        "hover_height": Field(F, "m", "hover point: the centre's height above the pad",
                              hi=1e3, **_POS),
        "align_radius": Field(F, "m", "distance to the hover point that ends the approach",
                              hi=1e3, **_POS),
        "dwell_time": Field(F, "s", "time the align criteria must hold", lo=0.0, hi=1e3),
        "descent_speed": Field(F, "m/s", "largest descent rate", hi=100.0, **_POS),
        "descent_time": Field(F, "s", "descent rate = height above touchdown / descent_time",
                              hi=1e3, **_POS),
        "touchdown_speed": Field(F, "m/s", "descent rate of the final crawl", hi=100.0,
                                 **_POS),
        "max_deck_rise": Field(F, "m/s", "a faster rising deck aborts the descent", hi=100.0,
                               **_POS),
        "max_sink_rate": Field(F, "m/s", "limit: relative vertical speed at contact", hi=100.0,
                               **_POS),
        "max_offset": Field(F, "m", "limit: horizontal distance from the pad centre",
                            hi=100.0, **_POS),
        "max_tilt_deg": Field(F, "deg", "limit: body z axis from the deck normal", hi=90.0,
                              **_POS),
        "max_relative_speed": Field(F, "m/s", "limit: horizontal relative speed at contact",
                                    hi=100.0, **_POS),
        "settle_time": Field(F, "s", "the run ends this long after touchdown", lo=0.0,
                             hi=1e3),
    },
    "disturbance": SCHEMA["disturbance"],
    "wind": {
        "mean": Field(F, "m/s", "steady wind in E", 3, lo=-100.0, hi=100.0),
        "turbulence_w20": Field(F, "m/s", "Dryden turbulence: wind speed at 20 ft (0: none)",
                                lo=0.0, hi=50.0),
        "gust_amplitude": Field(F, "m/s", "1-cosine gust peak v_m (0: none)", lo=0.0,
                                hi=100.0),
        "gust_start": Field(F, "s", "gust start t0", lo=0.0, hi=MAX_DURATION_S),
        "gust_half_length": Field(F, "s", "gust build-up time d", hi=1e3, **_POS),
        "gust_direction": Field(F, "-", "gust direction in E (normalized)", 3, lo=-1.0,
                                hi=1.0),
    },
})
del F, I, B, S

#: The schema of each model.
SCHEMAS: Mapping[str, Mapping[str, Mapping[str, Field]]] = MappingProxyType(
    {"paper": SCHEMA, "landing": LANDING_SCHEMA})


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
    campaign_table : dict or None
        The file's ``[campaign]`` table as written (``--set campaign.KEY``
        applied), not validated here: :func:`quadland.simulate`, margins and
        codegen ignore it, and ``quadland campaign`` validates it against
        the scenario (:func:`quadland.campaign.campaign_spec_of`).
    """

    name: str
    source: str
    data: Mapping[str, Mapping[str, Any]]
    overrides: tuple[str, ...] = ()
    campaign_table: dict | None = None

    def __getitem__(self, dotted: str):
        section, key = dotted.split(".", 1)
        return self.data[section][key]

    @property
    def model(self) -> str:
        """The loop it selects: ``"paper"`` (the 4-DOF loop) or ``"landing"`` (6-DOF)."""
        return self.data["scenario"].get("model", "paper")

    def to_dict(self) -> dict:
        """Plain nested dict (lists, not tuples) for JSON output."""
        return {s: {k: list(v) if isinstance(v, tuple) else v for k, v in kv.items()}
                for s, kv in self.data.items()}

    def to_toml(self) -> str:
        """The resolved scenario as TOML: loading it gives the same scenario, bit for bit.

        Floats are written with Python's shortest round-trip ``repr``; every
        key is written, overrides included, so that the file alone repeats
        the run.

        Examples
        --------
        >>> sc = load_scenario("paper", ["simulation.duration=0.1"])
        >>> import tomllib
        >>> tomllib.loads(sc.to_toml())["simulation"]["duration"]
        0.1
        """
        head = (f"Scenario {self.name}, resolved by quadland from {Path(self.source).name}"
                + (f" with {', '.join(self.overrides)}" if self.overrides else ""))
        # a comment holds printable text only (a file name may hold anything)
        head = "".join(c if c.isprintable() else "?" for c in " ".join(head.split()))
        lines = [f"# {head}", ""]
        for section, kv in self.data.items():
            lines.append(f"[{section}]")
            lines.extend(f"{key} = {toml_value(value)}" for key, value in kv.items())
            lines.append("")
        if self.campaign_table is not None:
            lines.append(_campaign_toml(self.campaign_table))
        return "\n".join(lines)

    def replace(self, **changes) -> Scenario:
        """A new validated scenario with ``{"section.key": value}`` changes."""
        raw = self.to_dict()
        for dotted, value in changes.items():
            section, key = _split_key(dotted)
            raw.setdefault(section, {})[key] = value
        data = _validate(raw, self.source, self.name)
        return Scenario(data["scenario"]["name"], self.source, data, self.overrides,
                        self.campaign_table)


def _campaign_toml(table: Mapping[str, Any]) -> str:
    """A ``[campaign]`` table as TOML: its values, then each sub-table as a section."""
    lines = ["[campaign]"]
    lines += [f"{_toml_key(k)} = {toml_value(v)}" for k, v in table.items()
              if not isinstance(v, Mapping)]
    for name, sub in table.items():
        if isinstance(sub, Mapping):
            lines += ["", f"[campaign.{_toml_key(name)}]"]
            lines += [f"{_toml_key(k)} = {toml_value(v)}" for k, v in sub.items()]
    return "\n".join(lines) + "\n"


def _toml_key(key) -> str:
    """A TOML key: bare when it can be, else a quoted string."""
    key = str(key)
    return key if re.fullmatch(r"[A-Za-z0-9_-]+", key) else _toml_string(key)


def _toml_string(text: str) -> str:
    """A TOML basic string: printable characters as they are, the rest escaped."""
    out = []
    for c in text:
        if c in '"\\':
            out.append("\\" + c)
        elif c.isprintable():
            out.append(c)
        else:
            out.append(f"\\u{ord(c):04X}" if ord(c) < 0x10000 else f"\\U{ord(c):08X}")
    return '"' + "".join(out) + '"'


def toml_value(value) -> str:
    """A value as TOML text: floats as their shortest round trip, tables inline."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, str):
        return _toml_string(value)
    if isinstance(value, Mapping):
        return "{" + ", ".join(f"{_toml_key(k)} = {toml_value(v)}"
                               for k, v in value.items()) + "}"
    if isinstance(value, datetime.date | datetime.time):   # TOML's dates and times
        return value.isoformat()
    return "[" + ", ".join(toml_value(v) for v in value) + "]"


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
    raw = _parse_toml(_read_text(path), str(path))
    campaign = raw.pop("campaign", None)
    if campaign is not None and not isinstance(campaign, dict):
        raise ScenarioError(f"{path}: [campaign] must be a table")
    pairs = _parse_overrides(overrides)
    overridden = {}
    for dotted, value in pairs:
        section, key = _split_key(dotted)
        if section == "campaign":                   # campaign.runs, .seed, .sampling
            if campaign is None:
                raise ScenarioError(f"override {_show(dotted)}: {path} has no [campaign] table")
            campaign[key] = value
            continue
        if not any(section in schema for schema in SCHEMAS.values()):
            raise ScenarioError(f"override {_show(dotted)}: "
                                f"{_unknown('section', _show(section), _SECTIONS)}")
        known = {k for schema in SCHEMAS.values() for k in schema.get(section, {})}
        if key not in known:
            name = f"{section}.{_show(key)}"
            raise ScenarioError(f"override {_show(dotted)}: "
                                f"{_unknown('key', name, _dotted_all(section))}")
        raw.setdefault(section, {})
        if not isinstance(raw[section], dict):
            raise ScenarioError(f"{path}: [{section}] must be a table")
        raw[section][key] = value
        overridden[(section, key)] = dotted
    stem = re.sub(r"[^A-Za-z0-9._-]", "-", path.stem)
    data = _validate(raw, str(path), default_name=stem.lstrip(".-_")[:64] or "scenario",
                     overridden=overridden)
    return Scenario(data["scenario"]["name"], str(path), data,
                    tuple(f"{k}={_show(v)}" for k, v in pairs), _plain_copy(campaign))


def _plain_copy(value):
    """A deep copy of parsed TOML (dicts and lists), for a table kept as written."""
    if isinstance(value, Mapping):
        return {k: _plain_copy(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain_copy(v) for v in value]
    return value


#: Largest scenario file read, bytes.
MAX_FILE_BYTES = 1 << 20


def _read_text(path: Path) -> str:
    try:
        with open(path, "rb") as fh:
            data = fh.read(MAX_FILE_BYTES + 1)
    except OSError as exc:
        raise ScenarioError(f"{path}: cannot read: {exc.strerror or exc}") from None
    if len(data) > MAX_FILE_BYTES:
        raise ScenarioError(f"{path}: larger than {MAX_FILE_BYTES >> 20} MiB; not a scenario")
    try:
        return data.decode("utf-8-sig")             # a UTF-8 byte-order mark is accepted
    except UnicodeDecodeError as exc:
        line = data[:exc.start].count(b"\n") + 1
        raise ScenarioError(f"{path}: not UTF-8 text (byte 0x{data[exc.start]:02x} at line "
                            f"{line})") from None


_LOCATION_RE = re.compile(r"\s*\(at line (\d+), column (\d+)\)$")
_KEY_RE = re.compile(r"""\s*([A-Za-z0-9_\-."' ]+?)\s*=""")


def _parse_toml(text: str, source: str) -> dict:
    """``tomllib.loads`` with every failure as one line naming the cause."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        msg = str(exc)
        where = _LOCATION_RE.search(msg)
        cause = _LOCATION_RE.sub("", msg).rstrip(".")
        if where is None:
            raise ScenarioError(f"{source}: malformed TOML: {_show(cause, 80)}") from None
        line_no = int(where.group(1))
        lines = text.splitlines()
        line = lines[line_no - 1] if 0 < line_no <= len(lines) else ""
        if cause.startswith("Cannot overwrite a value") or cause.startswith("Cannot declare"):
            key = _KEY_RE.match(line)
            name = _duplicate_name(lines, line_no, key.group(1).strip() if key else line.strip())
            what = "section" if name.startswith("[") else "key"
            raise ScenarioError(f"{source}: duplicate {what} {_show(name)} (line {line_no})") \
                from None
        raise ScenarioError(f"{source}: malformed TOML at line {line_no}, column "
                            f"{where.group(2)}: {_show(cause, 80)}") from None
    except RecursionError:
        raise ScenarioError(f"{source}: malformed TOML: nested too deeply") from None
    except ValueError as exc:                       # e.g. an integer of over 4300 digits
        raise ScenarioError(f"{source}: malformed TOML: {_show(str(exc), 80)}") from None


def _duplicate_name(lines: list[str], line_no: int, key: str) -> str:
    """``section.key`` of a duplicated key, from the nearest table header above it."""
    if key.startswith("["):
        return key
    for line in reversed(lines[:line_no - 1]):
        head = line.strip()
        if head.startswith("[") and "]" in head:
            return f"{head[1:head.index(']')].strip()}.{key}"
    return key


def _show(value, limit: int = 40) -> str:
    """A value as one short line for an error message."""
    text = value if isinstance(value, str) else repr(value)
    text = " ".join(text.split())
    return text if len(text) <= limit else text[:limit - 3] + "..."


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
    section, dot, key = str(dotted).partition(".")
    if not dot or not section or not key:
        raise ScenarioError(f"override {_show(str(dotted))}: expected section.key=value")
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
            raise ScenarioError(f"override {_show(str(item))}: expected section.key=value")
        dotted, text = dotted.strip(), text.strip()
        try:
            value = tomllib.loads(f"v = {text}")["v"]
        except (tomllib.TOMLDecodeError, ValueError):
            value = text
        except RecursionError:
            raise ScenarioError(f"override {_show(dotted)}: value nested too deeply") from None
        pairs.append((dotted, value))
    return pairs


def _unknown(what: str, name: str, known: Iterable[str]) -> str:
    hint = difflib.get_close_matches(name, list(known), n=1)
    return f"unknown {what} '{name}'" + (f" (did you mean '{hint[0]}'?)" if hint else "")


def _model(raw: Mapping) -> str:
    """``scenario.model`` of a raw scenario, checked; "paper" when absent."""
    table = raw.get("scenario", {})
    model = table.get("model", "paper") if isinstance(table, Mapping) else "paper"
    if model not in MODELS:
        raise ScenarioError(f"scenario.model: must be one of {', '.join(MODELS)}, "
                            f"got {_show(model)}")
    return model


def _validate(raw: Mapping, source: str, default_name: str = "scenario",
              overridden: Mapping[tuple[str, str], str] | None = None) -> dict:
    """Check every section and key of ``raw`` against its model's schema; fill nothing but
    the name (and, for the paper's, leave ``scenario.model`` out: it is the default).

    ``overridden`` maps ``(section, key)`` to the ``--set`` text that put it
    there: a key of another model's schema is blamed on that override, not
    on the file."""
    model = _model(raw)
    schema = SCHEMAS[model]
    overridden = overridden or {}
    if model == "paper" and isinstance(raw.get("scenario"), Mapping):
        raw = {**raw, "scenario": {k: v for k, v in raw["scenario"].items() if k != "model"}}
    out: dict[str, dict] = {}
    for section, table in raw.items():
        if section not in schema:
            given = [d for (s, _), d in overridden.items() if s == section]
            where = f"override {_show(given[0])}" if given else source
            raise ScenarioError(f"{where}: {_unknown('section', _show(section), schema)}"
                                + _other_model(section, model))
        if not isinstance(table, Mapping):
            raise ScenarioError(f"{source}: [{section}] must be a table")
        for key in table:
            if key not in schema[section]:
                dotted = f"{section}.{_show(key)}"
                where = f"override {_show(overridden[section, key])}" \
                    if (section, key) in overridden else source
                raise ScenarioError(f"{where}: {_unknown('key', dotted, _dotted(section, model))}"
                                    + _other_model(section, model, key))
    for section, fields in schema.items():
        table = raw.get(section, {})
        out[section] = {}
        for key, field in fields.items():
            dotted = f"{section}.{key}"
            if key not in table:
                if section == "scenario":
                    out[section][key] = "" if key == "description" else default_name
                    continue
                raise ScenarioError(f"{source}: missing key {dotted} ({field.doc}, {field.unit})")
            out[section][key] = _check_value(dotted, table[key], field)
    nodes = out["rbf"]
    if nodes["center_max"] < nodes["center_min"]:
        raise ScenarioError("rbf.center_max: must be >= rbf.center_min")
    if model == "landing":
        _check_landing(out)
        return out
    q = out["quadrotor"]
    if q["rotor_force_max"] <= q["rotor_force_min"]:
        raise ScenarioError("quadrotor.rotor_force_max: must be > quadrotor.rotor_force_min")
    if out["simulation"]["integrator"] == "cvodes" and out["controller"]["rate_hz"] > 0:
        raise ScenarioError("simulation.integrator: cvodes integrates the continuous loop only "
                            "(controller.rate_hz = 0); the sampled-data loop takes RK4 steps "
                            "(raise simulation.rk_steps_per_interval for accuracy)")
    return out


def _check_landing(data: dict) -> None:
    """The landing schema's cross-key rules."""
    deck = data["deck"]
    for name in ("heave", "roll", "pitch"):
        keys = [k for k in deck if k.startswith(f"{name}_")]
        if len({len(deck[k]) for k in keys}) != 1:
            raise ScenarioError(f"deck.{keys[1]}: must have as many values as deck.{keys[0]}")
    wind = data["wind"]
    if wind["gust_amplitude"] > 0 and not any(wind["gust_direction"]):
        raise ScenarioError("wind.gust_direction: must not be all zero when "
                            "wind.gust_amplitude > 0")
    guidance = data["landing"]
    if guidance["touchdown_speed"] > guidance["descent_speed"]:
        raise ScenarioError("landing.touchdown_speed: must be <= landing.descent_speed")
    if guidance["hover_height"] <= data["quadrotor"]["gear_height"]:
        raise ScenarioError("landing.hover_height: must be above quadrotor.gear_height")


#: Every section of every schema.
_SECTIONS = tuple(dict.fromkeys(s for schema in SCHEMAS.values() for s in schema))


def _other_model(section: str, model: str, key: str | None = None) -> str:
    """A hint when the section or key belongs to another model's schema."""
    for other, schema in SCHEMAS.items():
        if other != model and section in schema and (key is None or key in schema[section]):
            return f" (a key of scenario.model = \"{other}\")" if key else \
                f" (a section of scenario.model = \"{other}\")"
    return ""


def _dotted_all(section: str) -> list[str]:
    """``section.key`` of every model's schema (for did-you-mean)."""
    return sorted({f"{section}.{k}" for schema in SCHEMAS.values()
                   for k in schema.get(section, {})})


def _dotted(section: str, model: str = "paper") -> list[str]:
    return [f"{section}.{k}" for k in SCHEMAS[model][section]]


def require_model(scenario: Scenario, model: str, what: str) -> None:
    """Refuse, in one line, a scenario of another model than ``what`` handles."""
    if scenario.model != model:
        raise ScenarioError(f"scenario.model: {what} handles scenario.model = \"{model}\" "
                            f"only, got \"{scenario.model}\"")


def _type_name(kind: type) -> str:
    return {float: "a number", int: "an integer", bool: "true or false", str: "a string"}[kind]


def _check_scalar(dotted: str, value, field: Field):
    kind = field.kind
    if kind is bool:
        if not isinstance(value, bool | np.bool_):
            raise ScenarioError(f"{dotted}: expected true or false, got {_show(value)}")
        return bool(value)
    if kind is str:
        if not isinstance(value, str):
            raise ScenarioError(f"{dotted}: expected a string, got {_show(value)}")
        if field.choices and value not in field.choices:
            raise ScenarioError(f"{dotted}: must be one of {', '.join(field.choices)}, "
                                f"got {_show(value)}")
        return value
    if isinstance(value, bool | np.bool_) or not isinstance(value, numbers.Real):
        raise ScenarioError(f"{dotted}: expected {_type_name(kind)}, got {_show(value)}")
    if kind is int and isinstance(value, numbers.Integral):
        value = int(value)                          # exact, however many digits
        complaint = field.complaint(value)
        if complaint:
            raise ScenarioError(f"{dotted}: {complaint}, got {_show(value)}")
        return value
    try:
        number = float(value)
    except OverflowError:
        number = math.inf
    if not math.isfinite(number):
        raise ScenarioError(f"{dotted}: must be finite and {field.range_text() or 'finite'}, "
                            f"got {_show(value)}")
    if kind is int:
        if not float(number).is_integer():
            raise ScenarioError(f"{dotted}: expected an integer, got {_show(value)}")
        value = int(value)
    complaint = field.complaint(value if kind is int else number)
    if complaint:
        raise ScenarioError(f"{dotted}: {complaint}, got {_show(value)}")
    return value if kind is int else number


def _check_value(dotted: str, value, field: Field):
    if field.length is None:
        if isinstance(value, list | tuple | dict):
            raise ScenarioError(f"{dotted}: expected {_type_name(field.kind)}, "
                                f"got {_show(value)}")
        checked = _check_scalar(dotted, value, field)
    else:
        shortest = field.length if field.min_length is None else field.min_length
        if not isinstance(value, list | tuple) or not shortest <= len(value) <= field.length:
            count = field.length if shortest == field.length else \
                f"{shortest} to {field.length}"
            raise ScenarioError(f"{dotted}: expected a list of {count} numbers "
                                f"({field.unit}), got {_show(value)}")
        checked = tuple(_check_scalar(dotted, v, field) for v in value)
    if field.check is not None:
        complaint = field.check(checked)
        if complaint:
            raise ScenarioError(f"{dotted}: {complaint}, got {_show(value)}")
    return checked
