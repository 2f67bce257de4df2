"""The pure-C example: flights, benchmark, scenario headers and Makefile."""

from __future__ import annotations

import numpy as np

from quadland_symbolic.closed_loop import (
    PAPER_PLANT_STATE,
    closed_loop_state,
)
from quadland_symbolic.codegen.config import Defaults, LandingDefaults
from quadland_symbolic.codegen.registry import FUNCTIONS, c_sources
from quadland_symbolic.codegen.render import common_context, render
from quadland_symbolic.codegen.simulator import loop_header
from quadland_symbolic.codegen.structs import (
    output_layout,
)
from quadland_symbolic.landing.contact import N_FEET
from quadland_symbolic.landing.gear import CUT_THRUST, FAILURES, GEAR_SIGNALS, GEAR_STATE
from quadland_symbolic.landing.guidance import (
    GUIDANCE_STATE,
)
from quadland_symbolic.landing.land_detector import LAND_DETECTOR_PARAMS
from quadland_symbolic.landing.navigation import (
    BLOCKS,
    DECK_INIT,
    IMU,
    NAV,
    estimator_params,
)
from quadland_symbolic.landing.plant import (
    LANDING_DISTURBANCE,
    LANDING_PLANT_PARAMS,
    LANDING_PLANT_STATE,
)
from quadland_symbolic.landing.quadrotor import QUAD6_STATE
from quadland_symbolic.landing.relative import TOUCHDOWN_FIGURES
from quadland_symbolic.landing.sensed_loop import (
    DELIVERY_SLOTS,
    NAV_PACKET_OF,
    SENSED_TRAJECTORY,
    delivery_record,
)
from quadland_symbolic.landing.sensors import NOISES, SENSOR_NAMES, SENSOR_PACKETS, SENSOR_PARAMS
from quadland_symbolic.landing.signals import LANDING_SIGNALS, LANDING_TRAJECTORY
from quadland_symbolic.layout import Layout
from quadland_symbolic.parameters import QUADROTOR
from quadland_symbolic.quadrotor import QUAD_STATE
from quadland_symbolic.relative import E1
from quadland_symbolic.vehicle import VEHICLE_MEASUREMENT, VEHICLE_STATE

__all__ = ["example_columns", "example_context", "LAND_ESTIMATE", "land_columns", "land_context",
           "LAND_MODEL", "generate_example"]


def example_columns(l: int) -> list[tuple[str, str]]:
    """Columns of the example's CSV: ``(name, C expression)``, names from the layouts.

    The names are the layouts' element names, the same as
    ``quadland.kinds.paper.simulate.TRAJECTORY``'s for the same signals; ``n_clipped``
    and ``status`` are the example's own (ints, last). The expressions read
    the closed-loop state ``x``, the step's output ``out`` and the vehicle's
    parameters ``vehicle``.
    """
    x = closed_loop_state(l)
    names = x.element_names()

    def at(name):
        return f"(double)x[{names.index(name)}]"

    xq, xv, pos1, zeta = (x.slice(n) for n in ("xq", "xv", "pos1", "zeta_hat"))
    # e1 = [z1 - z2, phi1 - phi2, theta1 - theta2, psi1 - psi2] with phi2 = theta2 = 0 (eq. 5, 7)
    e1 = {"z_e": f"{at('z1')} - (double)vehicle->z2", "phi_e": at("phi1"), "theta_e": at("theta1"),
          "psi_e": f"{at('psi1')} - {at('psi2')}"}
    cols = [("t", "t")]
    cols += [(n, e1[n]) for n in E1.element_names()]
    cols += [(names[i], at(names[i])) for s in (xq, xv, pos1) for i in range(s.start, s.stop)]
    for fname in ("u", "wrench", "rotor"):
        f = output_layout(l)[fname]
        cols += [(n, f"(double)out->{fname}[{i}]") for i, n in enumerate(f.element_names())]
    cols += [(names[i], at(names[i])) for i in range(zeta.start, zeta.stop)]
    cols += [("norm_W_hat", "sqrt(norm_W_hat)"), ("n_clipped", "out->n_clipped"),
             ("status", "status")]
    return cols


