"""The filter's step with each sensor's updates evaluated only when due.

:func:`~quadland_symbolic.landing.estimator_switch.conditional_step_function` against
the branch-free step it must equal (:func:`~quadland_symbolic.landing.estimator.
estimator_step_function`, every update computed and selected), bit for bit, over a
flight with packets due, late, stale, from the future, not finite and outliers; the
generated C's branches; and the stages' composition.
"""

from __future__ import annotations

import re

import casadi as ca
import numpy as np
import pytest
from filter_packets import packet

from quadland_symbolic.kalman import fifo_push_pop
from quadland_symbolic.landing.estimator import (
    FLIGHT_COUPLING,
    FLIGHT_DEPTH,
    N_HIST,
    estimator_diagnostics,
    estimator_init_function,
    estimator_memory,
    estimator_step_function,
)
from quadland_symbolic.landing.estimator_switch import (
    conditional_step_function,
    conditional_step_stages,
    fifo_switch,
)
from quadland_symbolic.landing.navigation import (
    ESTIMATOR_DEFAULTS,
    NAV_PACKETS,
    SENSORS,
    estimator_params,
)
from quadland_symbolic.stages import Staged

DT = 0.004


def _bits(v):
    return np.asarray(v, dtype=np.float64).ravel().view(np.uint64)


@pytest.mark.parametrize(("seed", "held"), [(1, True), (2, True), (1, False)])
def test_the_conditional_step_equals_the_branch_free_step_bit_for_bit(seed, held):
    """``held``: the FIFOs' slots in a Switch (the default); else selected every step."""
    rng = np.random.default_rng(seed)
    sizes = (N_HIST, FLIGHT_DEPTH, FLIGHT_COUPLING)
    branch_free = estimator_step_function(*sizes)
    conditional = conditional_step_function(*sizes, held=held)
    assert branch_free.is_a("SXFunction") and conditional.is_a("MXFunction")
    lay, lp = estimator_memory(*sizes), estimator_params()
    p = lp.pack(dict(ESTIMATOR_DEFAULTS))
    p[lp.slice("range_deck_radius")], p[lp.slice("range_deck_sigmas")] = 1e30, 0.0
    mem = _first_memory(sizes, rng.normal(size=18) * 0.05)
    t, quiet = 7.0, 0
    for _ in range(300):
        t += DT
        pkts = [packet(layout, rng, t, mem[lay.slice("t_h")][0]) for layout in NAV_PACKETS]
        imu = np.r_[0.02, -0.01, 0.5, 0.0, 0.0, 9.8, rng.normal(size=3) * 0.01]
        want = branch_free(mem, imu, *pkts, p, DT, t)
        got = conditional(mem, imu, *pkts, p, DT, t)
        for a, b in zip(want, got, strict=True):
            np.testing.assert_array_equal(_bits(b), _bits(a))
        d = estimator_diagnostics().unpack(np.asarray(want[2]).ravel())
        quiet += not np.any(d["fused"] + d["rejected"] + d["held"])
        mem = np.asarray(want[0]).ravel()
    # every kind of outcome happened, and most steps fused nothing
    assert np.all(d["n_fused"] > 0) and np.sum(d["n_rejected"]) > 0
    assert np.all(d["n_discarded"] + d["n_dropped"] > 0)
    assert quiet > 150


def _first_memory(sizes, x_noise=None):
    """The filter's memory at t = 7 s from a hover 3 m up (``x_noise`` added to the first
    18 states)."""
    x0 = np.r_[0.3, -0.2, 3.0, 0.2, -0.1, -0.3, 0.5, 0.1, 0.0, np.zeros(12)]
    if x_noise is not None:
        x0[:18] += x_noise
    P0 = np.r_[[0.5] * 3, [0.25] * 6, [0.1] * 3, [1.0] * 3, [0.04] * 3, [0.01] * 3]
    return np.asarray(estimator_init_function(*sizes)(x0, P0, [0, 0, 0.3, 0, 0, 0.05, 0, 0, 0],
                                                      7.0)).ravel()


