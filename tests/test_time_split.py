"""The plant's terms of time alone, computed once an instant (issue 20).

:func:`quadland_symbolic.codegen.time_split.time_split` cuts an SX Function into the
values of the time and the parameters alone (``<name>_time``) and the rest (the core,
which reads them). The references: the Function itself, evaluated by CasADi on the same
inputs and compared bit for bit; a count of the core's instructions by hand for a small
Function; and, compiled, the same model built without the split (the previous
simulator), flown on the runtime's own arguments, every row, signal and state bit for bit.
"""

from __future__ import annotations

import dataclasses

import casadi as ca
import numpy as np
import pytest
from flight_capture import captured

from quadland.engine.compiled import CompiledLoop, built_model
from quadland_symbolic.codegen import simulator
from quadland_symbolic.codegen.time_split import HOISTED, time_split

_TRIG = (ca.OP_SIN, ca.OP_COS)


def _bits(v) -> np.ndarray:
    return np.asarray(v, dtype=float).view(np.uint64)


def _ops(f: ca.Function) -> list:
    return [f.instruction_id(k) for k in range(f.n_instructions())]


def _same_on_random(f, core, hoisted, rng, n=25):
    """``core(<f's inputs>, hoisted(t, pp))`` against ``f`` bit for bit at ``n`` points."""
    ti = [f.name_in().index(name) for name in hoisted.name_in()]
    for _ in range(n):
        args = [rng.normal(scale=3.0, size=f.nnz_in(i)) for i in range(f.n_in())]
        ref = f.call(args)
        got = core.call([*args, hoisted.call([args[i] for i in ti])[0]])
        for a, b in zip(ref, got, strict=True):
            assert np.array_equal(_bits(a), _bits(b))


def test_a_small_function_by_hand():
    # f = x sin(w t + phi) + a cos(w t + phi), x^2: sin(...) and a cos(...) are of
    # (t, pp) alone and read by terms of x; x^2 is not; the sum's terms are both
    x, t, pp = ca.SX.sym("x"), ca.SX.sym("t"), ca.SX.sym("pp", 3)
    arg = pp[0] * t + pp[1]
    f = ca.Function("f", [x, t, pp], [x * ca.sin(arg) + pp[2] * ca.cos(arg), x * x],
                    ["x", "t", "pp"], ["y", "z"])
    core, hoisted = time_split(f)
    assert core.name_in() == ["x", "t", "pp", HOISTED] and core.name_out() == ["y", "z"]
    assert hoisted.name() == "f_time" and hoisted.name_in() == ["t", "pp"]
    assert hoisted.nnz_out(0) == 2                        # sin(arg) and pp[2] cos(arg)
    assert not any(op in _TRIG for op in _ops(core))
    # the core: x * h0, + h1, x * x: three operations
    assert sum(op not in (ca.OP_INPUT, ca.OP_OUTPUT, ca.OP_CONST) for op in _ops(core)) == 3
    _same_on_random(f, core, hoisted, np.random.default_rng(1))
    for v in (0.0, -0.0, np.inf, np.nan, 1e308):          # special values pass as they are
        args = [v, 0.5, np.array([2.0, v, -1.0])]
        h = hoisted(args[1], args[2])
        for a, b in zip(f.call(args), core.call([*args, h]), strict=True):
            assert np.array_equal(_bits(a), _bits(b))


def test_nothing_of_time_alone_is_none():
    x, t, pp = ca.SX.sym("x"), ca.SX.sym("t"), ca.SX.sym("pp")
    # t and pp read as they are (no computed value of them alone): nothing to hoist
    assert time_split(ca.Function("g", [x, t, pp], [x * t + x * pp], ["x", "t", "pp"],
                                  ["y"])) is None
    assert time_split(ca.Function("g", [x, t, pp], [ca.sin(x * t)], ["x", "t", "pp"],
                                  ["y"])) is None


def test_an_output_of_time_alone_is_hoisted():
    x, t, pp = ca.SX.sym("x"), ca.SX.sym("t"), ca.SX.sym("pp")
    f = ca.Function("g", [x, t, pp], [ca.vertcat(ca.sin(pp * t), x)], ["x", "t", "pp"], ["y"])
    core, hoisted = time_split(f)
    assert hoisted.nnz_out(0) == 1 and not any(op in _TRIG for op in _ops(core))
    _same_on_random(f, core, hoisted, np.random.default_rng(2))


@pytest.fixture(scope="module")
def ship_model():
    return built_model(captured("ship")[0].model)


def _time_alone_trig(f: ca.Function) -> tuple[int, int]:
    """Sines and cosines of ``f`` whose operand is of ``t`` and ``pp`` alone, and the others."""
    timed = {f.name_in().index(n) for n in ("t", "pp") if n in f.name_in()}
    alone, counts = {}, [0, 0]
    for k in range(f.n_instructions()):
        op, ins, res = f.instruction_id(k), f.instruction_input(k), f.instruction_output(k)
        if op == ca.OP_OUTPUT:
            continue
        if op == ca.OP_INPUT:
            alone[res[0]] = ins[0] in timed
        elif op == ca.OP_CONST:
            alone[res[0]] = True
        else:
            alone[res[0]] = all(alone[j] for j in ins if j >= 0)
            if op in _TRIG:
                counts[0 if alone[res[0]] else 1] += 1
    return counts[0], counts[1]


