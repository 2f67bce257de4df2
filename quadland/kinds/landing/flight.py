"""The landing's flight code: its C defaults, its build, and its API called from Python.

The landing step and guidance generated as C (``quadland_landing.h``, one tree
with the paper's step), with a landing scenario's values as its C defaults
(:func:`landing_defaults`; ``generated/`` carries the highway scenario's), and
beside them the navigation filter (``quadland_estimator.h``) and the land
detector (``quadland_land_detector.h``), which have no scenario values; built on
first use and loaded with ``ctypes`` (:func:`load_landing_api`).
"""

from __future__ import annotations

import ctypes
import dataclasses
import functools

import numpy as np

from quadland.constants import TILT_MIN
from quadland.engine.build import build_library
from quadland.engine.compiled import FlightCode
from quadland.engine.flightcode import Library, ctypes_struct, label, real_type
from quadland.engine.recall import code_recipe
from quadland.kinds.landing.gear import contact_step, free_flight_gap, gear_span
from quadland.kinds.landing.report import GEAR_LIMITS, TOUCHDOWN_LIMITS
from quadland.kinds.landing.sensed import (
    handover,
    imu_at_rest,
    sensed_vectors,
    sensor_settings,
    sensors_enabled,
)
from quadland.kinds.landing.values import landing_values
from quadland.kinds.paper.flight import PAPER_SCENARIO, default_paper
from quadland.scenario import Scenario, load_scenario
from quadland_symbolic.codegen import CodegenConfig, LandingDefaults, SensorDefaults, c_sources
from quadland_symbolic.codegen.structs import landing_api_structs
from quadland_symbolic.landing.loop import landing_loop_params
from quadland_symbolic.landing.plant import LANDING_PLANT_PARAMS
from quadland_symbolic.landing.sensed_loop import sensed_loop_params
from quadland_symbolic.landing.sensors import SENSOR_NAMES

__all__ = ["LANDING_SCENARIO", "landing_defaults", "default_landing", "flight_files",
           "flight_code", "LandingApi", "load_landing_api"]

#: The scenario whose values the landing's half of ``generated/`` carries.
LANDING_SCENARIO = "highway"


def landing_defaults(sc: Scenario) -> LandingDefaults:
    """The C defaults of the landing step, the guidance and the example ``land``: a
    landing scenario's values (:func:`quadland.kinds.landing.values.landing_values`)."""
    lv = landing_values(sc)
    pc = landing_loop_params(lv.l).unpack(lv.pc)
    model = LANDING_PLANT_PARAMS.unpack(pc["pp"])        # the controller's own model
    d, sim, wind = sc.data["disturbance"], sc.data["simulation"], sc.data["wind"]
    g = sc.data["landing"]
    e = np.asarray(wind["gust_direction"], dtype=float)
    e = e / np.linalg.norm(e) if np.linalg.norm(e) > 0 else e      # as quadland.engine.wind does

    def floats(v):
        return tuple(float(x) for x in np.asarray(v, dtype=float))

    return LandingDefaults(
        scenario=label(sc), l=lv.l, p_quad=model["p_quad"], p_ctrl=pc["p_ctrl"],
        p_act=model["p_act"],
        p_guid=pc["p_guid"], tilt_min=TILT_MIN, pp=lv.pp, xp0=lv.xp0,
        duration=float(sim["duration"]), output_rate_hz=float(sim["output_rate_hz"]),
        control_rate_hz=float(sc.data["controller"]["rate_hz"]),
        disturbance_rate_hz=float(d["sample_rate_hz"]),
        rk_steps=int(sim["rk_steps_per_interval"]),
        delay_periods=int(sc.data["controller"]["delay_periods"]),
        force_bias=floats(d["force_bias"]), force_amplitude=float(d["force_amplitude"]),
        force_frequency=float(d["force_frequency"]), moment_bias=floats(d["moment_bias"]),
        moment_amplitude=float(d["moment_amplitude"]),
        moment_frequency=float(d["moment_frequency"]), wind_mean=floats(wind["mean"]),
        gust_start=float(wind["gust_start"]), gust_half_length=float(wind["gust_half_length"]),
        gust_amplitude=float(wind["gust_amplitude"]), gust_direction=floats(e),
        settle_time=float(g["settle_time"]),
        limits=tuple((k, float(g[k])) for k in TOUCHDOWN_LIMITS + GEAR_LIMITS),
        h_after=contact_step(sc, np.asarray(LANDING_PLANT_PARAMS.unpack(lv.pp)["p_quad"],
                                            dtype=float).ravel()),
        free_gap=free_flight_gap(sc),
        mass=float(sc.data["quadrotor"]["mass"]), gear_span=gear_span(sc.data),
        sensors=_sensor_defaults(sc, lv) if sensors_enabled(sc) else None)


def _sensor_defaults(sc: Scenario, lv) -> SensorDefaults:
    """The example's sensors, filter and detector: the sensed loop's vectors
    (:func:`quadland.kinds.landing.sensed.sensed_vectors`), its random parts off."""
    pc = sensed_loop_params(lv.l).unpack(sensed_vectors(sc, lv)[0])
    rate = float(sc.data["controller"]["rate_hz"])
    settings = sensor_settings(sc)
    g = float(sc.data["quadrotor"]["gravity"])
    nav0, P0_diag, deck0 = handover(sc, lv, random=False)
    return SensorDefaults(
        p_sens=pc["p_sens"], p_est=pc["p_est"], p_ld=pc["p_ld"],
        every=tuple(int(round(rate / settings[n]["rate_hz"])) for n in SENSOR_NAMES),
        first=tuple(int(round(settings[n]["phase"] * rate)) for n in SENSOR_NAMES),
        delay=tuple(int(d) for d in pc["delay"]), nav0=nav0, P0_diag=P0_diag, deck0=deck0,
        imu0=imu_at_rest(lv.xp0, g))




