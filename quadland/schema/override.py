"""An override's key (``--set section.key=value``) checked against the schemas.

A key of the scenario's own model is accepted without reading any other
model's schema (:func:`own_key`): loading a paper scenario with overrides does
not import the landing's. Any other key is checked against every model's
schema (:func:`check_override_key`), as before: a key of another model passes
here and is refused, with its model named, when the scenario is validated.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from quadland.exceptions import ScenarioError
from quadland.schema import DEFAULT_MODEL, MODELS, SCHEMAS, did_you_mean, sections, show

__all__ = ["own_key", "check_override_key", "unknown_name", "dotted_all"]


def unknown_name(what: str, name: str, known: Iterable[str]) -> str:
    """``unknown key 'a.b'``, with the closest of ``known`` suggested if one is close."""
    hint = did_you_mean(name, known)
    return f"unknown {what} '{show(name)}'" + (f" (did you mean '{hint}'?)" if hint else "")


def dotted_all(section: str) -> list[str]:
    """``section.key`` of every model's schema (for did-you-mean)."""
    return sorted({f"{section}.{k}" for schema in SCHEMAS.values()
                   for k in schema.get(section, {})})


def own_key(raw: Mapping, section: str, key: str) -> bool:
    """Whether ``section.key`` is a key of the schema of the model ``raw`` names so far
    (``scenario.model``, the default model's when absent), reading no other schema."""
    table = raw.get("scenario", {})
    model = table.get("model", DEFAULT_MODEL) if isinstance(table, Mapping) else DEFAULT_MODEL
    return model in MODELS and key in SCHEMAS[model].get(section, {})


def check_override_key(dotted: str, section: str, key: str) -> None:
    """Refuse an override whose section or key no model's schema has.

    Raises
    ------
    ScenarioError
        ``override 'a.b': unknown section 'a' (did you mean ...)`` or ``unknown key``.
    """
    if not any(section in schema for schema in SCHEMAS.values()):
        raise ScenarioError(f"override {show(dotted)}: "
                            f"{unknown_name('section', section, sections())}")
    known = {k for schema in SCHEMAS.values() for k in schema.get(section, {})}
    if key not in known:                        # a dot left in it: a sub-section's
        raise ScenarioError(f"override {show(dotted)}: " + (
            unknown_name("section", f"{section}.{key.rpartition('.')[0]}", sections())
            if "." in key else unknown_name("key", f"{section}.{key}", dotted_all(section))))
