"""The sensed loop's world stage without the gear's contact far from the deck (issue 20).

The world stage (``sensed_world``) reads the IMU's truth, the specific force, off the
plant's derivative with the gear's contact. Its free function
(:attr:`quadland_symbolic.stages.Staged.free`) reads it off the plant without the contact;
the compiled simulator calls it where its driver flies the free plant (the lowest foot
more than ``near`` above the deck, before the first contact). The references: the stage
itself, evaluated by CasADi on the runtime's own arguments at gaps of 1,000 and 800 onset
widths (the contact exactly zero: ``tests/test_free_plant.py``'s bound of 746) against
the free function, bit for bit, and at a foot in the deck (they differ there); and,
compiled, the same model built without the free function (``staged_c.FREE_STAGES`` off,
the simulator as it was), flown on the runtime's arguments, every row, signal and state
bit for bit.
"""

from __future__ import annotations

import dataclasses

import casadi as ca
import numpy as np
import pytest
from flight_capture import captured

from quadland.engine.compiled import CompiledLoop, built_model
from quadland_symbolic.codegen import simulator, staged_c
from quadland_symbolic.landing.contact import contact_function
from quadland_symbolic.landing.loop import first_contact_function
from quadland_symbolic.landing.plant import LANDING_PLANT_PARAMS, LANDING_PLANT_STATE
from quadland_symbolic.landing.quadrotor import QUAD6_STATE
from quadland_symbolic.stages import Staged


def _bits(v) -> np.ndarray:
    return np.asarray(v, dtype=float).view(np.uint64)


@pytest.fixture(scope="module")
def highway():
    loop, args, kwargs = captured("highway")
    return built_model(loop.model), args, kwargs


def _at_gap(xp0, pp, gap: float, t: float) -> np.ndarray:
    """``xp0`` moved down so that the lowest foot is ``gap`` metres above the deck."""
    xp = np.array(xp0, dtype=float)
    z = LANDING_PLANT_STATE.index("z1")
    for _ in range(3):                                 # the gap is linear in z: exact
        xp[z] -= float(first_contact_function()(xp, t, pp)) - gap
    return xp


def test_the_free_world_is_the_stage_where_the_contact_is_zero(highway):
    model, args, kwargs = highway
    staged = model.controller_stages
    stage = {s.name(): s for s in staged.stages}["sensed_world"]
    free = dict(staged.free)["sensed_world"]
    assert free.name_in() == stage.name_in() and free.name_out() == stage.name_out()
    # a third fewer operations: the contact's exp, log1p and tanh a foot left out
    assert free.n_instructions() < 0.8 * stage.n_instructions()
    ops = [free.instruction_id(k) for k in range(free.n_instructions())]
    assert ca.OP_LOG1P not in ops and ca.OP_TANH not in ops
    table = kwargs["N"]                                # the sensors' rows, drawn as flown
    while table.filled <= 130:
        table.more(table.filled)
    xp0, pp, N = np.asarray(args[0], dtype=float), np.asarray(args[5], dtype=float), \
        table.rows
    rng = np.random.default_rng(19)
    for gap, equal in ((np.inf, True), (0.1, True), (0.08, True), (-0.002, False)):
        for k in (0, 7, 130):
            t = 0.004 * k
            xp = xp0.copy() if np.isinf(gap) else _at_gap(xp0, pp, gap, t)
            q = LANDING_PLANT_STATE.slice("x1q")            # attitude, rates, speeds
            xp[q] += rng.normal(scale=0.05, size=q.stop - q.start)
            if not np.isinf(gap):                       # the perturbed state's own gap
                xp = _at_gap(xp, pp, gap, t)
                assert float(first_contact_function()(xp, t, pp)) == pytest.approx(gap)
            a = dict(xp=xp, xc=np.asarray(args[1], dtype=float),
                     pc=np.asarray(args[6], dtype=float), t=t, uh_held=np.full(4, 6.0),
                     w=np.asarray(args[3], dtype=float)[k], pp=pp, n=N[k])
            ref, got = stage(**a), free(**a)
            same = all(np.array_equal(_bits(ref[n]), _bits(got[n])) for n in ref)
            assert same == equal, (gap, k)
            # only the IMU's record can differ (its specific force)
            assert all(np.array_equal(_bits(ref[n]), _bits(got[n]))
                       for n in ref if n != "record_imu")


def test_a_free_function_must_have_its_stage_s_names():
    x, y = ca.SX.sym("x"), ca.SX.sym("y")
    a = ca.Function("a", [x], [2 * x], ["x"], ["y"])
    other = ca.Function("a_free", [y], [2 * y], ["y"], ["z"])
    with pytest.raises(ValueError, match="not a stage's names"):
        Staged("s", (a,), (("x", 1),), (("y", ("y",)),), free=(("a", other),))
    with pytest.raises(ValueError, match="not a stage's names"):
        Staged("s", (a,), (("x", 1),), (("y", ("y",)),), free=(("b", a),))
    ok = Staged("s", (a,), (("x", 1),), (("y", ("y",)),), free=(("a", a),))
    assert ok.with_stages((a,), [a]).free == (("a", a),)


