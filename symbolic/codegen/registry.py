"""The registry of CasADi functions written as C: one entry per function."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import casadi as ca

from quadland_symbolic.closed_loop import (
    closed_loop_function,
    closed_loop_jacobian_function,
    plant_function,
)
from quadland_symbolic.codegen.config import CodegenConfig
from quadland_symbolic.control_step import control_step_function
from quadland_symbolic.landing.controller import (
    landing_guidance_function,
    landing_step_function,
    measured_cues_function,
)
from quadland_symbolic.landing.estimator import (
    FLIGHT_COUPLING,
    FLIGHT_DEPTH,
    N_HIST,
    estimator_init_function,
    estimator_step_function,
)
from quadland_symbolic.landing.land_detector import land_detector_function
from quadland_symbolic.landing.loop import (
    first_contact_function,
    gear_gap_function,
    landing_gear_signals_function,
)
from quadland_symbolic.landing.plant import (
    loop_plant_function,
)
from quadland_symbolic.landing.relative import touchdown_figures_function
from quadland_symbolic.landing.ride import anchor_function, landed_row_function
from quadland_symbolic.landing.sensed_loop import detector_cues_function
from quadland_symbolic.landing.sensors import (
    SENSOR_NAMES,
    measurement_function,
    sense_datalink_function,
    sense_gnss_function,
    sense_imu_function,
    sense_rangefinder_function,
    sense_vision_function,
)
from quadland_symbolic.landing.signals import landing_signals_function
from quadland_symbolic.vehicle import vehicle_function

__all__ = ["GeneratedFunction", "ESTIMATOR_SIZES", "FUNCTIONS", "BY_NAME", "API_FILE",
           "c_sources"]

#: The navigation filter's sizes as flown: the horizon, the FIFO depths and the
#: covariance coupling (quadland_symbolic.landing.estimator).
ESTIMATOR_SIZES = (("n_hist", N_HIST), ("depth", FLIGHT_DEPTH), ("coupling", FLIGHT_COUPLING))


@dataclasses.dataclass(frozen=True)
class GeneratedFunction:
    """One CasADi function written as C.

    Attributes
    ----------
    name : str
        The ``casadi.Function``'s name and the stem of its ``.c``/``.h``.
    builder : callable
        ``builder(l)`` (or ``builder()`` without ``per_node_count``)
        returns the function.
    per_node_count : bool
        Whether the function depends on the RBF node count ``l``.
    wrapper : str, optional
        File of its named-pointer wrapper ``ql_<name>(...)``, whose
        arguments are the function's ``name_in``/``name_out``; None when
        ``quadland.c`` wraps it.
    doc : str
        Comment of the wrapper in its header (``{ql}``/``{QL}`` stand for
        the build's prefixes).
    part : {"paper", "landing", "estimator", "land_detector"}
        Which API it belongs to: ``quadland.h`` (the paper's control step,
        ``l`` of the paper's scenario), ``quadland_landing.h`` (the landing
        step and guidance, ``l`` of the landing scenario),
        ``quadland_estimator.h`` (the navigation filter) or
        ``quadland_land_detector.h`` (the land detector and its cues).
    sizes : tuple of (str, object)
        Keyword arguments of the builder besides ``l`` (the filter's sizes),
        which the banner names.
    """

    name: str
    builder: Callable[..., ca.Function]
    per_node_count: bool = True
    wrapper: str | None = None
    doc: str = ""
    part: str = "paper"
    sizes: tuple[tuple[str, object], ...] = ()

    @property
    def source(self) -> str:
        """Dotted path of the builder, for the banner."""
        return f"{self.builder.__module__}.{self.builder.__qualname__}"

    def function(self, l: int) -> ca.Function:
        """The ``casadi.Function`` for ``l`` RBF nodes."""
        kw = dict(self.sizes)
        fn = self.builder(l, **kw) if self.per_node_count else self.builder(**kw)
        if fn.name() != self.name:
            raise ValueError(f"{self.source} builds {fn.name()!r}, registered as {self.name!r}")
        return fn

    def origin(self, l: int) -> str:
        """The builder's call, as the banner names it."""
        args = ([f"l={l}"] if self.per_node_count else []) + [f"{k}={v!r}" for k, v in self.sizes]
        return f"{self.source}({', '.join(args)})"

    def c_name(self, config: CodegenConfig) -> str:
        """Its C symbol in a build: ``ql_casadi_control_step``."""
        return f"{config.prefix}casadi_{self.name}"

    def arguments(self, l: int) -> tuple[tuple[str, ...], tuple[str, ...]]:
        """Names of its inputs and outputs: the wrapper's arguments."""
        fn = self.function(l)
        return tuple(fn.name_in()), tuple(fn.name_out())


#: The sensors' truth models (``sense_<name>``), in the order of ``SENSOR_NAMES``.
SENSOR_BUILDERS = (sense_imu_function, sense_vision_function, sense_gnss_function,
                   sense_rangefinder_function, sense_datalink_function)


#: The CasADi functions written as C, in file order: the one registry.
FUNCTIONS = (
    GeneratedFunction("control_step", control_step_function),
    GeneratedFunction("closed_loop", closed_loop_function, wrapper="quadland_model.c",
                      doc="x_dot of the continuous-time closed loop "
                          "(quadland_symbolic.closed_loop)."),
    GeneratedFunction("closed_loop_jacobian", closed_loop_jacobian_function,
                      wrapper="quadland_jacobian.c",
                      doc="d x_dot / d x: the {QL}CLOSED_LOOP_JACOBIAN_NNZ nonzeros in "
                          "compressed\n * column storage; {ql}closed_loop_jacobian_sparsity "
                          "gives the pattern\n * (CasADi format: nrow, ncol, colind[ncol + 1], "
                          "row[nnz])."),
    GeneratedFunction("plant", plant_function, per_node_count=False, wrapper="quadland_model.c",
                      doc="xp_dot of the plant alone (quadrotor, vehicle, planar position) "
                          "under a\n * held wrench and disturbance w."),
    GeneratedFunction("landing_step", landing_step_function, part="landing"),
    GeneratedFunction("landing_guidance", landing_guidance_function, per_node_count=False,
                      part="landing"),
    *(GeneratedFunction(name, builder, per_node_count=False, wrapper="quadland_landing_model.c",
                        doc=doc, part="landing") for name, builder, doc in (
        ("landing_loop_plant", loop_plant_function,
         "xp_dot of the landing plant (quadrotor with motor lag, vehicle; the deck's\n"
         " * motion is prescribed) under held rotor commands and w = [v_wind (E), d_F,\n"
         " * d_M (body)]."),
        ("landing_sensors", measurement_function,
         "The landing step's measurements y from the plant's state: perfect sensors."),
        ("landing_cues", measured_cues_function,
         "The guidance's cues on perfect sensing from y and the guidance's\n"
         " * parameters: touchdown when the measured gear gap is at or below zero,\n"
         " * the marker's age 0."),
        ("landing_signals", landing_signals_function,
         "The landing trajectory's signals y ({QL}LANDING_NY): both bodies, the\n"
         " * relative state, the rotors, the external forces, phase and aborts."),
        ("landing_gear_gap", gear_gap_function,
         "The landing gear's height above the deck plane, m: touchdown is its zero\n"
         " * crossing."),
        ("landing_first_contact", first_contact_function,
         "The lowest foot's height above the deck plane, m: the gear's first\n"
         " * contact is its zero crossing (the integration goes on through it)."),
        ("landing_gear_signals", landing_gear_signals_function,
         "The gear's signals (foot and centre gaps, load, feet down, lock, relative\n"
         " * roll, pitch and tilt, tip-over and friction margins, the lowest foot's\n"
         " * sink rate, the farthest foot's offset) of the plant's state under the\n"
         " * held disturbance w (its wind in the friction margin)."),
        ("landing_anchor", anchor_function,
         "The pose at touchdown (p_e, R_deck^T R1) from the signals y there."),
        ("landed_row", landed_row_function,
         "A row of the ride after touchdown at t_td: the signals y and the state x1q\n"
         " * of the quadrotor pinned to the deck at anchor, its rotor forces winding\n"
         " * down from F_td, the phase LANDED from t_td + settle."),
        ("vehicle", vehicle_function, "xv_dot of the vehicle alone (eq. 3-4)."),
        *((f"sense_{name}", builder,
           f"The {name}'s packet y from the plant's state under its noise (a zero\n"
           " * noise vector: the exact truth; quadland_symbolic.landing.sensors).")
          for name, builder in zip(SENSOR_NAMES, SENSOR_BUILDERS, strict=True)),
        ("touchdown_figures", touchdown_figures_function,
         "Sink rate (m/s), offset (m), relative speed (m/s) and tilt (deg) of a\n"
         " * contact."),
    )),
    GeneratedFunction("landing_free_plant", loop_plant_function, per_node_count=False,
                      wrapper="quadland_landing_model.c", part="landing",
                      sizes=(("contact", False),),
                      doc="xp_dot of the landing plant in free flight: landing_loop_plant "
                          "without the\n * gear's contact, exactly zero while every foot is "
                          "far above the deck."),
    *(GeneratedFunction(name, builder, per_node_count=False, part="estimator",
                        sizes=ESTIMATOR_SIZES)
      for name, builder in (("estimator_step", estimator_step_function),
                            ("estimator_init", estimator_init_function))),
    *(GeneratedFunction(name, builder, per_node_count=False, part="land_detector")
      for name, builder in (("land_detector", land_detector_function),
                            ("land_detector_cues", detector_cues_function))),
)


BY_NAME = {f.name: f for f in FUNCTIONS}


#: The readable API's source of each part, which calls its functions without a wrapper.
API_FILE = {"paper": "quadland.c", "landing": "quadland_landing.c",
            "estimator": "quadland_estimator.c", "land_detector": "quadland_land_detector.c"}


def c_sources(functions=("control_step",)) -> tuple[str, ...]:
    """The ``.c`` files that link the API of ``functions`` (names in :data:`FUNCTIONS`).

    For each part (``quadland.h``, ``quadland_landing.h``,
    ``quadland_estimator.h``, ``quadland_land_detector.h``) a function belongs
    to (the paper's without any): its API file and the functions it calls (the
    paper's control step; the landing step and guidance; the filter's step and
    init; the detector's step and cues); each other
    function with its wrapper's file; ``quadland_status.c`` always.
    """
    unknown = set(functions) - set(BY_NAME)
    if unknown:
        raise ValueError(f"unknown generated functions {sorted(unknown)}")
    parts = [p for p in API_FILE if any(BY_NAME[f].part == p for f in functions)] or ["paper"]
    chosen = [f for f in FUNCTIONS
              if f.name in functions or (f.part in parts and f.wrapper is None)]
    files = [f"{f.name}.c" for f in chosen] + [API_FILE[p] for p in parts]
    for f in chosen:
        if f.wrapper and f.wrapper not in files:
            files.append(f.wrapper)
    return (*files, "quadland_status.c")