def _split_step(sizes, held):
    """:func:`conditional_step_stages` composed by name, as the sensed loop composes them."""
    fused, finish = conditional_step_stages(*sizes, held=held)
    ins = (("mem", estimator_memory(*sizes).size), ("imu", 9),
           *((p.name, p.size) for p in NAV_PACKETS), ("p_est", estimator_params().size),
           ("dt", 1), ("t", 1))
    return Staged("split", (fused, finish), ins,
                  tuple((n, (n,)) for n in ("mem_next", "y", "diag"))).function()


@pytest.mark.parametrize(("seed", "held"), [(4, True), (5, False)])
def test_the_finish_as_a_stage_equals_the_joined_step_bit_for_bit(seed, held):
    """The step as two stages (the finish writing its outputs where they go) against the
    joined step over 300 periods of packets due, late, stale, from the future, not finite
    and outliers: every output the same bits, fed back as the next memory."""
    rng = np.random.default_rng(seed)
    sizes = (N_HIST, FLIGHT_DEPTH, FLIGHT_COUPLING)
    joined, split = conditional_step_function(*sizes, held=held), _split_step(sizes, held)
    lay, lp = estimator_memory(*sizes), estimator_params()
    p = lp.pack(dict(ESTIMATOR_DEFAULTS))
    mem = _first_memory(sizes)
    t, fused = 7.0, 0.0
    for _ in range(300):
        t += DT
        pkts = [packet(layout, rng, t, mem[lay.slice("t_h")][0]) for layout in NAV_PACKETS]
        imu = np.r_[0.02, -0.01, 0.5, 0.0, 0.0, 9.8, rng.normal(size=3) * 0.01]
        want = joined(mem, imu, *pkts, p, DT, t)
        got = split(mem, imu, *pkts, p, DT, t)
        for a, b in zip(want, got, strict=True):
            np.testing.assert_array_equal(_bits(b), _bits(a))
        fused += np.sum(estimator_diagnostics().unpack(np.asarray(want[2]).ravel())["fused"])
        mem = np.asarray(want[0]).ravel()
    assert fused > 0


def test_its_c_branches_once_per_sensor(tmp_path, monkeypatch):
    """CasADi's C of the Switch: an ``if`` on the due flag around the sensor's updates."""
    monkeypatch.chdir(tmp_path)
    conditional_step_function(N_HIST, FLIGHT_DEPTH, FLIGHT_COUPLING).generate("step.c")
    text = (tmp_path / "step.c").read_text()
    # one on the due flag around the sensor's updates, one on its FIFO's flags
    assert len(re.findall(r"if \(arg\[0\] \? casadi_to_int\(\*arg\[0\]\) : 0\) \{", text)) \
        == 2 * len(SENSORS)
    for s in SENSORS:
        assert f"fuse_{s}:" in text and f"skip_{s}:" in text
        assert f"move_{s}:" in text and f"hold_{s}:" in text


