"""Scenario files: schema, loading, overrides and validation.

A scenario is a TOML file whose sections and keys are fixed by its model's schema
(:data:`quadland.schema.SCHEMAS`).
It is validated once, here; everything downstream trusts it. Its
``[campaign]`` table is kept as written (``Scenario.campaign_table``): only a
campaign validates it (``quadland.campaign``), the commands that ignore it
never refuse a scenario for its sake.
"""

from __future__ import annotations

import dataclasses
import datetime
import difflib
import re
import tomllib
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

from quadland.exceptions import ScenarioError
from quadland.extends import resolve_extends
from quadland.schema import (
    CAMPAIGN_KEYS,
    CROSS_CHECKS,
    DEFAULT_MODEL,
    MODELS,
    SCHEMAS,
    check_value,
    nest_sections,
    show,
    split_dotted,
)
from quadland.schema.override import check_override_key, own_key, unknown_name

__all__ = ["Scenario", "load_scenario", "scenario_names", "SCENARIO_DIR", "toml_value"]

#: Folder of the scenarios shipped with quadland.
SCENARIO_DIR = Path(__file__).parent / "scenarios"


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
        section, key = split_dotted(dotted)
        return self.data[section][key]

    @property
    def model(self) -> str:
        """The loop it selects: ``"paper"`` (the 4-DOF loop) or ``"landing"`` (6-DOF)."""
        return self.data["scenario"].get("model", DEFAULT_MODEL)

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
        A shipped scenario's name (``"paper"``) or a TOML file (:mod:`quadland.extends`).
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
    raw = resolve_extends(path, _read_raw, _resolve)     # extends = "highway": its bases
    campaign = raw.pop("campaign", None)
    if campaign is not None and not isinstance(campaign, dict):
        raise ScenarioError(f"{path}: [campaign] must be a table")
    pairs = _parse_overrides(overrides)
    overridden = {}
    for dotted, value in pairs:
        section, key = _split_key(dotted)
        if section == "campaign":                   # campaign.runs, .seed, .sampling, ...
            if campaign is None:
                raise ScenarioError(f"override {show(dotted)}: {path} has no [campaign] table")
            _check_campaign_key(dotted, key)
            campaign[key] = value
            continue
        if not own_key(raw, section, key):         # else: any model's, or an error
            check_override_key(dotted, section, key)
        raw.setdefault(section, {})
        if not isinstance(raw[section], dict):
            raise ScenarioError(f"{path}: [{section}] must be a table")
        raw[section][key] = value
        overridden[(section, key)] = dotted
    stem = re.sub(r"[^A-Za-z0-9._-]", "-", path.stem)
    data = _validate(raw, str(path), default_name=stem.lstrip(".-_")[:64] or "scenario",
                     overridden=overridden)
    return Scenario(data["scenario"]["name"], str(path), data,
                    tuple(f"{k}={show(v)}" for k, v in pairs), _plain_copy(campaign))


def _read_raw(path: Path) -> dict:
    """A scenario file's sections as written (``extends`` left in)."""
    return nest_sections(_parse_toml(_read_text(path), str(path)))


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
            raise ScenarioError(f"{source}: malformed TOML: {show(cause, 80)}") from None
        line_no = int(where.group(1))
        lines = text.splitlines()
        line = lines[line_no - 1] if 0 < line_no <= len(lines) else ""
        if cause.startswith("Cannot overwrite a value") or cause.startswith("Cannot declare"):
            key = _KEY_RE.match(line)
            name = _duplicate_name(lines, line_no, key.group(1).strip() if key else line.strip())
            what = "section" if name.startswith("[") else "key"
            raise ScenarioError(f"{source}: duplicate {what} {show(name)} (line {line_no})") \
                from None
        raise ScenarioError(f"{source}: malformed TOML at line {line_no}, column "
                            f"{where.group(2)}: {show(cause, 80)}") from None
    except RecursionError:
        raise ScenarioError(f"{source}: malformed TOML: nested too deeply") from None
    except ValueError as exc:                       # e.g. an integer of over 4300 digits
        raise ScenarioError(f"{source}: malformed TOML: {show(str(exc), 80)}") from None


def _duplicate_name(lines: list[str], line_no: int, key: str) -> str:
    """``section.key`` of a duplicated key, from the nearest table header above it."""
    if key.startswith("["):
        return key
    for line in reversed(lines[:line_no - 1]):
        head = line.strip()
        if head.startswith("[") and "]" in head:
            return f"{head[1:head.index(']')].strip()}.{key}"
    return key


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
    section, key = split_dotted(str(dotted))
    if not section or not key:
        raise ScenarioError(f"override {show(str(dotted))}: expected section.key=value")
    return section, key


def _check_campaign_key(dotted: str, key: str) -> None:
    """Refuse an override of anything but a top-level key of ``[campaign]``."""
    keys = ", ".join(CAMPAIGN_KEYS)
    head = key.partition(".")[0]
    if key in CAMPAIGN_KEYS:
        return
    if head in CAMPAIGN_KEYS:
        raise ScenarioError(f"override {show(dotted)}: only the [campaign] table's own keys "
                            f"can be set ({keys}); give campaign.{head} whole "
                            f"(campaign.{head}={{...}}) or edit the scenario file")
    hint = difflib.get_close_matches(head, list(CAMPAIGN_KEYS), n=1)
    raise ScenarioError(f"override {show(dotted)}: unknown key campaign.{show(key)} (the "
                        f"[campaign] table's keys: {keys})"
                        + (f"; did you mean 'campaign.{hint[0]}'?" if hint else ""))


