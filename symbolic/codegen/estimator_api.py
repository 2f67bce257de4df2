"""The readable API of the navigation filter: quadland_estimator.h and .c.

The filter is :func:`quadland_symbolic.landing.estimator.estimator_step_function`
at the sizes flown (:data:`~quadland_symbolic.codegen.registry.ESTIMATOR_SIZES`:
``N_HIST``, ``FLIGHT_DEPTH``, ``FLIGHT_COUPLING``) and its
``estimator_init_function``. Its structs are the model's layouts (the state
``NAV``, the IMU sample, one per packet, the parameters, the memory and the
diagnostics), its output is ``quadland_landing.h``'s
``ql_landing_measurement``, and the valid values of its parameters are one
table, :data:`ESTIMATOR_PARAM_RANGES`, from which ``ql_check_estimator_params``
and the step's own range test are generated. The defaults are
:data:`~quadland_symbolic.landing.navigation.ESTIMATOR_DEFAULTS`: no scenario
sets them.
"""

from __future__ import annotations

import functools
from types import MappingProxyType

import casadi as ca

from quadland_symbolic.codegen.config import DEFAULT_CONFIG, CodegenConfig
from quadland_symbolic.codegen.landing_api import vector_context
from quadland_symbolic.codegen.paper_api import emit_part, param_range_context, struct_context
from quadland_symbolic.codegen.registry import BY_NAME, ESTIMATOR_SIZES
from quadland_symbolic.codegen.render import common_context
from quadland_symbolic.codegen.structs import CStruct, ParamRange, Range, member_ranges
from quadland_symbolic.landing.controller import LANDING_MEASUREMENT
from quadland_symbolic.landing.estimator import (
    estimator_diagnostics,
    estimator_memory,
    estimator_step_function,
)
from quadland_symbolic.landing.navigation import (
    BLOCKS,
    DATALINK,
    DECK_INIT,
    ESTIMATOR_DEFAULTS,
    GNSS,
    IMU,
    NAV,
    RANGE,
    SENSORS,
    VISION,
    estimator_params,
)
from quadland_symbolic.layout import Layout

__all__ = ["ESTIMATOR_PARAM_RANGES", "estimator_param_ranges", "flight_memory",
           "estimator_api_structs", "imu_outputs", "estimator_sizes", "estimator_api_context",
           "generate_estimator"]

_POSITIVE = Range(lo=0.0, lo_open=True)
_NONNEGATIVE = Range(lo=0.0)

#: Valid values of every member of ``ql_estimator_params`` by member path (NaN and
#: infinities are invalid everywhere): gravity, the noise densities and sigmas
#: positive (a zero density or sigma makes a covariance or an innovation
#: variance singular; the tilt bias' sigma may be zero, its time constant not),
#: the vision noise's growth with range and the ages not
#: negative, ``range_min_cos`` in (0, 1] (the range model divides by
#: ``n2 . b3_E`` once it is at least that), the deck radius positive and its
#: standard deviations not negative (E12a), the gates positive.
ESTIMATOR_PARAM_RANGES = MappingProxyType({
    "g": _POSITIVE,
    **{k: _POSITIVE for k in ("q_acc", "q_at", "q_b", "q_ab", "vision_sigma0")},
    # the tilt bias: its standard deviation may be 0 (z: the tilt moves the input
    # horizontally only), its correlation time must be positive (exp(-dt / tilt_tau))
    "tilt_sigma": _NONNEGATIVE,
    "tilt_tau": _POSITIVE,
    # the share of the input bias the tilt levels (E2b): 0 (apart) to 1 (all of it)
    "tilt_levels_bias": Range(lo=0.0, hi=1.0),
    "vision_k_range": _NONNEGATIVE,
    "vision_heading_sigma": _NONNEGATIVE,
    "range_k_range": _NONNEGATIVE,
    **{k: _POSITIVE for k in ("gnss_rel_sigma", "gnss_v1_sigma", "gnss_vt_sigma",
                              "range_sigma")},
    "range_min_cos": Range(lo=0.0, hi=1.0, lo_open=True),
    "range_deck_radius": _POSITIVE,
    "range_deck_sigmas": _NONNEGATIVE,
    **{k: _POSITIVE for k in ("datalink_v_sigma", "datalink_a_sigma")},
    **{f"gate_{b.name}": _POSITIVE for b in BLOCKS},
    "gate_lockout": _NONNEGATIVE,
    **{f"max_age_{s}": _NONNEGATIVE for s in SENSORS},
    "deck_extrapolation_max": _NONNEGATIVE,
    "heave_time": _NONNEGATIVE,           # 0: a flat deck, the constant acceleration (E17a)
    "heave_frequency": _NONNEGATIVE,      # 0: the filter's own frequency (E17a), (E17b)
    "heave_in_filter": Range(lo=0.0, hi=1.0),  # a switch: the oscillator in Phi too (E17b)
    "heave_height": _NONNEGATIVE,         # the oscillator only at or below this p_r z
})


