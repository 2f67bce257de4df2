"""Emitter settings and the scenario values the generated C carries."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import numpy as np

__all__ = ["TEMPLATE_DIR", "STATUS_CODES", "CodegenConfig", "DEFAULT_CONFIG", "FlightDefaults",
           "Defaults", "SensorDefaults", "LandingDefaults"]

#: Folder of the Jinja2 templates (installed with the package).
TEMPLATE_DIR = Path(__file__).resolve().parent.parent / "templates"


#: Status codes of ``ql_control_step`` and ``ql_check_params`` (name in the
#: double build, value, meaning).
STATUS_CODES = (
    ("QL_OK", 0, "success; outputs and adaptive state updated"),
    ("QL_ERR_NULL", 1, "a NULL pointer argument"),
    ("QL_ERR_INVALID", 2, "dt <= 0, or a state out of range (guidance, filter memory)"),
    ("QL_ERR_NONFINITE_INPUT", 3, "an input, a parameter or the state is NaN or infinite"),
    ("QL_ERR_TILT", 4, "|cos(theta1) cos(phi1)| < tilt_min: thrust map not invertible"),
    ("QL_ERR_NONFINITE_OUTPUT", 5,
     "the law overflowed: a NaN or infinite value from finite inputs"),
    ("QL_ERR_PARAM", 6, "a parameter outside its range (ql_check_params names it)"),
)


@dataclasses.dataclass(frozen=True)
class CodegenConfig:
    """Emitter settings of the generated C.

    Attributes
    ----------
    precision : {"double", "float"}
        Type of every real; ``"float"`` also writes float constants
        (``1.5f``) and calls float math (``expf``).
    prefix : str, optional
        Prefix of every global C name of the build (functions, types and,
        upper-cased, macros and enumerators); ``"ql_"`` for double and
        ``"qlf_"`` for float by default.
    casadi_int : str
        C type of CasADi's integers (sparsity patterns).
    null_checks : bool
        Keep CasADi's convention that a NULL ``arg[i]`` reads as zeros and
        a NULL ``res[i]`` is skipped. Off by default: the tests cost two
        instructions per scalar read or written (a fifth of the control
        step), and every caller in the generated API passes all pointers.
    builder : str
        Name of the command that regenerates, written into each header.
    """

    precision: str = "double"
    prefix: str | None = None
    casadi_int: str = "int"
    null_checks: bool = False
    builder: str = "quadland codegen (symbolic/codegen/)"

    def __post_init__(self):
        if self.precision not in ("double", "float"):
            raise ValueError(f"precision must be 'double' or 'float', got {self.precision!r}")
        if self.prefix is None:
            object.__setattr__(self, "prefix", "ql_" if self.precision == "double" else "qlf_")
        if not re.fullmatch(r"[a-z][a-z0-9]*_", self.prefix):
            raise ValueError(f"prefix must be lower-case letters and digits ending in '_', "
                             f"got {self.prefix!r}")

    @property
    def is_float(self) -> bool:
        """True for the single-precision build."""
        return self.precision == "float"

    @property
    def macro_prefix(self) -> str:
        """Prefix of the build's macros and enumerators (``QL_``)."""
        return self.prefix.upper()

    def literal(self, value: float) -> str:
        """A C literal of ``value`` in this precision (shortest round trip)."""
        text = repr(float(value))
        if not np.isfinite(value):
            raise ValueError(f"non-finite default {value}")
        if "." not in text and "e" not in text:
            text += ".0"
        return text + ("f" if self.is_float else "")

    def math(self, name: str) -> str:
        """Name of the C math function ``name`` in this precision."""
        return name + ("f" if self.is_float else "")


#: The double-precision build's settings, the default of every emitter.
DEFAULT_CONFIG = CodegenConfig()


@dataclasses.dataclass(frozen=True)
class FlightDefaults:
    """What every flight's C defaults hold: the scenario, the network, the example's clocks
    and its deterministic disturbance.

    Attributes
    ----------
    scenario : str
        Which scenario they are, for the comments: its name and overrides
        (never a path, so that the output does not depend on the machine).
    l : int
        RBF node count.
    tilt_min : float
        Smallest accepted ``|cos(theta1) cos(phi1)|``.
    duration, output_rate_hz, control_rate_hz, disturbance_rate_hz : float
        The example's flight: s, Hz, Hz (0 = continuous, the paper's loop
        only), Hz.
    force_bias, moment_bias : tuple of float
        N, N m, per axis.
    force_amplitude, force_frequency, moment_amplitude, moment_frequency : float
        The disturbance's sine: N, rad/s, N m, rad/s.
    """

    scenario: str
    l: int
    tilt_min: float
    duration: float
    output_rate_hz: float
    control_rate_hz: float
    disturbance_rate_hz: float
    force_bias: tuple[float, float, float]
    force_amplitude: float
    force_frequency: float
    moment_bias: tuple[float, float, float]
    moment_amplitude: float
    moment_frequency: float