def test_the_staged_c_calls_the_free_world_on_the_driver_s_flag(highway):
    model, _, _ = highway
    files = simulator.simulator_sources(model, "sampled")
    prefix = f"qlsim_{model.name}_"
    composed = files[f"{prefix}controller.c"]
    n_in = len(model.controller_stages.inputs)
    flag = f"arg[{n_in + 1}]"                          # after the parameters' values
    assert f"if ({flag} && {flag}[0] != 0) {{" in composed
    assert f"{prefix}controller_sensed_world_free(arg1" in composed
    assert composed.count("_free(arg1") == 1            # the world stage alone
    assert f"{prefix}controller_sensed_world_free.c" in files
    driver = files[f"{prefix}sampled.c"]
    assert "far = !evented && g_start > near;" in driver
    assert f"k.arg[{n_in + 1}] = &far;" in driver
    # without the free stages (as before): no flag, no free function
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(staged_c, "FREE_STAGES", False)
        before = simulator.simulator_sources(model, "sampled")
    assert "_free(arg1" not in before[f"{prefix}controller.c"]
    assert "&far" not in before[f"{prefix}sampled.c"]


def _without(model, mp):
    mp.setattr(staged_c, "FREE_STAGES", False)
    try:
        return CompiledLoop(dataclasses.replace(model, name=f"{model.name}_nofree"), "sampled")
    finally:
        mp.undo()


@pytest.mark.slow
@pytest.mark.parametrize("scenario", ["highway", "ship"])
def test_the_compiled_flight_is_the_whole_world_s_to_the_bit(scenario):
    now, args, kwargs = captured(scenario)
    model = built_model(now.model)
    assert dict(model.controller_stages.free)
    with pytest.MonkeyPatch.context() as mp:
        before = _without(model, mp)
    a, b = now.sampled(*args, **kwargs), before.sampled(*args, **kwargs)
    assert a.status == b.status
    for field in ("X", "R", "times", "x_end"):
        assert np.array_equal(_bits(getattr(a, field)), _bits(getattr(b, field))), field
    assert len(a.times) > 1000


def _tilted(rng, xp0, pp, gap: float, t: float) -> np.ndarray:
    """``xp0`` with a body tilted up to 0.8 rad, any yaw, fast rates and speeds, the rotors'
    forces drawn, its lowest foot ``gap`` metres above the deck at ``t``."""
    xp, x1q = xp0.copy(), LANDING_PLANT_STATE.slice("x1q")
    q = QUAD6_STATE.unpack(np.arange(x1q.start, x1q.stop))
    xp[np.ravel(q["eta1"])] = rng.uniform([-0.8, -0.8, -np.pi], [0.8, 0.8, np.pi])
    xp[np.ravel(q["V1"])] = rng.normal(scale=6.0, size=3)
    xp[np.ravel(q["Omega1"])] = rng.normal(scale=4.0, size=3)
    xp[np.ravel(q["F"])] = rng.uniform(0.0, 15.0, size=4)
    return _at_gap(xp, pp, gap, t)


@pytest.mark.slow
def test_the_free_world_on_a_rough_sea_s_deck():
    """Review (issue 20): on ``ship_ss5``'s deck (its heave, roll and pitch at instants over
    30 s), bodies tilted, spinning and fast: beyond the underflow (746 onset widths) the
    contact's wrench (:func:`~quadland_symbolic.landing.contact.contact_function`, an
    independent evaluation) is exactly zero and the free world stage is the stage's, bit
    for bit; within 30 widths the IMU's record differs for many states, each one where
    the wrench is not zero (so the comparison sees the contact)."""
    loop, args, kwargs = captured("ship_ss5")
    model = built_model(loop.model)
    stage = {s.name(): s for s in model.controller_stages.stages}["sensed_world"]
    free = dict(model.controller_stages.free)["sensed_world"]
    xp0, pp = np.asarray(args[0], dtype=float), np.asarray(args[5], dtype=float)
    p, table, rng = LANDING_PLANT_PARAMS.unpack(pp), kwargs["N"], np.random.default_rng(28)
    width = kwargs["near"] / 1000.0                     # free_flight_gap's onset width
    for widths, far in ((1000.0, True), (746.5, True), (30.0, False), (0.0, False)):
        touched = 0
        for _ in range(40):
            t = float(rng.uniform(0.0, 30.0))
            k = int(t / 0.004)
            while table.filled <= k:
                table.more(table.filled)
            xp = _tilted(rng, xp0, pp, widths * width, t)
            s = LANDING_PLANT_STATE.unpack(xp)
            d_F, d_M, _, _ = contact_function()(s["x1q"], s["xv"], t, t, p["p_veh"],
                                                p["p_deck"], p["p_gear"], p["p_lock"])
            zero = not np.any(np.asarray(ca.vertcat(d_F, d_M)))
            a = dict(xp=xp, xc=np.asarray(args[1], dtype=float),
                     pc=np.asarray(args[6], dtype=float), t=t, uh_held=rng.uniform(0, 15, 4),
                     w=np.asarray(args[3], dtype=float)[k % len(args[3])], pp=pp,
                     n=table.rows[k])
            ref, got = stage(**a), free(**a)
            same = np.array_equal(_bits(ref["record_imu"]), _bits(got["record_imu"]))
            assert (zero and same) or not far, (widths, t)
            assert same or not zero, (widths, t)        # a difference only where it pushes
            touched += not same
        assert far or touched >= 10, widths
