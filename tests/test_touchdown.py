"""Touchdown located within the step: free fall onto a heaving deck, in closed form.

A level, non-rotating quadrotor with its rotors off and no drag falls
freely: ``z1(t) = z0 - g t^2 / 2``. The deck heaves as ``h + A sin(w t + phi)``
and neither rolls nor pitches, so the gear meets it when
``z0 - g t^2 / 2 - gear_height - h - A sin(w t + phi) = 0``, solved here by
Brent's method. The simulator's drivers (compiled and on CasADi's VM) run
the 6-DOF plant of ``quadland_symbolic.landing`` with the gear gap as their event
and must stop at that instant, found within a 10 ms step.
"""

import casadi as ca
import numpy as np
import pytest
import scipy.optimize
from reference import NO_AERO

from quadland.engine.compiled import SIM_EVENT, CompiledLoop, VMLoop
from quadland.engine.loop import Clock
from quadland_symbolic.landing.deck import N_DECK, pack_deck
from quadland_symbolic.landing.gear import contact_params
from quadland_symbolic.landing.plant import (
    LANDING_PLANT_PARAMS,
    LANDING_PLANT_STATE,
    landing_plant_function,
)
from quadland_symbolic.landing.quadrotor import ACTUATOR, COMMAND, QUAD6_STATE
from quadland_symbolic.landing.relative import gear_gap
from quadland_symbolic.layout import Field, Layout
from quadland_symbolic.loop import LoopModel
from quadland_symbolic.parameters import QUADROTOR, VEHICLE
from quadland_symbolic.quadrotor import BODY_DISTURBANCE
from quadland_symbolic.vehicle import VEHICLE_STATE

G, Z0, GEAR, H, A, W, PHI = 9.81, 6.0, 0.25, 1.5, 0.68, 0.349, 0.7


def _free_fall_model() -> LoopModel:
    """The landing plant behind a controller that keeps the rotors off."""
    xp, w, t = LANDING_PLANT_STATE.sym(), BODY_DISTURBANCE.sym(), ca.SX.sym("t")
    pp = LANDING_PLANT_PARAMS.sym()
    none = Layout("none", (Field("unused", 1, "-", "no memory"),))
    xc, pc, first = none.sym(), none.sym(), ca.SX.sym("first")
    uh = COMMAND.sym()
    plant = ca.Function("plant", [xp, uh, w, t, pp], [landing_plant_function()(xp, uh, w, t, pp)],
                        ["xp", "uh", "w", "t", "pp"], ["xp_dot"])
    controller = ca.Function("controller", [xp, xc, pc, first, t],
                             [xc, ca.DM.zeros(4), ca.DM.zeros(1), ca.DM.ones(1)],
                             ["xp", "xc", "pc", "first", "t"], ["xc_next", "uh", "rec", "guard"])
    assemble = ca.Function("assemble", [xp, xc], [xp], ["xp", "xc"], ["x"])
    x, p = LANDING_PLANT_STATE.sym(), LANDING_PLANT_PARAMS.sym()
    s, ps = LANDING_PLANT_STATE.unpack(x), LANDING_PLANT_PARAMS.unpack(p)
    gap = gear_gap(s["x1q"], s["xv"], t, ps["p_act"], ps["p_veh"], ps["p_deck"])
    outputs = ca.Function("outputs", [x, w, t, p], [gap], ["x", "w", "t", "p"], ["y"])
    rhs = ca.Function("rhs", [x, w, t, p], [ca.DM.zeros(LANDING_PLANT_STATE.size)],
                      ["x", "w", "t", "p"], ["x_dot"])
    sp, spp = LANDING_PLANT_STATE.unpack(xp), LANDING_PLANT_PARAMS.unpack(pp)
    event = ca.Function("event", [xp, t, pp],
                        [gear_gap(sp["x1q"], sp["xv"], t, spp["p_act"], spp["p_veh"],
                                  spp["p_deck"])], ["xp", "t", "pp"], ["g"])
    gap_layout = Layout("gap", (Field("gear_gap", 1, "m", "gear above the deck"),))
    return LoopModel("freefall", LANDING_PLANT_STATE, BODY_DISTURBANCE, LANDING_PLANT_PARAMS,
                     gap_layout, rhs,
                     outputs, LANDING_PLANT_STATE, COMMAND, none, LANDING_PLANT_PARAMS, none,
                     Layout("rec", (Field("r", 1, "-", "nothing"),)), plant, controller,
                     assemble, event=event)


