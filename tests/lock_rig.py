"""The magnets' rig the foot-magnet tests share: highway_100's gear (feet at ``(+-FX,
+-FY, -H)``) over a still, flat car roof, and the lock's wrench as a CasADi Function."""

import functools

import casadi as ca
import numpy as np

from quadland_symbolic.landing.contact import GEAR, LOCK, gear_defaults, lock_defaults, lock_wrench
from quadland_symbolic.landing.deck import DECK_PARAMS, pack_deck
from quadland_symbolic.landing.quadrotor import QUAD6_STATE
from quadland_symbolic.parameters import VEHICLE
from quadland_symbolic.vehicle import VEHICLE_STATE

FX, FY, H = 0.30, 0.20, 0.15                      # m: highway_100's gear
F_HOLD, G0 = 200.0, 1e-3                          # N, m: its two magnets' force, the gap scale


@functools.cache
def lock_function() -> ca.Function:
    """``lock_wrench`` as ``lock(x1q, xv, t, t_switch, p_vehicle, p_deck, p_gear, p_lock)``."""
    x1q, xv, t, ts = QUAD6_STATE.sym(), VEHICLE_STATE.sym(), ca.SX.sym("t"), ca.SX.sym("ts")
    pv, pd, pg, pl = VEHICLE.sym(), DECK_PARAMS.sym(), GEAR.sym(), LOCK.sym()
    return ca.Function("lock", [x1q, xv, t, ts, pv, pd, pg, pl],
                       list(lock_wrench(x1q, xv, t, ts, pv, pd, pg, pl)))


def lock_packs(at_feet: int = 1, **lock):
    """The vehicle's, the deck's, the gear's and the lock's packed parameters: a still car,
    a flat deck at 0, the rig's feet, the magnets (in the feet or under the centre) at
    ``F_HOLD`` and ``G0``, on at once, with ``lock``'s keys over them."""
    veh = dict(m11=1500.0, m22=1500.0, m33=2500.0, d11=150.0, d22=1500.0, d33=2500.0,
               tau=[0.0, 0.0, 0.0], z2=0.0)
    d = {f"{n}_{w}": np.zeros(3) for n in ("heave", "roll", "pitch")
         for w in ("amp", "freq", "phase")}
    d.update(pad_offset=[0.0, 0.0, 0.0], deck_height=0.0)
    g = gear_defaults("car_roof")
    g["r_feet"] = [v for f in ((FX, FY, -H), (-FX, FY, -H), (-FX, -FY, -H), (FX, -FY, -H))
                   for v in f]
    lk = dict(lock_defaults("foot_magnets" if at_feet else "magnet"), F_hold=F_HOLD,
              lock_delay=0.0, lock_gap_scale=G0)
    lk.update(lock)
    return VEHICLE.pack(veh), pack_deck(d), GEAR.pack(g), LOCK.pack(lk)