@functools.cache
def estimator_param_ranges() -> tuple[ParamRange, ...]:
    """Every member of ``ql_estimator_params`` in order, with its range."""
    return member_ranges(estimator_params(), ESTIMATOR_PARAM_RANGES)


def flight_memory() -> Layout:
    """``ql_estimator_memory``: the filter's memory at the sizes flown."""
    return estimator_memory(**dict(ESTIMATOR_SIZES))


@functools.cache
def estimator_api_structs() -> tuple[CStruct, ...]:
    """Every struct of ``quadland_estimator.h``, in declaration order.

    Its output ``y`` is ``quadland_landing.h``'s ``ql_landing_measurement``.
    """
    return (
        CStruct("nav_state", NAV, "The filter's state (E1), frame E (z up): layout nav."),
        CStruct("imu", IMU, "This period's IMU sample and attitude estimate (every period)."),
        CStruct("vision_packet", VISION,
                "A vision packet: fresh = 1 in the period it arrived, tau its capture time."),
        CStruct("gnss_packet", GNSS, "A GNSS packet (both receivers), as the vision packet."),
        CStruct("range_packet", RANGE, "A range finder packet, as the vision packet."),
        CStruct("datalink_packet", DATALINK,
                "The vehicle's broadcast of its deck's motion, as the vision packet."),
        CStruct("deck_init", DECK_INIT,
                "The deck's rotation assumed before the first broadcast (zeros: level,\n"
                " * heading along E's x, not rotating)."),
        CStruct("estimator_params", estimator_params(),
                "Everything the filter is tuned with; {ql}estimator_params_init fills the\n"
                " * defaults."),
        CStruct("estimator_memory", flight_memory(),
                "The filter's memory: the state and covariance at the horizon, the input\n"
                " * buffer, the FIFOs, the latest broadcast and the counters. Start with\n"
                " * {ql}estimator_init."),
        CStruct("estimator_diagnostics", estimator_diagnostics(),
                "What one step reports besides the landing step's measurements."),
    )


@functools.cache
def imu_outputs() -> tuple[str, ...]:
    """The fields of ``y`` that are this period's IMU sample as passed.

    Read from the step's expression graph: the entries of ``y`` that depend on
    ``imu`` at all (the attitude estimate and the rates, E15's table); the graph of
    the branch-free step, the same function as the one generated (whose updates are
    evaluated only when due) as one SX expression.
    """
    rows = set(_y_on_imu()[0])
    fields = tuple(f.name for f in LANDING_MEASUREMENT.fields
                   if rows & set(range(*LANDING_MEASUREMENT.offsets()[f.name])))
    covered = {i for n in fields for i in range(*LANDING_MEASUREMENT.offsets()[n])}
    if covered != rows:
        raise ValueError(f"y depends on the IMU in part of a field: {sorted(rows)}")
    return fields


def estimator_sizes() -> list[dict]:
    """The filter API's size macros (name without prefix, value, comment)."""
    sizes = dict(ESTIMATOR_SIZES)
    mem = flight_memory()
    return [
        dict(name="NAV_SIZE", value=NAV.size,
             doc=f"reals in {{ql}}nav_state: {', '.join(NAV.names())}"),
        dict(name="ESTIMATOR_N_HIST", value=sizes["n_hist"],
             doc="periods between the horizon and now: D = n_hist dt"),
        *(dict(name=f"ESTIMATOR_DEPTH_{s.upper()}", value=d, doc=f"FIFO depth of {s} packets")
          for s, d in zip(SENSORS, sizes["depth"], strict=True)),
        dict(name="ESTIMATOR_COVARIANCE_SIZE", value=mem["P_h"].size,
             doc=f"stored covariance entries (coupling {sizes['coupling']})"),
        dict(name="ESTIMATOR_MEMORY_SIZE", value=mem.size, doc="reals in {ql}estimator_memory"),
        dict(name="ESTIMATOR_PARAMS_SIZE", value=estimator_params().size,
             doc="reals in {ql}estimator_params"),
        dict(name="ESTIMATOR_DIAGNOSTICS_SIZE", value=estimator_diagnostics().size,
             doc="reals in {ql}estimator_diagnostics"),
        dict(name="ESTIMATOR_BLOCKS", value=len(BLOCKS),
             doc=f"measurement blocks: {', '.join(b.name for b in BLOCKS)}"),
        dict(name="ESTIMATOR_SENSORS", value=len(SENSORS), doc=f"sensors: {', '.join(SENSORS)}"),
    ]


