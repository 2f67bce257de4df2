"""The scenario schemas: every section and key of each loop kind's scenarios.

Data only, at the bottom of the runtime: the loader (:mod:`quadland.scenario`)
and the campaign table's checks read it; each loop kind
(:mod:`quadland.kinds`) names its schema. A new kind adds its module here
and one line to :data:`SCHEMAS` and :data:`CROSS_CHECKS`.
"""

from __future__ import annotations

import difflib
import functools
import importlib
from collections.abc import Callable, Iterable, Mapping
from types import MappingProxyType

from quadland.schema.by_model import ByModel
from quadland.schema.fields import (
    MAX_DURATION_S,
    MAX_RATE_HZ,
    Field,
    check_value,
    show,
)
from quadland.schema.paper import PAPER_SCHEMA

__all__ = ["Field", "check_value", "show", "MAX_RATE_HZ", "MAX_DURATION_S", "PAPER_SCHEMA",
           "LANDING_SCHEMA", "SCHEMAS", "CROSS_CHECKS", "MODELS", "DEFAULT_MODEL",
           "SHARED_KEYS", "CAMPAIGN_KEYS", "SECTIONS", "sections", "split_dotted", "nest_sections",
           "did_you_mean"]

#: Names this package loads on first use: the landing's schema imports the landing's
#: symbolic modules, which a paper scenario does not need (:mod:`quadland.schema.by_model`).
_LAZY = {"LANDING_SCHEMA": "quadland.schema.landing"}

#: The schema of each model (``scenario.model``; "paper" when absent), each loaded
#: when first read.
SCHEMAS: Mapping[str, Mapping[str, Mapping[str, Field]]] = ByModel(
    {"paper": ("quadland.schema.paper", "PAPER_SCHEMA"),
     "landing": ("quadland.schema.landing", "LANDING_SCHEMA")})

#: Each model's rules across keys, run after every key passed its own check.
CROSS_CHECKS: Mapping[str, Callable[[dict], None]] = ByModel(
    {"paper": ("quadland.schema.paper", "check_paper"),
     "landing": ("quadland.schema.landing", "check_landing")})

#: The models a scenario may select with ``scenario.model``.
MODELS = tuple(SCHEMAS)

#: The model of a scenario that names none (the paper's, as quadland began).
DEFAULT_MODEL = "paper"

#: The keys every kind's schema holds, with the same meaning: the engine (the
#: resource plan, the envelope's step hints, the disturbance samples), the run's
#: provenance and the margin review read them whatever the kind. A new kind's
#: schema holds them too (``tests/test_architecture.py`` checks it); a kind
#: without a network or a sampled controller says so with ``rbf.nodes`` and
#: ``controller.rate_hz = 0`` where its schema allows.
SHARED_KEYS = (
    "simulation.duration", "simulation.output_rate_hz", "simulation.rk_steps_per_interval",
    "simulation.seed", "controller.rate_hz", "rbf.nodes", "disturbance.noise",
    "disturbance.sample_rate_hz", "disturbance.force_bias", "disturbance.force_amplitude",
    "disturbance.force_frequency", "disturbance.force_noise_std", "disturbance.moment_bias",
    "disturbance.moment_amplitude", "disturbance.moment_frequency",
    "disturbance.moment_noise_std",
)

#: The top-level keys of a scenario's ``[campaign]`` table and what each holds:
#: the only ``campaign.*`` keys an override (``--set``) may give.
CAMPAIGN_KEYS: Mapping[str, str] = MappingProxyType({
    "runs": "number of runs", "seed": "campaign seed", "sampling": "random, sobol or lhs",
    "dispersions": "table of dispersed keys", "limits": "table of metric upper limits"})



def __getattr__(name):
    if name in _LAZY:
        value = globals()[name] = getattr(importlib.import_module(_LAZY[name]), name)
        return value
    if name == "SECTIONS":
        return sections()
    raise AttributeError(f"module 'quadland.schema' has no attribute {name!r}")


@functools.cache
def sections() -> tuple[str, ...]:
    """Every section of every schema (:data:`SECTIONS`, every schema loaded).

    A section's name may hold a dot (``sensors.vision``, TOML's
    ``[sensors.vision]``, a table inside ``[sensors]``).
    """
    return tuple(dict.fromkeys(s for schema in SCHEMAS.values() for s in schema))


def split_dotted(dotted: str) -> tuple[str, str]:
    """``(section, key)`` of a dotted key name: the longest known section that prefixes it
    (``sensors.vision.latency`` is ``sensors.vision``'s ``latency``), else the part before
    the first dot."""
    head, dot, tail = dotted.rpartition(".")
    if dot and "." in head and head in sections():
        return head, tail
    section, _, key = dotted.partition(".")
    return section, key


def nest_sections(raw: dict) -> dict:
    """Parsed TOML with each dotted section's table (``raw["sensors"]["vision"]``) moved to
    its own name (``raw["sensors.vision"]``); other entries as they are."""
    out = dict(raw)
    # a table in a table is looked up in every schema's sections; [campaign]'s are the
    # campaign's own (no schema has a campaign section): a paper scenario without one
    # reads no other model's schema
    if not any(isinstance(v, dict) for name, table in raw.items()
               if name != "campaign" and isinstance(table, dict) for v in table.values()):
        return out
    for section in sections():
        parent, dot, child = section.rpartition(".")
        table = out.get(parent)
        if dot and isinstance(table, dict) and isinstance(table.get(child), dict):
            table = dict(table)
            out[section] = table.pop(child)
            out[parent] = table
    return out


def did_you_mean(name: str, known: Iterable[str]) -> str | None:
    """The dotted name of ``known`` closest to ``name``, or None.

    Matched part by part: each dot-separated part of ``name`` against the parts that
    can follow those already matched (itself when it is one, else difflib's closest at
    a ratio of 0.6 or more), so that a shared section does not make every key of it look
    close: ``quadrotor.xyz`` suggests nothing, ``sensors.visoin.latency``
    ``sensors.vision.latency``.

    Examples
    --------
    >>> did_you_mean("sensors.visoin", ["sensors", "sensors.vision", "sensors.imu"])
    'sensors.vision'
    >>> did_you_mean("quadrotor.xyz", ["quadrotor.mass", "quadrotor.inertia"]) is None
    True
    """
    split = [str(k).split(".") for k in known]
    done: list[str] = []
    for part in str(name).split("."):
        n = len(done)
        after = list(dict.fromkeys(k[n] for k in split if len(k) > n and k[:n] == done))
        match = part if part in after else next(
            iter(difflib.get_close_matches(part, after, n=1)), None)
        if match is None:
            return None
        done.append(match)
    return ".".join(done) if done in split else None
