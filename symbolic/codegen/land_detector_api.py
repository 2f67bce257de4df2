"""The readable API of the land detector: quadland_land_detector.h and .c.

The detector is :func:`quadland_symbolic.landing.land_detector.land_detector_function`
(``ql_land_detector_step``) with the cues the flight code forms for it,
:func:`quadland_symbolic.landing.sensed_loop.detector_cues_function`
(``ql_land_detector_form_cues``). Its structs are the model's layouts (the memory,
the cues, the parameters, the flags); the valid values of its parameters are
one table, :data:`LAND_DETECTOR_PARAM_RANGES`, from which
``ql_check_land_detector_params`` and the step's own range test are generated.
The defaults are :data:`~quadland_symbolic.landing.land_detector.LAND_DETECTOR_DEFAULTS`:
no scenario sets them, as the filter's.

It is a part of its own (``quadland_land_detector.h``), not a function of the
filter's or the landing's header: it is one flight object with its own memory,
parameters and defaults, usable on any estimate (the step reads only its cues);
the cues helper reads the landing's and the filter's structs, so the header
includes ``quadland_estimator.h`` (and through it ``quadland_landing.h`` and
``quadland.h``) for their types, and links without their code.
"""

from __future__ import annotations

import functools
from types import MappingProxyType

from quadland_symbolic.codegen.config import DEFAULT_CONFIG, CodegenConfig
from quadland_symbolic.codegen.landing_api import vector_context
from quadland_symbolic.codegen.paper_api import emit_part, param_range_context, struct_context
from quadland_symbolic.codegen.registry import BY_NAME
from quadland_symbolic.codegen.render import common_context
from quadland_symbolic.codegen.structs import (
    CStruct,
    ParamRange,
    Range,
    guidance_state_layout,
    member_ranges,
)
from quadland_symbolic.landing.controller import LANDING_MEASUREMENT
from quadland_symbolic.landing.guidance import GUIDANCE_PARAMS, GUIDANCE_STATE
from quadland_symbolic.landing.land_detector import (
    LAND_DETECTOR_CUES,
    LAND_DETECTOR_DEFAULTS,
    LAND_DETECTOR_FLAGS,
    LAND_DETECTOR_PARAMS,
    LAND_DETECTOR_STATE,
    TIME_CAP,
)
from quadland_symbolic.landing.navigation import IMU, RANGE
from quadland_symbolic.landing.quadrotor import COMMAND
from quadland_symbolic.parameters import QUADROTOR

__all__ = ["LAND_DETECTOR_PARAM_RANGES", "land_detector_param_ranges",
           "land_detector_api_structs", "land_detector_sizes", "land_detector_api_context",
           "generate_land_detector"]

_NONNEGATIVE = Range(lo=0.0)
_WIDENING = Range(lo=1.0)

#: Valid values of every member of ``ql_land_detector_params`` (NaN and infinities are
#: invalid everywhere): thresholds, windows, the range's timeout and the spike's size
#: and window not negative; the widening and lengthening factors at least 1 (they
#: widen and lengthen, docs/land_detector.md); the running mean's time constant
#: positive; ``contact_thrust`` 0 or 1 (the scenario schema's ``[land_detector]`` ranges,
#: unbounded above).
LAND_DETECTOR_PARAM_RANGES = MappingProxyType({
    **{k: _NONNEGATIVE for k in ("gap_max", "vz_max", "thrust_low", "contact_time",
                                 "maybe_time", "landed_time")},
    "hold_factor": _WIDENING,
    "no_range_factor": _WIDENING,
    **{k: _NONNEGATIVE for k in ("range_timeout", "spike_min", "spike_window")},
    "accel_tau": Range(lo=0.0, lo_open=True),
    "contact_thrust": Range(choices=(0.0, 1.0)),
})

#: The stage flags of the memory (each 0 or 1 in a valid memory); its other members but
#: the range's gap and the running mean are times, never negative.
_STAGES = ("ground_contact", "maybe_landed", "landed")
_FREE = ("range_gap", "f_z_mean")


@functools.cache
def land_detector_param_ranges() -> tuple[ParamRange, ...]:
    """Every member of ``ql_land_detector_params`` in order, with its range."""
    return member_ranges(LAND_DETECTOR_PARAMS, LAND_DETECTOR_PARAM_RANGES)