def imu_passed_inputs() -> tuple[tuple[str, int], ...]:
    """The IMU's fields that :func:`imu_outputs` pass on, with their sizes.

    Read from the step's expression graph: the entries of ``imu`` that ``y`` depends
    on at all (the attitude estimate and the rates; the specific force enters the
    filter's memory, not ``y``). The C step refuses a non-finite value in them
    (``QL_ERR_NONFINITE_INPUT``), so ``y`` is finite on ``QL_OK``.
    """
    cols = set(_y_on_imu()[1])
    return tuple((f.name, f.size) for f in IMU.fields
                 if cols & set(range(*IMU.offsets()[f.name])))


@functools.cache
def _y_on_imu() -> tuple[tuple[int, ...], tuple[int, ...]]:
    """The (row, column) pairs of ``dy/dimu``'s sparsity in the generated step's graph."""
    fn = estimator_step_function(**dict(ESTIMATOR_SIZES))
    y = fn.call({n: fn.sx_in(n) for n in fn.name_in()})["y"]
    rows, cols = ca.jacobian(y, fn.sx_in("imu")).sparsity().get_triplet()
    return tuple(rows), tuple(cols)


def _step_context(config: CodegenConfig) -> dict:
    """Where ``ql_estimator_step`` and ``ql_estimator_init`` put each argument and result."""
    step, init = (BY_NAME[n].function(0) for n in ("estimator_step", "estimator_init"))
    offsets = LANDING_MEASUREMENT.offsets()
    passed = imu_outputs()
    checked, run = [], None            # the runs of y the filter computes
    for f in LANDING_MEASUREMENT.fields:
        a, b = offsets[f.name]
        if f.name in passed:
            run = None
        elif run is not None and run["offset"] + run["size"] == a:
            run["size"] += b - a
        else:
            run = dict(offset=a, size=b - a)
            checked.append(run)
    mem = flight_memory()
    return dict(
        c_name=BY_NAME["estimator_step"].c_name(config),
        arg={n: i for i, n in enumerate(step.name_in())},
        res={n: i for i, n in enumerate(step.name_out())},
        packets=[dict(name=s, type=f"{s}_packet") for s in SENSORS],
        counts=[dict(name=f"count_{s}", depth=d)
                for s, d in zip(SENSORS, dict(ESTIMATOR_SIZES)["depth"], strict=True)],
        y_checked=checked, y_passed=passed,
        imu_checked=[dict(name=n, size=s) for n, s in imu_passed_inputs()],
        mem_size=mem.size, y_size=LANDING_MEASUREMENT.size,
        init=dict(c_name=BY_NAME["estimator_init"].c_name(config),
                  arg={n: i for i, n in enumerate(init.name_in())},
                  res={n: i for i, n in enumerate(init.name_out())},
                  deck_size=DECK_INIT.size),
    )


def estimator_api_context(config: CodegenConfig) -> dict:
    """The templates' context of ``quadland_estimator.h`` and ``.c``."""
    structs = estimator_api_structs()
    p_est = estimator_params().pack(dict(ESTIMATOR_DEFAULTS))
    return dict(
        common_context(config),
        aliases=config.prefix != "ql_",
        sizes=estimator_sizes(),
        sizes_text=", ".join(f"{k} = {v!r}" for k, v in ESTIMATOR_SIZES),
        structs=[struct_context(s, structs, config.prefix) for s in structs],
        defaults=vector_context("p_est", p_est, config),
        ranges=param_range_context(0, config, lambda _: estimator_param_ranges()),
        step=_step_context(config),
        wrapped=[],
    )


def generate_estimator(config: CodegenConfig = DEFAULT_CONFIG) -> dict[str, str]:
    """Text of the filter API's C files of one precision (``quadland_estimator.h``, ...).

    They include the same build's ``quadland_landing.h`` (for
    ``ql_landing_measurement``) and through it ``quadland.h``.
    """
    return emit_part("estimator", 0, config, estimator_api_context(config),
                     ("quadland_estimator.h", "quadland_estimator.c"))
