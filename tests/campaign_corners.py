"""The corners of a landing scenario's campaign dispersions of the airframe, for the margin
checks (issue 19 item 2): taken from the scenario's own file, its nominal values and its
``[campaign]`` table's ranges, so that a file's drag or range change moves its corners.
"""

import itertools

from quadland.campaign.draws import apply_mode, extremes
from quadland.campaign.spec import campaign_spec_of
from quadland.scenario import load_scenario

#: The airframe's keys whose dispersion has corners (issue 19 item 2: motor lag, mass,
#: inertia, drag linear and quadratic, thrust-to-weight); a scenario's campaign that
#: leaves one out keeps it at the nominal.
AIRFRAME_KEYS = ("quadrotor.mass", "quadrotor.inertia", "quadrotor.drag_translational",
                 "quadrotor.drag_quadratic", "quadrotor.motor_time_constant",
                 "quadrotor.thrust_to_weight")
#: Short names of the keys for a corner's test id.
_SHORT = {"quadrotor.mass": "m", "quadrotor.inertia": "I", "quadrotor.drag_translational": "kt",
          "quadrotor.drag_quadratic": "kq", "quadrotor.motor_time_constant": "tau",
          "quadrotor.thrust_to_weight": "tw"}


def _value(target, mode, x):
    vals = [apply_mode(mode, n, x) for n in target.nominal]
    if target.scalar:
        return repr(vals[0])
    return "[" + ", ".join(repr(v) for v in vals) + "]"


def airframe_corners(name, overrides=()):
    """Every corner of scenario ``name``'s dispersed airframe keys, as overrides.

    Each key goes to the least and the largest value its dispersion can draw (``extremes``
    of the sampling), the keys in :data:`AIRFRAME_KEYS` order; ``2 ** k`` corners for ``k``
    dispersed keys. Every element of a list key goes to the same end: these are the
    diagonal corners only. Without ``common = true`` the campaign draws each element of a
    list key on its own (one of its runs can fly the roll inertia at +10 % and the yaw
    inertia at -10 %), so its box has ``2 ** 11`` vertices for the five keys of today's
    files; the review of the twenty-first session measured off-diagonal ones
    (docs/landing.md).

    Parameters
    ----------
    name : str
        A shipped scenario.
    overrides : sequence of str, optional
        Applied to the file first (its nominal values or its table).

    Returns
    -------
    list of list of str
        One list of ``section.key=value`` overrides per corner.
    """
    spec = campaign_spec_of(load_scenario(name, list(overrides)))
    by_key = {d.key: d for d in spec.dispersions}
    ends = []
    for key in AIRFRAME_KEYS:
        disp = by_key.get(key)
        if disp is None:
            continue
        lows, highs = zip(*extremes(disp), strict=True)
        assert len(set(lows)) == 1 and len(set(highs)) == 1, (key, lows, highs)
        ends.append([[f"{t.key}={_value(t, disp.mode, x)}" for t in disp.targets]
                     for x in (lows[0], highs[0])])
    return [[o for part in combo for o in part] for combo in itertools.product(*ends)]


def corner_id(corner):
    """A corner's test id: each key's short name and its (first) value; ``hover`` for none."""
    if not corner:
        return "hover"
    parts = []
    for o in corner:
        key, value = o.split("=", 1)
        parts.append(f"{_SHORT[key]}{float(value.strip('[]').split(',')[0]):g}")
    return "-".join(parts)
