"""The landing loop on a flat deck, without the deck's sinusoid sums (issue 20).

A deck whose every amplitude is zero (a car's roof) moves by ``0 * sin(...)``:
:func:`quadland_symbolic.landing.flat_deck.flat_deck_loop` rebuilds the loop's
integrated functions with those amplitudes the constant zero, and the runtime flies
it when a scenario's are. Checked here against the full loop itself: each rebuilt
function bit for bit (signs of zero included) at random inputs, and whole landings
bit for bit; and that the rebuilt functions no longer read the deck's sinusoids.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

import quadland
from quadland.kinds.landing import simulate as landing_simulate
from quadland.kinds.landing.contact_report import flat_gear_signals
from quadland.kinds.landing.sensed import sensed_vectors
from quadland.kinds.landing.values import landing_values
from quadland.scenario import load_scenario
from quadland_symbolic.landing.deck import DECK_PARAMS
from quadland_symbolic.landing.flat_deck import (
    AMPLITUDES,
    FLATTENED,
    amplitude_indices,
    flat_deck_loop,
)
from quadland_symbolic.landing.loop import (
    landing_gear_signals_function,
    landing_loop,
    landing_loop_params,
)
from quadland_symbolic.landing.plant import LANDING_PLANT_PARAMS
from quadland_symbolic.landing.sensed_loop import landing_sensed_loop, sensed_loop_params

LOOPS = [(landing_loop, False), (landing_loop, True), (landing_sensed_loop, False),
         (landing_sensed_loop, True)]


def _sines(prefix: str, layout) -> list[int]:
    """Positions of every sinusoid's amplitude, frequency and phase."""
    out = []
    for motion in ("heave", "roll", "pitch"):
        for part in ("amp", "freq", "phase"):
            s = layout.slice(f"{prefix}p_deck.{motion}_{part}")
            out.extend(range(s.start, s.stop))
    return out


def _random_inputs(f: ca.Function, layouts: dict, bases: dict, n: int, rng) -> list:
    """``n`` columns per input of ``f``: states and disturbances standard normal, times
    in 0 to 40 s, parameters highway's within 10 % with the deck's frequencies and
    phases random and its amplitudes zero (``layouts``, ``bases``: the parameter
    inputs' layouts and values, ``prefix`` of the plant's within, by input name)."""
    out = []
    for i in range(f.n_in()):
        name, size = f.name_in(i), f.size1_in(i)
        x = rng.standard_normal((size, n))
        if name in layouts:
            layout, prefix = layouts[name]
            x = bases[name][:, None] * (1 + 0.1 * x)
            sines = _sines(prefix, layout)
            x[sines] = rng.uniform(0.1, 3.0, (len(sines), n))
            x[list(amplitude_indices(layout, prefix))] = 0.0
        elif name == "t":
            x = rng.uniform(0.0, 40.0, (1, n))
        out.append(x)
    return out


@pytest.mark.parametrize("build, welded", LOOPS)
def test_each_rebuilt_function_computes_the_same_bits(build, welded):
    """Every function of the flat loop against the full loop's at 300 random inputs with
    zero amplitudes: the same bits (signs of zero included, NaN where NaN); the
    functions not rebuilt are the full loop's own."""
    model = build(10, welded)
    flat = flat_deck_loop(model)
    sc = load_scenario("highway")
    lv = landing_values(sc)
    pc = sensed_vectors(sc, lv)[0] if build is landing_sensed_loop else lv.pc
    layouts = {"pp": (LANDING_PLANT_PARAMS, ""), "p": (LANDING_PLANT_PARAMS, ""),
               "pc": (model.controller_params, "pp.")}
    bases = {k: np.asarray(v, dtype=float).ravel() for k, v in (("pp", lv.pp), ("p", lv.pp),
                                                                ("pc", pc))}
    rng = np.random.default_rng(20)
    checked = 0
    for name in ("rhs", "output_fn", "plant", "controller", "assemble", "step_args", "event",
                 "envelope", "ride_rhs", "ride_row", "free_plant"):
        full, rebuilt = getattr(model, name), getattr(flat, name)
        if full is None:
            continue
        if name not in FLATTENED:
            assert rebuilt is full
            continue
        args = _random_inputs(full, layouts, bases, 300, rng)
        a, b = full.map(300)(*args), rebuilt.map(300)(*args)
        a, b = (a, b) if isinstance(a, (list, tuple)) else ([a], [b])
        for u, v in zip(a, b, strict=True):
            u, v = np.asarray(u), np.asarray(v)
            nan = np.isnan(u) & np.isnan(v)
            assert nan.mean() < 0.5, name                     # mostly finite inputs
            assert np.array_equal(u.view(np.int64)[~nan], v.view(np.int64)[~nan]), name
        checked += 1
    assert checked >= 5


