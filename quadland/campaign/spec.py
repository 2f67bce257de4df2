"""A scenario's ``[campaign]`` table: runs, seed, sampling, dispersions, limits.

A loaded scenario keeps the table as written (``Scenario.campaign_table``);
only a campaign validates it (:func:`campaign_spec_of`, which
:func:`quadland.campaign.run_campaign` calls), so that ``quadland simulate``
and the other commands are never refused for a table they ignore. It is
checked against the scenario it belongs to: every dispersion names a key of
the model's schema, its parameters have the key's shape, every draw is a
finite number, and a bounded distribution cannot draw a value outside the
key's physical range. The result is a frozen :class:`CampaignSpec` of
:class:`Dispersion` objects; docs/campaign.md describes the table.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import numbers
from collections.abc import Mapping
from types import MappingProxyType
from typing import Any

from quadland.campaign.draws import U_EDGE, apply_mode, check_finite, check_reach, where
from quadland.exceptions import ScenarioError
from quadland.kinds import KINDS
from quadland.schema import (
    CAMPAIGN_KEYS,
    SCHEMAS,
    check_value,
    did_you_mean,
    show,
    split_dotted,
)

__all__ = ["Dispersion", "Target", "CampaignSpec", "campaign_spec", "campaign_spec_of",
           "apply_mode", "DISTRIBUTIONS", "MODES", "SAMPLINGS", "MAX_RUNS", "U_EDGE"]

#: Each distribution's required and optional parameters.
DISTRIBUTIONS: Mapping[str, tuple[tuple[str, ...], tuple[str, ...]]] = MappingProxyType({
    "uniform": (("low", "high"), ("mode", "common", "also")),
    "normal": (("std",), ("mean", "mode", "common", "also")),
    "truncnorm": (("std",), ("mean", "low", "high", "mode", "common", "also")),
    "choice": (("values",), ("weights",)),
    "seed": ((), ()),
})
#: How a numeric draw ``X`` becomes a value: ``nominal + X``, ``nominal (1 + X)``, ``X``.
MODES = ("offset", "relative", "absolute")
#: Ways of placing the runs in the unit cube (``scipy.stats.qmc`` for the last two).
SAMPLINGS = ("random", "sobol", "lhs")
#: Most runs one campaign may ask for.
MAX_RUNS = 1_000_000
_SEED_MAX = 2 ** 63 - 1
_TOP = CAMPAIGN_KEYS


@dataclasses.dataclass(frozen=True)
class Target:
    """One scenario key a dispersion sets.

    Attributes
    ----------
    key : str
        ``section.key``.
    nominal : tuple of float
        The scenario's value, one entry per element (one for a scalar).
    scalar : bool
        The key holds one number, not a list.
    """

    key: str
    nominal: tuple[float, ...]
    scalar: bool

    def columns(self) -> tuple[str, ...]:
        """Its columns of runs.csv: ``key`` or ``key[0]``, ``key[1]``, ..."""
        if self.scalar:
            return (self.key,)
        return tuple(f"{self.key}[{i}]" for i in range(len(self.nominal)))


@dataclasses.dataclass(frozen=True)
class Dispersion:
    """How one scenario key (and the keys of ``also``) varies from run to run.

    A numeric draw ``X`` per dimension (``uniform`` on ``[low, high]``,
    ``normal(mean, std)``, ``truncnorm``: the normal cut to ``[low, high]``)
    sets each element by ``mode``: ``offset`` ``nominal + X``, ``relative``
    ``nominal (1 + X)``, ``absolute`` ``X``. A list key draws one ``X`` per
    element, or one for all with ``common``. ``choice`` picks one of
    ``values`` (with ``weights``); ``seed`` sets the key to the run's seed.

    Attributes
    ----------
    key : str
    distribution : str
        One of :data:`DISTRIBUTIONS`.
    targets : tuple of Target
        The key, then the keys of ``also`` (which take the same ``X``).
    mode : str
    low, high, mean, std : tuple of float or None
        Per dimension; ``low``/``high`` may hold infinities (``truncnorm``
        without that bound).
    values : tuple
        ``choice``: the candidate values.
    weights : tuple of float or None
        ``choice``: relative probabilities (equal when None).
    common : bool
    table : mapping
        The entry as written (for ``scenario.toml`` and the campaign's identity).
    """

    key: str
    distribution: str
    targets: tuple[Target, ...]
    mode: str = "offset"
    low: tuple[float, ...] | None = None
    high: tuple[float, ...] | None = None
    mean: tuple[float, ...] | None = None
    std: tuple[float, ...] | None = None
    values: tuple = ()
    weights: tuple[float, ...] | None = None
    common: bool = False
    table: Mapping[str, Any] = dataclasses.field(default_factory=dict)

    @property
    def dims(self) -> int:
        """Dimensions of the unit cube it takes: 0 (seed), 1 or one per element."""
        if self.distribution == "seed":
            return 0
        if self.distribution == "choice" or self.common or self.targets[0].scalar:
            return 1
        return len(self.targets[0].nominal)

    def columns(self) -> tuple[str, ...]:
        """Its columns of runs.csv."""
        if self.distribution in ("choice", "seed"):
            return (self.key,)
        return tuple(c for t in self.targets for c in t.columns())


@dataclasses.dataclass(frozen=True)
class CampaignSpec:
    """A validated ``[campaign]`` table.

    Attributes
    ----------
    runs : int
        Runs of the campaign (``--runs`` overrides).
    seed : int
        The campaign seed: every run's draws derive from it and the run's index.
    sampling : str
        ``random`` (each run's own generator), ``sobol`` or ``lhs``
        (space-filling over all runs).
    dispersions : tuple of Dispersion
    limits : mapping of str to float
        Upper limits on metrics (the loop kind's ``metrics``), on top of
        a landing's own limits.
    table : mapping
        The table as written, normalized (for ``scenario.toml``).
    """

    runs: int
    seed: int
    sampling: str
    dispersions: tuple[Dispersion, ...]
    limits: Mapping[str, float]
    table: Mapping[str, Any]

    @property
    def dims(self) -> int:
        """Dimensions of the unit cube the sampling fills."""
        return sum(d.dims for d in self.dispersions)

    def columns(self) -> tuple[str, ...]:
        """The dispersed columns of runs.csv, in table order."""
        return tuple(c for d in self.dispersions for c in d.columns())

    def identity(self) -> dict:
        """What must not change for a campaign folder to be resumed (all but ``runs``)."""
        return {k: v for k, v in _plain(self.table).items() if k != "runs"}

def _plain(x):
    if isinstance(x, Mapping):
        return {k: _plain(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_plain(v) for v in x]
    return x


def _number(where: str, value, integer: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ScenarioError(f"{where}: expected {'an integer' if integer else 'a number'}, "
                            f"got {_show(value)}")
    if integer:
        if not isinstance(value, numbers.Integral):
            raise ScenarioError(f"{where}: expected an integer, got {_show(value)}")
        return int(value)
    try:
        number = float(value)
    except OverflowError:
        number = math.inf
    if not math.isfinite(number):
        raise ScenarioError(f"{where}: must be finite, got {_show(value)}")
    return number


def _show(value) -> str:
    return show(value)


def campaign_spec_of(scenario) -> CampaignSpec:
    """The validated ``[campaign]`` table of a loaded scenario.

    Parameters
    ----------
    scenario : Scenario

    Returns
    -------
    CampaignSpec

    Raises
    ------
    CampaignError
        The scenario has no ``[campaign]`` table.
    ScenarioError
        One line naming the entry at fault.
    """
    from quadland.exceptions import CampaignError
    from quadland.scenario import SCENARIO_DIR

    if scenario.campaign_table is None:
        raise CampaignError(f"scenario: {scenario.name} has no [campaign] table (the "
                            f"shipped {SCENARIO_DIR / 'highway.toml'} has one)")
    return campaign_spec(scenario.campaign_table, scenario.data, scenario.model,
                         scenario.source)


def campaign_spec(table, data: Mapping[str, Mapping[str, Any]], model: str,
                  source: str = "campaign") -> CampaignSpec:
    """Validate a ``[campaign]`` table against its scenario.

    Parameters
    ----------
    table : mapping
        The raw table, as TOML gives it.
    data : mapping
        The validated scenario (``Scenario.data``): the nominal values.
    model : str
        ``scenario.model``: its schema names the keys that may be dispersed.
    source : str
        The file, for messages about the table's shape.

    Returns
    -------
    CampaignSpec

    Raises
    ------
    ScenarioError
        One line naming the entry at fault.
    """

    if not isinstance(table, Mapping):
        raise ScenarioError(f"{source}: [campaign] must be a table")
    for key in table:
        if key not in _TOP:
            hint = difflib.get_close_matches(str(key), list(_TOP), n=1)
            raise ScenarioError(f"{source}: unknown key campaign.{_show(key)}"
                                + (f" (did you mean 'campaign.{hint[0]}'?)" if hint else ""))
    for key in ("runs", "seed", "dispersions"):
        if key not in table:
            raise ScenarioError(f"{source}: missing key campaign.{key} ({_TOP[key]})")
    runs = _number("campaign.runs", table["runs"], integer=True)
    if not 1 <= runs <= MAX_RUNS:
        raise ScenarioError(f"campaign.runs: must be in [1, {MAX_RUNS}], got {_show(runs)}")
    seed = _number("campaign.seed", table["seed"], integer=True)
    if not 0 <= seed <= _SEED_MAX:
        raise ScenarioError(f"campaign.seed: must be in [0, 9.22337e+18], got {_show(seed)}")
    sampling = table.get("sampling", "random")
    if sampling not in SAMPLINGS:
        raise ScenarioError(f"campaign.sampling: must be one of {', '.join(SAMPLINGS)}, "
                            f"got {_show(sampling)}")
    entries = table["dispersions"]
    if not isinstance(entries, Mapping) or not entries:
        raise ScenarioError("campaign.dispersions: must be a table of at least one "
                            "\"section.key\" = {distribution = ...}")
    schema = SCHEMAS[model]
    dispersions, taken = [], set()
    for key, entry in entries.items():
        disp = _dispersion(str(key), entry, data, schema)
        for t in disp.targets:
            if t.key in taken:
                raise ScenarioError(f"{where(key)}: {t.key} is dispersed twice")
            taken.add(t.key)
        dispersions.append(disp)
    limits = table.get("limits", {})
    if not isinstance(limits, Mapping):
        raise ScenarioError("campaign.limits: must be a table of metric = upper limit")
    names = [m.name for m in KINDS[model].metrics]
    checked_limits = {}
    for name, value in limits.items():
        if name not in names:
            hint = difflib.get_close_matches(str(name), names, n=1)
            raise ScenarioError(f"campaign.limits: unknown metric '{_show(name)}'"
                                + (f" (did you mean '{hint[0]}'?)" if hint else
                                   f" (metrics: {', '.join(names)})"))
        checked_limits[name] = _number(f"campaign.limits.{name}", value)
        if not checked_limits[name] > 0:
            raise ScenarioError(f"campaign.limits.{name}: must be > 0, got {_show(value)}")
    normalized = {"runs": runs, "seed": seed, "sampling": sampling,
                  "dispersions": {d.key: d.table for d in dispersions}}
    if checked_limits:
        normalized["limits"] = dict(checked_limits)
    return CampaignSpec(runs, seed, sampling, tuple(dispersions), checked_limits, normalized)


def _field(key: str, schema, given_by: str | None = None) -> Any:
    """The schema's field of ``key``; ``given_by`` names the entry that gave it."""
    section, name = split_dotted(key)
    if not name or section not in schema or name not in schema[section] or section == "scenario":
        known = [f"{s}.{k}" for s in schema if s != "scenario" for k in schema[s]]
        hint = did_you_mean(key, known)
        what = f"{_show(key)} is not" if given_by else "not"
        raise ScenarioError(f"{given_by or where(key)}: {what} a key of this scenario's schema"
                            + (f" (did you mean '{hint}'?)" if hint else ""))
    return schema[section][name]


def _per_dim(where: str, value, dims: int) -> tuple[float, ...]:
    """A parameter as one number per dimension: a number, or a list of ``dims``."""
    if isinstance(value, list | tuple):
        if len(value) != dims:
            raise ScenarioError(f"{where}: expected a number or a list of {dims} numbers, "
                                f"got {_show(value)}")
        return tuple(_number(where, v) for v in value)
    return (_number(where, value),) * dims


def _dispersion(key: str, entry, data, schema) -> Dispersion:
    field = _field(key, schema)
    if not isinstance(entry, Mapping):
        raise ScenarioError(f"{where(key)}: must be a table {{distribution = ...}}")
    dist = entry.get("distribution")
    if not isinstance(dist, str) or dist not in DISTRIBUTIONS:
        raise ScenarioError(f"{where(key, 'distribution')}: must be one of "
                            f"{', '.join(DISTRIBUTIONS)}, got {_show(dist)}")
    required, optional = DISTRIBUTIONS[dist]
    for name in entry:
        if name != "distribution" and name not in required + optional:
            allowed = ", ".join(required + optional) or "nothing else"
            raise ScenarioError(f"{where(key)}: {dist} takes {allowed}; "
                                f"got {_show(name)}")
    for name in required:
        if name not in entry:
            raise ScenarioError(f"{where(key)}: {dist} needs {name}")
    section, name = split_dotted(key)
    nominal_value = data[section][name]
    table = {k: _plain(v) for k, v in entry.items()}
    if dist == "seed":
        if (field.kind is not int or field.length is not None or field.lo is None
                or field.lo > 0 or field.hi is None or field.hi < _SEED_MAX):
            raise ScenarioError(f"{where(key)}: a seed dispersion needs an integer key of "
                                "range [0, 2^63 - 1] (simulation.seed)")
        return Dispersion(key, dist, (Target(key, (), True),), table=table)
    if dist == "choice":
        return _choice(key, entry, field, table)
    if field.kind is not float:
        kind = {int: "integers", bool: "true or false", str: "text"}[field.kind]
        raise ScenarioError(f"{where(key)}: {dist} draws real numbers; {key} holds {kind} "
                            "(use distribution = \"choice\")")
    scalar = field.length is None
    main = Target(key, (nominal_value,) if scalar else tuple(nominal_value), scalar)
    mode = entry.get("mode", "offset")
    if mode not in MODES:
        raise ScenarioError(f"{where(key, 'mode')}: must be one of {', '.join(MODES)}, "
                            f"got {_show(mode)}")
    common = entry.get("common", False)
    if not isinstance(common, bool):
        raise ScenarioError(f"{where(key, 'common')}: expected true or false, "
                            f"got {_show(common)}")
    if common and scalar:
        raise ScenarioError(f"{where(key, 'common')}: {key} is a single number")
    targets = [main, *_also(key, entry.get("also", []), scalar or common, mode, data, schema)]
    dims = 1 if (scalar or common) else len(main.nominal)
    params = {p: _per_dim(where(key, p), entry[p], dims) if p in entry else None
              for p in ("low", "high", "mean", "std")}
    if params["std"] is not None and any(s < 0 for s in params["std"]):
        raise ScenarioError(f"{where(key, 'std')}: must be >= 0")
    if dist == "truncnorm" and params["low"] is None and params["high"] is None:
        raise ScenarioError(f"{where(key)}: truncnorm needs low, high or both (else use "
                            "normal)")
    if dist != "uniform":
        params["mean"] = params["mean"] or (0.0,) * dims
    if dist == "truncnorm":
        params["low"] = params["low"] or (-math.inf,) * dims
        params["high"] = params["high"] or (math.inf,) * dims
    if params["low"] is not None:
        for lo, hi in zip(params["low"], params["high"], strict=True):
            if not lo < hi:
                raise ScenarioError(f"{where(key, 'low')}: must be below high "
                                    f"({lo:g} >= {hi:g})")
    disp = Dispersion(key, dist, tuple(targets), mode, params["low"], params["high"],
                      params["mean"], params["std"], common=common, table=table)
    check_finite(disp)
    if dist in ("uniform", "truncnorm"):
        check_reach(disp, schema)
    return disp


def _also(key: str, also, one_draw: bool, mode: str, data, schema) -> list[Target]:
    """The targets of a dispersion's ``also``: keys that take the same offset or factor."""
    if not isinstance(also, list | tuple) or not all(isinstance(a, str) for a in also):
        raise ScenarioError(f"{where(key, 'also')}: expected a list of \"section.key\" names")
    if also and not one_draw:
        raise ScenarioError(f"{where(key, 'also')}: needs one draw for all: "
                            "a single-number key or common = true")
    if also and mode == "absolute":
        raise ScenarioError(f"{where(key, 'also')}: the other keys take the same offset or "
                            "factor; mode = \"absolute\" has none")
    targets = []
    for other in also:
        f = _field(other, schema, where(key, "also"))
        if f.kind is not float:
            raise ScenarioError(f"{where(key, 'also')}: {other} does not hold numbers")
        s, n = split_dotted(other)
        v = data[s][n]
        targets.append(Target(other, (v,) if f.length is None else tuple(v), f.length is None))
    return targets


def _choice(key: str, entry, field, table) -> Dispersion:

    values = entry["values"]
    if not isinstance(values, list | tuple) or not values:
        raise ScenarioError(f"{where(key, 'values')}: expected a non-empty list of values")
    checked = []
    for v in values:
        try:
            checked.append(check_value(key, v, field))
        except ScenarioError as exc:
            raise ScenarioError(f"{where(key, 'values')}: {exc}") from None
    weights = entry.get("weights")
    if weights is not None:
        weights = _per_dim(where(key, "weights"), weights, len(checked)) \
            if isinstance(weights, list | tuple) else None
        if weights is None or any(w < 0 for w in weights) or not sum(weights) > 0:
            raise ScenarioError(f"{where(key, 'weights')}: expected {len(checked)} numbers "
                                ">= 0, not all zero")
    return Dispersion(key, "choice", (Target(key, (), field.length is None),),
                      values=tuple(checked), weights=weights, table=table)


