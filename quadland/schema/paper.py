"""The schema of the paper's 4-DOF loop (``scenario.model = "paper"``, the default)."""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType

from quadland.exceptions import ScenarioError
from quadland.schema.fields import (
    MAX_DURATION_S,
    MAX_RATE_HZ,
    Field,
    one_line,
    safe_name,
    tilt_below_90,
)

__all__ = ["PAPER_SCHEMA", "check_paper", "check_rbf"]

F, I, B, S = float, int, bool, str
_POS = dict(lo=0.0, lo_open=True)
#: The scenario schema: section -> key -> Field. Every number has a physical range.
PAPER_SCHEMA: Mapping[str, Mapping[str, Field]] = MappingProxyType({
    "scenario": {
        "name": Field(S, "-", "short name, used for the output folder", check=safe_name),
        "description": Field(S, "-", "one line describing the scenario", check=one_line),
    },
    "simulation": {
        "duration": Field(F, "s", "simulated time", lo=1e-3, hi=MAX_DURATION_S),
        "output_rate_hz": Field(F, "Hz", "rows per second of trajectory.csv", lo=1e-3,
                                hi=MAX_RATE_HZ),
        "integrator": Field(S, "-", "rk: compiled RK4 on the exact grid; cvodes: CasADi's "
                            "variable-step reference (continuous loop)", choices=("cvodes", "rk")),
        "reltol": Field(F, "-", "cvodes relative tolerance", lo=1e-14, hi=1e-2),
        "abstol": Field(F, "-", "cvodes absolute tolerance", lo=1e-14, hi=1e-2),
        "rk_steps_per_interval": Field(I, "-", "RK4 steps per hold interval (rk)", lo=1,
                                       hi=1000),
        "seed": Field(I, "-", "seed of every random draw", lo=0, hi=2 ** 63 - 1),
    },
    "quadrotor": {
        "mass": Field(F, "kg", "m1", lo=1e-3, hi=1e4),
        "inertia": Field(F, "kg m^2", "Ix, Iy, Iz", 3, lo=1e-6, hi=1e4),
        "drag_translational": Field(F, "N s/m", "Kt1..Kt3", 3, lo=0.0, hi=1e3),
        "drag_rotational": Field(F, "N m s/rad", "Kr1..Kr3", 3, lo=0.0, hi=1e3),
        "gravity": Field(F, "m/s^2", "g_s", lo=0.1, hi=100.0),
        "arm_length": Field(F, "m", "d, centre to rotor axis", lo=1e-3, hi=10.0),
        "rotor_drag_factor": Field(F, "m", "c, yaw moment per unit thrust", lo=1e-4, hi=10.0),
        "rotor_force_min": Field(F, "N", "lower rotor-force limit (the sampled step clips)",
                                 lo=-1e6, hi=1e6),
        "rotor_force_max": Field(F, "N", "upper rotor-force limit (the sampled step clips)",
                                 lo=1e-3, hi=1e6),
    },
    "vehicle": {
        "m11": Field(F, "kg", "surge mass", lo=1e-3, hi=1e8),
        "m22": Field(F, "kg", "sway mass", lo=1e-3, hi=1e8),
        "m33": Field(F, "kg m^2", "yaw inertia", lo=1e-3, hi=1e10),
        "d11": Field(F, "kg/s", "surge damping", lo=0.0, hi=1e8),
        "d22": Field(F, "kg/s", "sway damping", lo=0.0, hi=1e8),
        "d33": Field(F, "kg m^2/s", "yaw damping", lo=0.0, hi=1e10),
        "tau": Field(F, "N, N, N m", "tau_x, tau_y, tau_z", 3, lo=-1e8, hi=1e8),
        "deck_altitude": Field(F, "m", "z2", lo=-1e4, hi=1e4),
    },
    "initial": {
        "z1": Field(F, "m", "quadrotor altitude", lo=-1e4, hi=1e4),
        "eta1_deg": Field(F, "deg", "roll, pitch, yaw", 3, lo=-3600.0, hi=3600.0,
                          check=tilt_below_90),
        "omega1_deg_s": Field(F, "deg/s", "body rates p, q, r", 3, lo=-1e4, hi=1e4),
        "velocity1": Field(F, "m/s", "body velocity u, v, w", 3, lo=-1e3, hi=1e3),
        "psi2_deg": Field(F, "deg", "vehicle heading", lo=-3600.0, hi=3600.0),
        "r2_deg_s": Field(F, "deg/s", "vehicle yaw rate", lo=-1e4, hi=1e4),
        "velocity2": Field(F, "m/s", "vehicle surge, sway", 2, lo=-1e3, hi=1e3),
        "position2": Field(F, "m", "vehicle x2, y2", 2, lo=-1e7, hi=1e7),
    },
    "reference": {
        "e1d": Field(F, "m, rad, rad, rad", "constant desired e1", 4, lo=-1e4, hi=1e4),
    },
    "controller": {
        "k1": Field(F, "1/s", "diagonal of k1", 4, hi=1e6, **_POS),
        "k2": Field(F, "1/s", "diagonal of k2", 4, hi=1e6, **_POS),
        "gamma1": Field(F, "-", "Gamma1 = gamma1 I", hi=1e6, **_POS),
        "gamma2": Field(F, "-", "Gamma2 = gamma2 I", hi=1e6, **_POS),
        "k_w": Field(F, "-", "W_hat leakage", hi=1e6, **_POS),
        "k_zeta": Field(F, "-", "zeta_hat leakage", hi=1e6, **_POS),
        "rho": Field(F, "-", "tanh width varrho", lo=1e-9, hi=1e6),
        "nominal_model": Field(B, "-", "feed forward the quadrotor's known dynamics"),
        "rate_hz": Field(F, "Hz", "control rate, 0 = continuous", lo=1.0, hi=MAX_RATE_HZ,
                         zero_ok=True),
        "backend": Field(S, "-", "control step implementation", choices=("casadi", "c")),
        "hold_compensation": Field(F, "periods", "extrapolation of the held command",
                                   lo=0.0, hi=1.0),
    },
    "rbf": {
        "nodes": Field(I, "-", "l, the number of nodes", lo=1, hi=1000),
        "center_min": Field(F, "-", "first centre coordinate", lo=-1e6, hi=1e6),
        "center_max": Field(F, "-", "last centre coordinate", lo=-1e6, hi=1e6),
        "width": Field(F, "-", "common spread epsilon", lo=1e-6, hi=1e6),
    },
    "disturbance": {
        "noise": Field(B, "-", "include the random part"),
        "sample_rate_hz": Field(F, "Hz", "hold interval of the disturbance", lo=1e-3,
                                hi=MAX_RATE_HZ),
        "force_bias": Field(F, "N", "constant part of d_F", 3, lo=-1e4, hi=1e4),
        "force_amplitude": Field(F, "N", "sine amplitude of d_F", lo=-1e4, hi=1e4),
        "force_frequency": Field(F, "rad/s", "sine frequency of d_F", lo=0.0, hi=1e5),
        "force_noise_std": Field(F, "N", "std of the noise on d_F", lo=0.0, hi=1e4),
        "moment_bias": Field(F, "N m", "constant part of d_M", 3, lo=-1e4, hi=1e4),
        "moment_amplitude": Field(F, "N m", "sine amplitude of d_M", lo=-1e4, hi=1e4),
        "moment_frequency": Field(F, "rad/s", "sine frequency of d_M", lo=0.0, hi=1e5),
        "moment_noise_std": Field(F, "N m", "std of the noise on d_M", lo=0.0, hi=1e4),
    },
})
del F, I, B, S


def check_rbf(data: dict) -> None:
    """The ``[rbf]`` section's rule across keys (the landing schema shares the section)."""
    nodes = data["rbf"]
    if nodes["center_max"] < nodes["center_min"]:
        raise ScenarioError("rbf.center_max: must be >= rbf.center_min")


def check_paper(data: dict) -> None:
    """The paper schema's cross-key rules."""
    check_rbf(data)
    q = data["quadrotor"]
    if q["rotor_force_max"] <= q["rotor_force_min"]:
        raise ScenarioError("quadrotor.rotor_force_max: must be > quadrotor.rotor_force_min")
    if data["simulation"]["integrator"] == "cvodes" and data["controller"]["rate_hz"] > 0:
        raise ScenarioError("simulation.integrator: cvodes integrates the continuous loop only "
                            "(controller.rate_hz = 0); the sampled-data loop takes RK4 steps "
                            "(raise simulation.rk_steps_per_interval for accuracy)")