@dataclasses.dataclass(frozen=True)
class Defaults(FlightDefaults):
    """Numeric defaults of the paper's step and its example (one scenario's values).

    Attributes
    ----------
    p_quad, p_veh, p_ctrl : ndarray
        Parameter vectors in the layouts of ``quadland_symbolic.parameters``.
    ref : ndarray, (12,)
        ``[e1d, e1d_dot, e1d_ddot]``.
    rotor_limits : tuple of float
        ``(F_min, F_max)``, N.
    hold : float
        Hold compensation of the control step, periods.
    x0 : ndarray
        Initial closed-loop state.

    The rest is :class:`FlightDefaults`'.
    """

    p_quad: np.ndarray
    p_veh: np.ndarray
    p_ctrl: np.ndarray
    ref: np.ndarray
    rotor_limits: tuple[float, float]
    hold: float
    x0: np.ndarray


@dataclasses.dataclass(frozen=True)
class SensorDefaults:
    """What the example ``land`` needs to fly a landing on its sensors (random parts off).

    Attributes
    ----------
    p_sens, p_est, p_ld : ndarray
        The sensors' constants (``quadland_symbolic.landing.sensors.SENSOR_PARAMS``),
        the filter's parameters (``estimator_params()``) and the land detector's
        (``LAND_DETECTOR_PARAMS``), the scenario's.
    every, first, delay : tuple of int
        Per sensor (``SENSOR_NAMES``' order): control ticks between two samples,
        the tick of the first, and the ticks from a sample to its reading.
    nav0, P0_diag, deck0 : ndarray
        The filter's handover (``ql_estimator_init``) at t = 0, its initial
        estimate the truth.
    imu0 : ndarray
        The IMU sample held before the first arrives.
    """

    p_sens: np.ndarray
    p_est: np.ndarray
    p_ld: np.ndarray
    every: tuple[int, ...]
    first: tuple[int, ...]
    delay: tuple[int, ...]
    nav0: np.ndarray
    P0_diag: np.ndarray
    deck0: np.ndarray
    imu0: np.ndarray


@dataclasses.dataclass(frozen=True)
class LandingDefaults(FlightDefaults):
    """Numeric defaults of the landing API and its example (one landing scenario's values).

    Attributes
    ----------
    p_quad, p_ctrl, p_act, p_guid : ndarray
        ``quadland_symbolic.parameters.QUADROTOR``, ``landing_controller_params(l)``,
        ``quadland_symbolic.landing.quadrotor.ACTUATOR``,
        ``quadland_symbolic.landing.guidance.GUIDANCE_PARAMS``.
    pp, xp0 : ndarray
        The example's plant parameters (``quadland_symbolic.landing.plant.LANDING_PLANT_PARAMS``)
        and initial plant state.
    rk_steps : int
        RK4 steps per interval of the merged time grid.
    delay_periods : int
        The computation delay: a step's rotor commands act this many control
        periods later.
    wind_mean : tuple of float
        m/s, E.
    gust_start, gust_half_length, gust_amplitude : float
        The 1-cosine gust: s, s, m/s (0: none).
    gust_direction : tuple of float
        Unit vector in E.
    settle_time : float
        s from touchdown to the end of the run.
    limits : tuple of (str, float)
        The touchdown limits by name (``max_sink_rate``, ...), in report order: the
        first-contact figures', then the gear's (``max_gear_load``, ...).
    h_after : float
        s, the longest RK4 step from the gear's first contact on.
    free_gap : float
        m: above it (the lowest foot's height over the deck at both ends of a grid
        interval) the plant without the contact flies (``landing_free_plant``).
    mass : float
        kg, the quadrotor's (the impact energy's).
    gear_span : float
        m, twice the farthest foot's distance from the centre: a run that stops with
        its lowest foot within it of the deck stopped on the deck (tipped over).
    sensors : SensorDefaults or None
        The example's sensors, filter and land detector (``sensors.enabled``);
        None: it flies on perfect sensing.

    The rest is :class:`FlightDefaults`'.
    """

    p_quad: np.ndarray
    p_ctrl: np.ndarray
    p_act: np.ndarray
    p_guid: np.ndarray
    pp: np.ndarray
    xp0: np.ndarray
    rk_steps: int
    delay_periods: int
    wind_mean: tuple[float, float, float]
    gust_start: float
    gust_half_length: float
    gust_amplitude: float
    gust_direction: tuple[float, float, float]
    settle_time: float
    limits: tuple[tuple[str, float], ...]
    h_after: float = 1e-3
    free_gap: float = 0.1
    mass: float = 2.0
    gear_span: float = 0.56
    sensors: SensorDefaults | None = None