def test_the_gear_signals_on_a_flat_deck_are_the_same_bits():
    """The gear's signals of a landing's rows (``contact_report``) on the flat deck, at
    random inputs: the full function's bits; and no sinusoid read."""
    full, flat = landing_gear_signals_function(), flat_gear_signals()
    pp0 = np.asarray(landing_values(load_scenario("highway")).pp, dtype=float).ravel()
    args = _random_inputs(full, {"pp": (LANDING_PLANT_PARAMS, "")}, {"pp": pp0}, 500,
                          np.random.default_rng(21))
    u, v = (np.asarray(f.map(500)(*args)) for f in (full, flat))
    nan = np.isnan(u) & np.isnan(v)
    assert nan.mean() < 0.5
    assert np.array_equal(u.view(np.int64)[~nan], v.view(np.int64)[~nan])
    pp = flat.index_in("pp")
    assert not _reads(flat, pp)[_sines("", LANDING_PLANT_PARAMS)].any()
    assert _reads(full, pp)[_sines("", LANDING_PLANT_PARAMS)].any()


@pytest.mark.parametrize("build, welded", LOOPS)
def test_the_rebuilt_functions_read_no_sinusoid(build, welded):
    """The deck's amplitudes, frequencies and phases reach no output of a rebuilt
    function (they reach the full plant's); the deck's height and pad still do."""
    model = build(10, welded)
    flat = flat_deck_loop(model)
    assert flat.name == f"{model.name}_flat"
    for name in FLATTENED:
        f = getattr(flat, name)
        if f is None:
            continue
        for i in range(f.n_in()):
            if f.name_in(i) not in ("pp", "p", "pc"):
                continue
            prefix = "pp." if f.name_in(i) == "pc" else ""
            layout = model.controller_params if prefix else LANDING_PLANT_PARAMS
            used = _reads(f, i)
            assert not used[_sines(prefix, layout)].any(), name
            if name == "plant":
                assert _reads(getattr(model, name), i)[_sines(prefix, layout)].any()
            if name in ("event", "output_fn") and f.name_in(i) in ("pp", "p"):
                assert used[layout.slice("p_deck.deck_height")].all()


def _reads(f: ca.Function, i: int) -> np.ndarray:
    """Which entries of input ``i`` reach some output of ``f`` (its Jacobian's columns)."""
    used = np.zeros(f.size1_in(i), dtype=bool)
    for j in range(f.n_out()):
        sp = f.sparsity_jac(i, j)
        used |= np.diff(np.asarray(sp.colind())) > 0
    return used


def test_amplitudes_are_the_deck_layouts_amp_fields():
    """Three motions of the deck's N_DECK sinusoids, where DECK_PARAMS puts them."""
    idx = amplitude_indices(LANDING_PLANT_PARAMS)
    start = LANDING_PLANT_PARAMS.slice("p_deck").start
    names = DECK_PARAMS.element_names()
    assert len(idx) == 3 * DECK_PARAMS["heave_amp"].size
    assert {names[k - start].rsplit("_", 1)[0] for k in idx} == set(AMPLITUDES)


def _fly(monkeypatch, name: str, flat: bool, overrides=()):
    chosen, rule = [], landing_simulate.flat_deck

    def choose(*args):
        chosen.append(rule(*args) if flat else False)
        return chosen[-1]

    monkeypatch.setattr(landing_simulate, "flat_deck", choose)
    result = quadland.simulate(load_scenario(name, list(overrides)))
    monkeypatch.undo()
    return result, chosen


def _bits(a, b) -> bool:
    cols = set(a.columns)
    return cols == set(b.columns) and all(
        np.array_equal(np.asarray(a[k]).view(np.int64), np.asarray(b[k]).view(np.int64))
        for k in cols) and np.array_equal(a.states.view(np.int64), b.states.view(np.int64))


@pytest.mark.parametrize("name, overrides", [
    ("highway", ()),
    pytest.param("highway", ("sensors.enabled=false", "gear.welded=true"),
                 marks=pytest.mark.slow),
])
def test_a_flat_deck_landing_is_the_same_bit_for_bit(monkeypatch, name, overrides):
    """highway (a car's flat roof) flown on the flat loop, as the runtime chooses, and on
    the full loop: every column and state the same bits; the welded ride on the true
    state too (its rows from the full loop's ``ride_row``)."""
    flat, chosen = _fly(monkeypatch, name, True, overrides)
    full, _ = _fly(monkeypatch, name, False, overrides)
    assert chosen == [True]
    assert _bits(flat, full)


def test_the_runtime_chooses_the_flat_deck_only_when_every_amplitude_is_zero():
    """highway's deck is flat; ship's sea is not; one amplitude in the controller's model
    alone is enough to keep the full loop."""
    for name, expect in (("highway", True), ("ship", False)):
        lv = landing_values(load_scenario(name))
        layout = landing_loop_params(lv.l)
        assert landing_simulate.flat_deck(lv.pp, lv.pc, layout) is expect
    lv = landing_values(load_scenario("highway"))
    pc = np.array(lv.pc, dtype=float).ravel()
    pc[amplitude_indices(landing_loop_params(lv.l), "pp.")[40]] = 1e-3
    assert not landing_simulate.flat_deck(lv.pp, pc, landing_loop_params(lv.l))
    pc = np.zeros(sensed_loop_params(lv.l).size)
    assert landing_simulate.flat_deck(lv.pp, pc, sensed_loop_params(lv.l))