@pytest.mark.parametrize("name", ["plant", "free_plant", "event"])
def test_the_ship_s_functions_split_bit_for_bit(ship_model, name):
    f = getattr(ship_model, name)
    alone, other = _time_alone_trig(f)
    assert alone > 80                                     # the deck's sinusoids
    core, hoisted = time_split(f)
    assert _time_alone_trig(core) == (0, other)           # every one of them hoisted
    assert _time_alone_trig(hoisted)[0] == alone
    _same_on_random(f, core, hoisted, np.random.default_rng(3), n=10)


@pytest.mark.slow
@pytest.mark.parametrize("scenario", ["ship", "highway"])
def test_the_compiled_flight_is_the_whole_plant_s_to_the_bit(scenario, monkeypatch):
    split, args, kwargs = captured(scenario)
    model = built_model(split.model)
    monkeypatch.setattr(simulator, "HOISTING", ())
    whole = CompiledLoop(dataclasses.replace(model, name=f"{model.name}_whole"), "sampled")
    monkeypatch.undo()
    a, b = split.sampled(*args, **kwargs), whole.sampled(*args, **kwargs)
    assert a.status == b.status
    for field in ("X", "R", "times", "x_end"):
        assert np.array_equal(_bits(getattr(a, field)), _bits(getattr(b, field))), field
    assert len(a.times) > 1000
    files = simulator.simulator_sources(model, "sampled")
    assert f"qlsim_{model.name}_plant_time.c" in files          # the split was flown
    assert f"qlsim_{model.name}_free_plant_time.c" in files


def test_a_call_or_a_free_variable_is_refused():
    # SX.unary/SX.binary cannot rebuild a call (OP_CALL, one of several outputs): refused
    # rather than rebuilt as something else
    x, t, pp = ca.SX.sym("x"), ca.SX.sym("t"), ca.SX.sym("pp", 2)
    g = ca.Function("g", [x], [ca.sin(x), ca.cos(x)], {"never_inline": True})
    s, c = g(pp[0] * t + pp[1])
    f = ca.Function("f", [x, t, pp], [x * c + s], ["x", "t", "pp"], ["y"])
    assert ca.OP_CALL in _ops(f)
    with pytest.raises(ValueError, match=f"operation {ca.OP_CALL}\\)"):
        time_split(f)
    q = ca.SX.sym("q")                                    # a free variable: refused too
    f = ca.Function("f", [x, t, pp], [x * q * ca.sin(pp[0] * t)], ["x", "t", "pp"], ["y"],
                    {"allow_free": True})
    with pytest.raises(ValueError, match="free variables"):
        time_split(f)


@pytest.mark.slow
def test_a_second_flight_with_another_deck_reads_its_own_deck():
    # one simulator flies the default deck, then another deck (its phases moved) from the
    # same instants: the second flight against the whole build's on the second deck, bit
    # for bit, and the two decks' flights differ. A flight's instants after its first are
    # only its own (the first flight's last is not 0), so a cache kept across calls would
    # be stale at most at t = 0: the driver's source is checked to keep it in the call's
    # own context, marked unknown before the first call of the function
    split, args, kwargs = captured("ship")
    model = built_model(split.model)
    lay = model.plant_params
    pp_a = np.asarray(args[5], dtype=float)
    pp_b = pp_a.copy()
    for name in ("heave_phase", "roll_phase", "pitch_phase"):
        pp_b[lay.slice(f"p_deck.{name}")] += 1.0
    args_b = (*args[:5], pp_b, *args[6:])
    first = split.sampled(*args, **kwargs)
    second = split.sampled(*args_b, **kwargs)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(simulator, "HOISTING", ())
        whole = CompiledLoop(dataclasses.replace(model, name=f"{model.name}_whole"), "sampled")
    ref = whole.sampled(*args_b, **kwargs)
    assert second.status == ref.status
    for field in ("X", "R", "times", "x_end"):
        assert np.array_equal(_bits(getattr(second, field)), _bits(getattr(ref, field))), field
    n = min(len(first.times), len(second.times))
    assert not np.array_equal(_bits(first.X[:n]), _bits(second.X[:n]))
    c = simulator.simulator_sources(model, "sampled")[f"qlsim_{model.name}_sampled.c"]
    driver = c[c.index(f"int qlsim_{model.name}_sampled("):]
    assert "static plant_ctx" not in c and "    plant_ctx ctx;" in driver
    for name in ("plant", "free_plant", "event"):
        assert driver.index(f"ctx.{name}_known = 0;") < driver.index("g_start = event(&ctx")