def _control(text: str) -> str | None:
    """The first control character of ``text`` (a newline, an escape), as U+XXXX, or None."""
    for c in text:
        if ord(c) < 0x20 or 0x7f <= ord(c) < 0xa0:
            return f"U+{ord(c):04X}"
    return None


def _printable(text: str) -> str:
    """``text`` with its control characters escaped (``\\n``, ``\\x1b``), for a message."""
    return "".join(c if _control(c) is None else c.encode("unicode_escape").decode("ascii")
                   for c in text)


def _check_printable(item) -> None:
    """Refuse an override whose text (or key) holds a control character.

    A newline or an escape would be echoed into a message or written into
    ``scenario.toml``; the text is named with it escaped. (A string value's
    own characters, TOML escapes included, are its key's to check.)
    """
    found = _control(item) if isinstance(item, str) else None
    if found:
        raise ScenarioError(f"override {show(_printable(item), 60)}: holds a control "
                            f"character ({found}); an override is one line of printable text")


def _parse_overrides(overrides) -> list[tuple[str, Any]]:
    if overrides is None:
        return []
    if isinstance(overrides, Mapping):
        for key in overrides:
            _check_printable(key)
        return list(overrides.items())
    pairs = []
    for item in overrides:
        _check_printable(str(item))
        dotted, eq, text = str(item).partition("=")
        if not eq or not dotted.strip():
            raise ScenarioError(f"override {show(str(item))}: expected section.key=value")
        dotted, text = dotted.strip(), text.strip()
        try:
            value = tomllib.loads(f"v = {text}")["v"]
        except (tomllib.TOMLDecodeError, ValueError):
            value = text
        except RecursionError:
            raise ScenarioError(f"override {show(dotted)}: value nested too deeply") from None
        pairs.append((dotted, value))
    return pairs


def _model(raw: Mapping) -> str:
    """``scenario.model`` of a raw scenario, checked; "paper" when absent."""
    table = raw.get("scenario", {})
    model = table.get("model", DEFAULT_MODEL) if isinstance(table, Mapping) else DEFAULT_MODEL
    if model not in MODELS:
        raise ScenarioError(f"scenario.model: must be one of {', '.join(MODELS)}, "
                            f"got {show(model)}")
    return model


def _validate(raw: Mapping, source: str, default_name: str = "scenario",
              overridden: Mapping[tuple[str, str], str] | None = None) -> dict:
    """Check every section and key of ``raw`` against its model's schema; fill nothing but
    the name (and leave ``scenario.model`` out where the schema has no such key: the
    default model's).

    ``overridden`` maps ``(section, key)`` to the ``--set`` text that put it
    there: a key of another model's schema is blamed on that override, not
    on the file."""
    model = _model(raw)
    schema = SCHEMAS[model]
    overridden = overridden or {}
    if isinstance(raw.get("scenario"), Mapping) and "model" not in schema.get("scenario", {}):
        # the default model's schema has no scenario.model: naming it is allowed
        raw = {**raw, "scenario": {k: v for k, v in raw["scenario"].items() if k != "model"}}
    out: dict[str, dict] = {}
    for section, table in raw.items():
        if section not in schema:
            given = [d for (s, _), d in overridden.items() if s == section]
            where = f"override {show(given[0])}" if given else source
            raise ScenarioError(f"{where}: {unknown_name('section', section, schema)}"
                                + _other_model(section, model))
        if not isinstance(table, Mapping):
            raise ScenarioError(f"{source}: [{section}] must be a table")
        for key in table:
            if key not in schema[section]:
                where = f"override {show(overridden[section, key])}" \
                    if (section, key) in overridden else source
                name = f"{section}.{key}"
                if isinstance(table[key], Mapping):     # [sensors.visoin]: a sub-table
                    raise ScenarioError(f"{where}: {unknown_name('section', name, schema)}")
                raise ScenarioError(f"{where}: {unknown_name('key', name, _dotted(section, model))}"
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
                if field.default is None:
                    raise ScenarioError(f"{source}: missing key {dotted} ({field.doc}, "
                                        f"{field.unit})")
                out[section][key] = check_value(dotted, field.default, field)
                continue
            out[section][key] = check_value(dotted, table[key], field)
    CROSS_CHECKS[model](out)
    return out


def _other_model(section: str, model: str, key: str | None = None) -> str:
    """A hint when the section or key belongs to another model's schema."""
    for other, schema in SCHEMAS.items():
        if other != model and section in schema and (key is None or key in schema[section]):
            return f" (a key of scenario.model = \"{other}\")" if key else \
                f" (a section of scenario.model = \"{other}\")"
    return ""


def _dotted(section: str, model: str = DEFAULT_MODEL) -> list[str]:
    return [f"{section}.{k}" for k in SCHEMAS[model][section]]


def require_model(scenario: Scenario, model: str, what: str) -> None:
    """Refuse, in one line, a scenario of another model than ``what`` handles."""
    if scenario.model != model:
        raise ScenarioError(f"scenario.model: {what} handles scenario.model = \"{model}\" "
                            f"only, got \"{scenario.model}\"")