@functools.cache
def land_detector_api_structs() -> tuple[CStruct, ...]:
    """Every struct of ``quadland_land_detector.h``, in declaration order."""
    return (
        CStruct("land_detector_state", LAND_DETECTOR_STATE,
                "The detector's memory: each stage's time and flag, the last fresh range,\n"
                " * the accelerometer's running mean. Start with {ql}land_detector_state_init."),
        CStruct("land_detector_cues", LAND_DETECTOR_CUES,
                "What the detector reads each period ({ql}land_detector_form_cues forms them)."),
        CStruct("land_detector_params", LAND_DETECTOR_PARAMS,
                "Thresholds and windows; {ql}land_detector_params_init fills the defaults."),
        CStruct("land_detector_flags", LAND_DETECTOR_FLAGS,
                "What one step reports: the three stages and the cues it saw, each 0 or 1."),
    )


def land_detector_sizes() -> list[dict]:
    """The detector API's size macros (name without prefix, value, comment)."""
    return [
        dict(name="LAND_DETECTOR_STATE_SIZE", value=LAND_DETECTOR_STATE.size,
             doc="reals in {ql}land_detector_state"),
        dict(name="LAND_DETECTOR_CUES_SIZE", value=LAND_DETECTOR_CUES.size,
             doc="reals in {ql}land_detector_cues"),
        dict(name="LAND_DETECTOR_PARAMS_SIZE", value=LAND_DETECTOR_PARAMS.size,
             doc="reals in {ql}land_detector_params"),
        dict(name="LAND_DETECTOR_FLAGS_SIZE", value=LAND_DETECTOR_FLAGS.size,
             doc="reals in {ql}land_detector_flags"),
    ]


def _context_of(name: str) -> dict:
    fn = BY_NAME[name].function(0)
    return dict(arg={n: i for i, n in enumerate(fn.name_in())},
                res={n: i for i, n in enumerate(fn.name_out())})


def _step_context(config: CodegenConfig) -> dict:
    """Where ``ql_land_detector_step`` and ``ql_land_detector_form_cues`` put their arguments."""
    offsets = LAND_DETECTOR_STATE.offsets()
    xg = guidance_state_layout()
    return dict(
        c_name=BY_NAME["land_detector"].c_name(config), **_context_of("land_detector"),
        stages=[offsets[n][0] for n in _STAGES],
        times=[offsets[f.name][0] for f in LAND_DETECTOR_STATE.fields
               if f.name not in _STAGES + _FREE],
        cues=dict(c_name=BY_NAME["land_detector_cues"].c_name(config),
                  **_context_of("land_detector_cues"),
                  xg=[dict(name=n, index=i, int=xg[n].ctype == "int")
                      for i, n in enumerate(GUIDANCE_STATE.names())],
                  sizes=dict(y=LANDING_MEASUREMENT.size, range=RANGE.size, imu=IMU.size,
                             F_cmd=COMMAND.size, xg=GUIDANCE_STATE.size,
                             p_guid=GUIDANCE_PARAMS.size, p_quad=QUADROTOR.size)),
    )


def land_detector_api_context(config: CodegenConfig) -> dict:
    """The templates' context of ``quadland_land_detector.h`` and ``.c``."""
    structs = land_detector_api_structs()
    p_ld = LAND_DETECTOR_PARAMS.pack(dict(LAND_DETECTOR_DEFAULTS))
    return dict(
        common_context(config),
        aliases=config.prefix != "ql_",
        sizes=land_detector_sizes(),
        time_cap=config.literal(TIME_CAP),
        structs=[struct_context(s, structs, config.prefix) for s in structs],
        defaults=vector_context("p_ld", p_ld, config),
        ranges=param_range_context(0, config, lambda _: land_detector_param_ranges()),
        step=_step_context(config),
        wrapped=[],
    )


def generate_land_detector(config: CodegenConfig = DEFAULT_CONFIG) -> dict[str, str]:
    """Text of the detector API's C files of one precision (``quadland_land_detector.h``, ...).

    They include the same build's ``quadland_estimator.h`` (for ``ql_imu``,
    ``ql_range_packet``) and through it ``quadland_landing.h`` and ``quadland.h``.
    """
    return emit_part("land_detector", 0, config, land_detector_api_context(config),
                     ("quadland_land_detector.h", "quadland_land_detector.c"))
