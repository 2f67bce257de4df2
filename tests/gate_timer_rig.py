"""A committed descent's guidance step with the crawl's gate on, by hand (shared by the
tests of the gate's wait: ``crawl_gate_wait_height`` and ``crawl_gate_count_height``)."""

from reference import GUIDANCE_P

from quadland_symbolic.landing.guidance import (
    DESCEND,
    GUIDANCE_CUES,
    GUIDANCE_PARAMS,
    GUIDANCE_STATE,
    guidance_function,
)

DT = 2.0 ** -7    # s: binary, so that the timer's sums and the wait are exact
HC = 0.25         # m: the gear below the centre, the contact height on the level gear
F = guidance_function()
CUES = GUIDANCE_CUES.pack(dict(touchdown=0.0, marker_age=0.0, contact_switch=0.0))


def gate_state(h, timer=0.0):
    """The guidance's state in a committed descent, the reference ``h`` above the contact
    and the gate's timer at ``timer``."""
    return GUIDANCE_STATE.pack(dict(phase=DESCEND, timer=timer, z_ref=HC + h, aborts=0,
                                    committed=1, armed=1.0, ms_rise=0.0, ms_rise_rate=0.0,
                                    ms_tilt_rate=0.0, ms_tilt_acc=0.0, lean_x=0.0, lean_y=0.0,
                                    lean_gust=0.0))


def gate_params(**keys):
    """The reference guidance parameters on the level gear, a 0.05 m gate, and ``keys``."""
    return GUIDANCE_PARAMS.pack(dict(GUIDANCE_P, touchdown_height=HC,
                                     **{"crawl_gate": 0.05, **keys}))