@pytest.mark.parametrize("sensor", SENSORS)
def test_the_fifo_switch_equals_the_selections_bit_for_bit(sensor):
    """Every push and pop flag, slots holding -0.0, NaN and numbers: the Switch's FIFO is
    ``fifo_push_pop``'s selected slots (the branch-free step's), read from the memory."""
    rng = np.random.default_rng(3)
    sizes = (N_HIST, FLIGHT_DEPTH, FLIGHT_COUPLING)
    lay = estimator_memory(*sizes)
    f = fifo_switch(sensor, *sizes)
    mem_s, pkt_s = lay.sym("mem"), ca.SX.sym("pkt", f.size1_in(2))
    push_s, pop_s = ca.SX.sym("push"), ca.SX.sym("pop")
    m = lay.unpack(mem_s)
    ref = ca.Function("ref", [mem_s, pkt_s, push_s, pop_s], [ca.vec(fifo_push_pop(
        m[f"fifo_{sensor}"], m[f"count_{sensor}"], pkt_s[1:], push_s,
        lambda h, n: pop_s)["slots"])])
    depth = lay[f"fifo_{sensor}"].shape[1]
    for trial in range(40):
        mem = rng.normal(size=lay.size)
        fifo = mem[lay.slice(f"fifo_{sensor}")]
        fifo[rng.random(fifo.size) < 0.3] = -0.0
        fifo[rng.random(fifo.size) < 0.05] = np.nan
        mem[lay.slice(f"fifo_{sensor}")] = fifo
        mem[lay.slice(f"count_{sensor}")] = rng.integers(0, depth + 1)
        pkt = rng.normal(size=f.size1_in(2))
        push, pop = trial % 2, (trial // 2) % 2
        want = ref(mem, pkt, push, pop)
        got = f(float(push or pop), mem, pkt, push, pop, float(push or pop))
        np.testing.assert_array_equal(_bits(got), _bits(want))
        if not (push or pop):       # -0.0 turned to +0.0, as 0 + x does
            assert not np.any(np.signbit(np.asarray(got))[np.asarray(got) == 0])


def test_stages_compose_by_name_and_refuse_what_is_missing():
    a, b = ca.SX.sym("a"), ca.SX.sym("b")
    double = ca.Function("double", [a], [2 * a], ["u1"], ["v"])
    add = ca.Function("add", [a, b], [a + b], ["v", "u0"], ["y"])
    staged = Staged("f", (double, add), (("u", 2),), (("out", ("y", "v")), ("twice", ("v",))),
                    slices=(("u0", "u", 0, 1), ("u1", "u", 1, 2)))
    out, twice = staged.function()([5.0, 3.0])
    assert np.asarray(out).ravel().tolist() == [11.0, 6.0] and float(twice) == 6.0
    with pytest.raises(ValueError, match="reads v"):
        Staged("f", (add,), (("u0", 1),), (("y", ("y",)),))
    with pytest.raises(ValueError, match="outputs v again"):
        Staged("f", (double, double), (("u1", 1),), (("v", ("v",)),))
    with pytest.raises(ValueError, match="no stage outputs z"):
        Staged("f", (double,), (("u1", 1),), (("z", ("z",)),))


def test_the_staged_c_reads_and_writes_in_place():
    """The sensed controller's C: the filter reads its memory in the loop's state and
    writes the next one where the next state holds it; every stage its own file but the
    delay lines' shifts (rings, tests/test_delivery_ring.py)."""
    from quadland_symbolic.codegen.simulator import simulator_sources
    from quadland_symbolic.landing.sensed_loop import landing_sensed_loop, sensed_loop_memory

    files = simulator_sources(landing_sensed_loop(10), "sampled")
    c = files["qlsim_landing_sensed_controller.c"]
    nav = sensed_loop_memory(10).slice("nav")
    block = c[c.index("/* sensed_filter */"):c.index("/* sensed_flight */")]
    assert f"arg1[0] = (arg[1] ? arg[1] + {nav.start} : 0);" in block
    assert f"res1[0] = (res[0] ? res[0] + {nav.start} : w + {nav.start});" in block
    # the finish is a stage: the filter's C copies none of the 775-real memory out
    assert block.count("/* sensed_finish */") == 1
    filt = files["qlsim_landing_sensed_controller_sensed_filter.c"]
    assert re.search(r"casadi_copy\([^;]*, 775,", filt) is None
    staged = landing_sensed_loop(10).controller_stages
    shifts = {line for line, _, _ in staged.rings}        # the delay lines: rings, no C
    for stage in staged.stages:
        written = f"qlsim_landing_sensed_controller_{stage.name()}.c" in files
        assert written is not bool(shifts & set(stage.name_out())), stage.name()
    assert len(shifts) == 5 and "/* sensed_push" not in c
    assert all(len(text) < 700_000 for name, text in files.items() if "controller" in name)