def example_context(d: Defaults) -> dict:
    l = d.l
    x = closed_loop_state(l)
    cols = example_columns(l)
    n_real = len(cols) - 2
    xq0 = x.slice("xq").start
    xv_names = VEHICLE_STATE.element_names()
    vehicle = []
    for f in VEHICLE_MEASUREMENT.fields:
        if f.name in xv_names:
            i = x.slice("xv").start + xv_names.index(f.name)
            vehicle.append(dict(name=f.name, expr=f"x[{i}]"))
        else:
            vehicle.append(dict(name=f.name, expr=f"vehicle->{f.name}"))
    offsets = QUAD_STATE.offsets()
    return dict(
        common_context(None),
        scenario=d.scenario,
        columns=[n for n, _ in cols],
        real_columns=[dict(name=n, expr=e) for n, e in cols[:n_real]],
        int_columns=[dict(name=n, expr=e) for n, e in cols[n_real:]],
        quad=[dict(name=f.name, offset=xq0 + offsets[f.name][0], size=f.size)
              for f in QUAD_STATE.fields],
        z1=xq0 + offsets["z1"][0],
        vehicle=vehicle,
        plant=[dict(name=f.name, xp=PAPER_PLANT_STATE.slice(f.name).start, x=x.slice(f.name).start,
                    size=f.size) for f in PAPER_PLANT_STATE.fields],
        W_hat=x.slice("W_hat").start, zeta_hat=x.slice("zeta_hat").start,
        d=d,
        bias=[repr(float(v)) for v in (*d.force_bias, *d.moment_bias)],
        x0_rows=[[repr(float(v)) for v in d.x0[i:i + 6]] for i in range(0, len(d.x0), 6)],
        x0_size=len(d.x0),
        step_sources=c_sources(),
        model_sources=c_sources(("closed_loop", "plant")),
    )


#: What the sensed example records of each control step for its CSV (the columns of
#: ``SENSED_TRAJECTORY`` that are not signals): the filter's estimate and its sigmas.
LAND_ESTIMATE = Layout("est", tuple(f for f in SENSED_TRAJECTORY.fields
                                    if f.name != "t" and f.name not in LANDING_SIGNALS.names()),
                       "the sensed example's recorded signals")


def land_columns(sensed: bool = False) -> list[tuple[str, str]]:
    """Columns of the example ``land``'s CSV: ``(name, C expression)``, from the layouts.

    The names are ``quadland_symbolic.landing.signals.LANDING_TRAJECTORY``'s (``quadland
    simulate``'s trajectory.csv of a landing), on sensors (``sensed``)
    ``quadland_symbolic.landing.sensed_loop.SENSED_TRAJECTORY``'s; the expressions read
    the time ``t``, the signals ``y`` (``quadland_symbolic.landing.loop.LANDING_SIGNALS``)
    and on sensors the recorded estimate ``est`` (:data:`LAND_ESTIMATE`).
    """
    cols = []
    for f in (SENSED_TRAJECTORY if sensed else LANDING_TRAJECTORY).fields:
        if f.name == "t":
            cols.append(("t", "t"))
            continue
        vec, lay = ("y", LANDING_SIGNALS) if f.name in LANDING_SIGNALS.names() else \
            ("est", LAND_ESTIMATE)
        at = lay.slice(f.name).start
        cols += [(n, f"(double){vec}[{at + i}]") for i, n in enumerate(f.element_names())]
    return cols


def _sensed_context(d: LandingDefaults) -> dict | None:
    """The sensed example's sensors, delay lines and flight code, from the layouts."""
    s = d.sensors
    if s is None:
        return None
    sensors = []
    for k, name in enumerate(SENSOR_NAMES):
        packet, record = SENSOR_PACKETS[name], delivery_record(name)
        sensors.append(dict(
            name=name, index=k, packet_size=packet.size, noise_size=NOISES[name].size,
            record_size=record.size, every=s.every[k], first=s.first[k], delay=s.delay[k],
            valid=packet.slice("valid").start if "valid" in packet.names() else None,
            values=[dict(name=f.name, record=record.slice(f.name).start,
                         packet=packet.slice(f.name).start, size=f.size)
                    for f in record.fields[2:]],
            struct=None if name == "imu" else f"{NAV_PACKET_OF[name].name}_packet"))
    return dict(
        sensors=sensors, slots=DELIVERY_SLOTS,
        max_noise=max(x["noise_size"] for x in sensors),
        max_packet=max(x["packet_size"] for x in sensors),
        max_record=max(x["record_size"] for x in sensors),
        vision_block=[b.name for b in BLOCKS].index("vision"),
        est=[dict(name=f.name, offset=LAND_ESTIMATE.slice(f.name).start, size=f.size)
             for f in LAND_ESTIMATE.fields], est_size=LAND_ESTIMATE.size,
        vectors={name: _rows(getattr(s, attr)) for name, attr in (
            ("p_sens", "p_sens"), ("p_est", "p_est"), ("p_ld", "p_ld"), ("nav0", "nav0"),
            ("P0_diag", "P0_diag"), ("deck0", "deck0"), ("imu0", "imu0"))},
        fields={name: ", ".join(f"{f.name} ({f.size})" for f in lay.fields) for name, lay in (
            ("p_sens", SENSOR_PARAMS), ("p_est", estimator_params()),
            ("p_ld", LAND_DETECTOR_PARAMS), ("nav0", NAV), ("deck0", DECK_INIT),
            ("imu0", IMU))},
    )