def _params():
    zeros = np.zeros(N_DECK)
    deck = pack_deck(dict(
        heave_amp=[A, 0, 0], heave_freq=[W, 0, 0], heave_phase=[PHI, 0, 0],
        roll_amp=zeros, roll_freq=zeros, roll_phase=zeros, pitch_amp=zeros,
        pitch_freq=zeros, pitch_phase=zeros, pad_offset=np.zeros(3), deck_height=H))
    quad = QUADROTOR.pack(dict(m1=2.0, I=[1.2416, 1.2416, 2.4832], Kt=np.zeros(3),
                               Kr=np.zeros(3), g=G, arm=0.25, c=0.05))
    act = ACTUATOR.pack(dict(motor_time_constant=0.02, F_max=10.0, gear_height=GEAR,
                             rotor_efficiency=[1.0] * 4, cg_offset=[0.0] * 3, **NO_AERO))
    veh = VEHICLE.pack(dict(m11=100, m22=100, m33=80, d11=100, d22=100, d33=80,
                            tau=np.zeros(3), z2=0.0))
    return LANDING_PLANT_PARAMS.pack(dict(p_quad=quad, p_act=act, p_veh=veh, p_deck=deck,
                                          **contact_params()))


def _meeting_time():
    def gap(t):
        return Z0 - G * t * t / 2 - GEAR - H - A * np.sin(W * t + PHI)
    grid = np.linspace(0, 5, 5001)
    k = int(np.argmax(gap(grid) <= 0))
    return scipy.optimize.brentq(gap, grid[k - 1], grid[k], xtol=1e-15, rtol=1e-15)


@pytest.mark.parametrize("loop_kind", [CompiledLoop, VMLoop], ids=["compiled", "vm"])
def test_free_fall_meets_a_heaving_deck_at_the_closed_form_time(loop_kind):
    model = _free_fall_model()
    loop = loop_kind(model, "sampled")
    x1q = QUAD6_STATE.pack(dict(p1=[3.0, -2.0, Z0], eta1=np.zeros(3), V1=np.zeros(3),
                                Omega1=np.zeros(3), F=np.zeros(4)))
    xp0 = LANDING_PLANT_STATE.pack(dict(x1q=x1q, xv=VEHICLE_STATE.zeros(), gear=np.zeros(3)))
    clocks = (Clock(100.0, 0.0, 5.0, True), Clock(100.0, 0.0, 5.0, True),
              Clock(100.0, 0.0, 5.0, False))                # 10 ms steps up to 5 s
    run = loop.sampled(xp0, np.zeros(1), clocks, np.zeros((501, BODY_DISTURBANCE.size)), 1,
                       _params(),
                       np.zeros(1), 1e-3)
    t_meet = _meeting_time()
    assert run.status == SIM_EVENT
    assert run.t_stop == pytest.approx(t_meet, abs=1e-10)
    # the state at the event: the gear on the deck, falling at g t
    end = LANDING_PLANT_STATE.unpack(run.x_end[:LANDING_PLANT_STATE.size])
    z1, w1 = end["x1q"][2], end["x1q"][8]
    assert z1 - GEAR == pytest.approx(H + A * np.sin(W * t_meet + PHI), abs=1e-9)
    assert w1 == pytest.approx(-G * t_meet, rel=1e-12)
    # rows before the event are recorded; the step that holds it is not
    last = int(t_meet / 0.01)
    assert run.rows == last + 1 and run.times[-1] == pytest.approx(last * 0.01, abs=1e-12)
    recorded = LANDING_PLANT_STATE.unpack(run.X[last].copy())
    assert recorded["x1q"][2] == pytest.approx(Z0 - G * (last * 0.01) ** 2 / 2, abs=1e-12)
