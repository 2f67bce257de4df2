"""A campaign run's scenario: the campaign's, with the run's draws, checked as far as they
change it.

:meth:`quadland.scenario.Scenario.replace` validates every key of the scenario again
(about 270 of a landing's, 1 ms a run). A campaign's scenario was validated once, when
it was loaded; a run changes only its dispersed keys, so :func:`dispersed` checks those
(each against its schema field, in the schema's order, as the full validation meets
them) and the model's cross-key checks, and keeps every other validated value. The
result is the scenario ``replace`` gives, and a draw ``replace`` refuses is refused with
the same message (tested in ``tests/test_dispersed.py``).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from quadland.scenario import Scenario
from quadland.schema import CROSS_CHECKS, SCHEMAS, check_value, split_dotted

__all__ = ["dispersed"]


def dispersed(base: Scenario, values: Mapping[str, Any]) -> Scenario:
    """``base.replace(**values)``, checking only the keys ``values`` changes.

    ``base`` is a validated scenario (loaded, or itself replaced). Keys outside its
    model's schema, or in ``[scenario]`` (the model, the name), take the full
    validation of :meth:`~quadland.scenario.Scenario.replace`.

    Raises
    ------
    ScenarioError
        The first changed key, in the schema's order, whose value its field refuses,
        or a cross-key check: the message ``replace`` gives.
    """
    schema = SCHEMAS[base.model]
    changed: dict[str, dict[str, Any]] = {}
    for dotted, value in values.items():
        section, key = split_dotted(str(dotted))
        if section == "scenario" or key not in schema.get(section, {}):
            return base.replace(**values)
        changed.setdefault(section, {})[key] = value
    data = {section: dict(table) for section, table in base.data.items()}
    for section, fields in schema.items():
        if section in changed:
            new = changed[section]
            for key, field in fields.items():
                if key in new:
                    data[section][key] = check_value(f"{section}.{key}", new[key], field)
    CROSS_CHECKS[base.model](data)
    return Scenario(data["scenario"]["name"], base.source, data, base.overrides,
                    base.campaign_table)