def _rows(values) -> list[list[str]]:
    values = [repr(float(v)) for v in np.asarray(values, dtype=float).ravel()]
    return [values[i:i + 6] for i in range(0, len(values), 6)]


def land_context(d: LandingDefaults) -> dict:
    """The example ``land``'s context: its scenario's values and the layouts' offsets."""
    def fields(layout):
        return ", ".join(f"{f.name} ({f.size})" for f in layout.fields)

    x1q = LANDING_PLANT_STATE.slice("x1q").start
    return dict(
        d=d,
        sensed=_sensed_context(d),
        columns=[dict(name=n, expr=e) for n, e in land_columns(d.sensors is not None)],
        xg=[dict(name=n, index=i) for i, n in enumerate(GUIDANCE_STATE.names())],
        w={n: a for n, (a, _) in LANDING_DISTURBANCE.offsets().items()},
        y={n: LANDING_SIGNALS.slice(n).start for n in ("p_e", "v_e", "eta1", "eta2")}
        | {"psi1": LANDING_SIGNALS.index("psi1")},
        figures=[dict(name=n, index=i, limit="max_" + n)
                 for i, n in enumerate(TOUCHDOWN_FIGURES.names())],
        limits=[(name, repr(float(v))) for name, v in d.limits],
        bias=[repr(float(v)) for v in (*d.force_bias, *d.moment_bias)],
        wind_mean=[repr(float(v)) for v in d.wind_mean],
        gust_direction=[repr(float(v)) for v in d.gust_direction],
        pp_rows=_rows(d.pp), pp_size=len(d.pp), pp_fields=fields(LANDING_PLANT_PARAMS),
        xp_rows=_rows(d.xp0), xp_size=len(d.xp0), xp_fields=fields(LANDING_PLANT_STATE),
        xv=LANDING_PLANT_STATE.slice("xv").start, x1q_size=QUAD6_STATE.size,
        rotors=x1q + QUAD6_STATE.slice("F").start,
        p_veh=LANDING_PLANT_PARAMS.slice("p_veh").start,
        gear={n: LANDING_PLANT_STATE.slice("gear").start + GEAR_STATE.slice(n).start
              for n in GEAR_STATE.names()},
        gs={n: GEAR_SIGNALS.slice(n).start for n in GEAR_SIGNALS.names()}, ngs=GEAR_SIGNALS.size,
        failures=FAILURES, n_feet=N_FEET, ny_F_total=LANDING_SIGNALS.index("F_total"),
        cut_thrust=repr(float(CUT_THRUST * d.mass * np.ravel(
            QUADROTOR.unpack(np.asarray(d.p_quad, dtype=float))["g"])[0])),
    )


#: The landing model's functions the example ``land`` calls.
LAND_MODEL = tuple(f.name for f in FUNCTIONS if f.part == "landing" and f.wrapper is not None)


def generate_example(defaults: Defaults, landing: LandingDefaults) -> dict[str, str]:
    """Text of the pure-C example: flights, benchmark, scenario headers and Makefile.

    ``fly.c`` flies the paper's scenario (``defaults``, ``scenario.h``),
    ``land.c`` the landing scenario (``landing``, ``land_scenario.h``),
    ``bench.c`` times either step or the navigation filter. The sources are precision-independent
    (``ql_real``; the float header spells its names ``ql_`` too when it is
    the only build included); the Makefile builds them against both the
    double (``../``) and the float (``../float/``) files.
    """
    status = "quadland_status.c"
    paper = example_context(defaults)
    paper.update(land_scenario=landing.scenario, common_sources=[status],
                 step_sources=[f for f in paper["step_sources"] if f != status],
                 land_sources=[f for f in c_sources(LAND_MODEL) if f != status],
                 estimator_sources=[f for f in c_sources(("estimator_step",)) if f != status],
                 detector_sources=[f for f in c_sources(("land_detector",)) if f != status],
                 land_sensed=landing.sensors is not None)
    land = dict(common_context(None), scenario=landing.scenario, **land_context(landing))
    files = {f"example/{name}": render(f"example/{name}.jinja", **paper)
             for name in ("scenario.h", "fly.c", "bench.c", "Makefile")}
    files.update({f"example/{name}": render(f"example/{name}.jinja", **land)
                  for name in ("land_scenario.h", "land.c")})
    files["example/quadland_loop.h"] = loop_header()
    return files

