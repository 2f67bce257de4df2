"""``extends``: a scenario file that gives only what differs from another.

A file whose top level says ``extends = "highway"`` (a shipped scenario's
name) or ``extends = "base.toml"`` (a path, relative to the file's folder)
starts from that scenario and replaces the keys it gives; a base may extend
another in turn. The result is one raw scenario that
:func:`quadland.scenario.load_scenario` validates as if it were written
whole, so ``scenario.toml`` in an output folder stays fully resolved.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path

from quadland.exceptions import ScenarioError
from quadland.schema import show

__all__ = ["EXTENDS_KEY", "NOT_INHERITED", "resolve_extends", "merge_scenarios"]

#: The top-level key naming a file's base.
EXTENDS_KEY = "extends"

#: ``(section, key)`` a base does not pass on: a scenario is named after its own file
#: unless it names itself, and a base's description is not the extending file's.
NOT_INHERITED = (("scenario", "name"), ("scenario", "description"))


def merge_scenarios(base: Mapping, child: Mapping) -> dict:
    """``child``'s sections over ``base``'s, key by key (a key's value replaced whole).

    A section of either that is not a table is kept as the file has it (the
    validation names it); ``[campaign]`` merges like a section.

    Examples
    --------
    >>> merge_scenarios({"a": {"x": 1, "y": 2}, "b": {"z": 3}}, {"a": {"y": 5}})
    {'a': {'x': 1, 'y': 5}, 'b': {'z': 3}}
    """
    out = {k: dict(v) if isinstance(v, Mapping) else v for k, v in base.items()}
    for section, table in child.items():
        if isinstance(table, Mapping) and isinstance(out.get(section), dict):
            out[section].update(table)
        else:
            out[section] = dict(table) if isinstance(table, Mapping) else table
    return out


def _looks_like_path(ref: str) -> bool:
    return ref.endswith(".toml") or "/" in ref or "\\" in ref


def _locate(ref, where: Path, resolve: Callable[[str], Path]) -> Path:
    """The file ``ref`` names, from the file ``where`` that extends it; one line if none."""
    if not isinstance(ref, str) or not ref.strip():
        raise ScenarioError(f"{where}: {EXTENDS_KEY} must be a shipped scenario's name or "
                            f"a file path (a string), got {show(ref)}")
    if _looks_like_path(ref):
        candidate = Path(ref).expanduser()
        candidate = candidate if candidate.is_absolute() else where.parent / candidate
        if not candidate.is_file():
            raise ScenarioError(f"{where}: {EXTENDS_KEY} '{show(ref)}': scenario file not found "
                                f"({candidate})")
        return candidate
    try:
        return resolve(ref)
    except ScenarioError as exc:
        raise ScenarioError(f"{where}: {EXTENDS_KEY}: {exc}") from None


def resolve_extends(path: Path, read: Callable[[Path], dict],
                    resolve: Callable[[str], Path]) -> dict:
    """The raw scenario of ``path`` with its chain of bases merged under it.

    Parameters
    ----------
    path : Path
        The scenario file.
    read : callable
        ``read(path)``: a file's parsed sections (``extends`` still in them).
    resolve : callable
        ``resolve(name)``: the file of a shipped scenario's name, or a
        :class:`~quadland.exceptions.ScenarioError`.

    Returns
    -------
    dict
        The sections, without ``extends``: each base's under the file that
        extends it (:func:`merge_scenarios`), less :data:`NOT_INHERITED`.

    Raises
    ------
    ScenarioError
        One line: an ``extends`` that is not a string, a base not found
        (an unknown name with the closest shipped one, a missing file), or a
        cycle (``a.toml -> b.toml -> a.toml``).
    """
    chain, layers = [path], [read(path)]
    seen = {path.resolve()}
    while EXTENDS_KEY in layers[-1]:
        base = _locate(layers[-1][EXTENDS_KEY], chain[-1], resolve)
        if base.resolve() in seen:
            names = " -> ".join(p.name for p in [*chain, base])
            raise ScenarioError(f"{path}: {EXTENDS_KEY} cycle: {names}")
        seen.add(base.resolve())
        chain.append(base)
        layers.append(read(base))
    merged: dict = {}
    for depth, layer in reversed(list(enumerate(layers))):
        layer = {k: v for k, v in layer.items() if k != EXTENDS_KEY}
        if depth:                                   # a base: what it does not pass on
            layer = {s: {k: v for k, v in t.items() if (s, k) not in NOT_INHERITED}
                     if isinstance(t, Mapping) else t for s, t in layer.items()}
        merged = merge_scenarios(merged, layer)
    return merged