@functools.cache
def default_landing(l: int) -> LandingDefaults:
    """:func:`landing_defaults` of :data:`LANDING_SCENARIO` with ``rbf.nodes = l``."""
    sc = load_scenario(LANDING_SCENARIO)
    if sc["rbf.nodes"] != l:
        sc = load_scenario(LANDING_SCENARIO, [f"rbf.nodes={l}"])
    return landing_defaults(sc)


@functools.lru_cache(maxsize=8)
def _flight_files(l: int, precision: str) -> tuple[tuple[str, str], ...]:
    from quadland_symbolic.codegen import (  # the C writers: on use
        generate,
        generate_estimator,
        generate_land_detector,
        generate_landing,
    )

    config = CodegenConfig(precision)
    files = generate(default_paper(load_scenario(PAPER_SCENARIO)["rbf.nodes"]), config)
    files.update(generate_landing(default_landing(l), config))
    files.update(generate_estimator(config))
    files.update(generate_land_detector(config))
    return tuple(sorted(files.items()))


def flight_files(l: int, precision: str = "double") -> dict[str, str]:
    """The C files of one build of the landing's flight code for ``l`` nodes.

    The landing step and guidance with :data:`LANDING_SCENARIO`'s defaults and
    ``rbf.nodes = l``, beside the paper's step (the tree they share), the
    navigation filter and the land detector; for the scenarios' own ``l`` the
    files equal ``generated/`` (``generated/float/``).
    """
    if precision not in ("double", "float"):
        raise ValueError(f"precision must be 'double' or 'float', got {precision!r}")
    return dict(_flight_files(l, precision))


def flight_code(l: int, sensed: bool = False) -> FlightCode:
    """The flight C the simulator flies with ``controller.backend = "c"``: the landing step
    and guidance, and on sensors (``sensed``) the navigation filter and the land detector."""
    functions = ("landing_step", "estimator_step", "land_detector") if sensed else \
        ("landing_step",)
    return FlightCode(c_sources(functions),
                      code_recipe("landing flight", f"l={l}", f"functions={functions}"),
                      functools.partial(_flight_files, l, "double"))


@dataclasses.dataclass(frozen=True)
class LandingApi:
    """The landing API (``quadland_landing.h``) loaded with ``ctypes``.

    Attributes
    ----------
    lib : object
        The library, its names spelled ``ql_`` in either precision
        (``ql_landing_step``, ``ql_guidance_step``, ``ql_check_landing_params``,
        ...).
    LandingMeasurement, GuidanceCues, PositionReference, LandingState,
    LandingControllerParams, ActuatorParams, LandingParams, LandingOutput, GuidanceState,
    GuidanceParams : type
        ``ctypes.Structure`` mirrors of the header's structs (:func:`ctypes_struct`).
    real : type
        ``ctypes.c_double`` or ``ctypes.c_float``.
    """

    lib: object
    LandingMeasurement: type
    GuidanceCues: type
    PositionReference: type
    LandingState: type
    LandingControllerParams: type
    ActuatorParams: type
    LandingParams: type
    LandingOutput: type
    GuidanceState: type
    GuidanceParams: type
    real: type


@functools.lru_cache(maxsize=8)
def load_landing_api(l: int, precision: str = "double", opt: str = "-O2") -> LandingApi:
    """The landing step and guidance for ``l`` nodes, compiled (the highway scenario's
    defaults, ``rbf.nodes = l``)."""
    files = flight_files(l, precision)
    config = CodegenConfig(precision)
    lib = Library(ctypes.CDLL(str(build_library(files, c_sources(("landing_step",)), opt))),
                   config.prefix)
    real = real_type(precision)
    api = LandingApi(lib=lib, real=real, **{s.mirror: ctypes_struct(s.layout, real)
                                            for s in landing_api_structs(l)})
    P = ctypes.POINTER
    lib.ql_landing_step.argtypes = [P(api.LandingMeasurement), P(api.PositionReference),
                                    P(api.LandingParams), real, P(api.LandingState),
                                    P(api.LandingOutput)]
    lib.ql_guidance_step.argtypes = [P(api.LandingMeasurement), P(api.GuidanceCues),
                                     P(api.GuidanceParams), real, P(api.GuidanceState),
                                     P(api.PositionReference)]
    for name, struct in (("landing", api.LandingParams), ("guidance", api.GuidanceParams)):
        check = getattr(lib, f"ql_check_{name}_params")
        check.argtypes = [P(struct), P(ctypes.c_char_p)]
        check.restype = ctypes.c_int
    lib.ql_landing_step.restype = lib.ql_guidance_step.restype = ctypes.c_int
    lib.ql_landing_state_init.argtypes = [P(api.LandingState), P(api.LandingMeasurement)]
    lib.ql_guidance_state_init.argtypes = [P(api.GuidanceState), P(api.GuidanceParams)]
    lib.ql_phase_name.restype = ctypes.c_char_p
    return api
