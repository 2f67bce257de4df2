"""The staged controller's values of its parameters alone, computed once a flight (issue 20).

:func:`quadland_symbolic.codegen.staged_c.staged_sources` cuts each SX stage of the
compiled simulators' staged controller on the inputs the driver holds constant over a
flight (the controller's and the plant's parameters, ``pc`` and ``pp``, and their
slices): the values of those alone go into ``<stage>_params``, computed once before the
first tick, and the core reads them. The references: each stage itself, evaluated by
CasADi on the same inputs, bit for bit; a small staged Function whose cut is counted by
hand; and, compiled, the same model built without the cut (the simulator as it was),
flown on the runtime's own arguments, every row, signal and state bit for bit, also on a
second flight of other parameters from the same simulator.
"""

from __future__ import annotations

import dataclasses

import casadi as ca
import numpy as np
import pytest
from flight_capture import captured

from quadland.engine.compiled import CompiledLoop, built_model
from quadland_symbolic.codegen import simulator, staged_c
from quadland_symbolic.codegen.time_split import HOISTED
from quadland_symbolic.stages import Staged

_LIBM = (ca.OP_SIN, ca.OP_COS, ca.OP_EXP, ca.OP_SINH, ca.OP_COSH, ca.OP_LOG, ca.OP_EXPM1)


def _bits(v) -> np.ndarray:
    return np.asarray(v, dtype=float).view(np.uint64)


def _ops(f: ca.Function) -> list:
    return [f.instruction_id(k) for k in range(f.n_instructions())]


def _emitted(staged, constants):
    """``staged_sources``' files and sizes, and the Functions it emitted by name."""
    emitted = {}

    def emit(name, f):
        emitted[name] = f
        return {f"{name}.c": ""}

    files, sizes = staged_c.staged_sources("p_", staged, emit, constants)
    return files, sizes, emitted


def test_a_small_staged_function_by_hand():
    # stage a: y = x sin(k) + exp(k) x^2 (sin(k), exp(k) of the constant k alone; the
    # cut needs MIN_PARAMS instructions, so k's terms are padded by a chain of sines);
    # stage b: z = y cos(t), nothing of k: not cut
    x, k, t = ca.SX.sym("x"), ca.SX.sym("k", 2), ca.SX.sym("t")
    kk = k[0]
    for _ in range(staged_c.MIN_PARAMS):
        kk = ca.sin(kk) + k[1]
    a = ca.Function("a", [x, k], [x * kk + ca.exp(k[1]) * x * x], ["x", "k"], ["y"])
    y = ca.SX.sym("y")
    b = ca.Function("b", [y, t], [y * ca.cos(t)], ["y", "t"], ["z"])
    staged = Staged("ctl", (a, b), (("x", 1), ("pc", 3), ("t", 1)), (("z", ("z",)),),
                    (("k", "pc", 1, 3),))
    files, sizes, emitted = _emitted(staged, ("pc",))
    assert set(emitted) == {"p_ctl_a", "p_ctl_a_params", "p_ctl_b"}
    core, params = emitted["p_ctl_a"], emitted["p_ctl_a_params"]
    assert core.name_in() == ["x", "k", HOISTED] and params.name_in() == ["k"]
    assert params.nnz_out(0) == 2 and sizes["n_params"] == 2     # kk and exp(k[1])
    assert ca.OP_SIN not in _ops(core) and ca.OP_EXP not in _ops(core)
    # the core: x * h0, x * x... h1 * x * x, the sum: four operations
    assert sum(op not in (ca.OP_INPUT, ca.OP_OUTPUT, ca.OP_CONST) for op in _ops(core)) == 4
    assert emitted["p_ctl_b"] is b
    c = files["p_ctl.c"]
    assert "arg1[2] = arg[3] + 0;" in c                   # the core reads arg[n_in]
    assert "int p_ctl_params(" in c and "arg1[0] = (arg[1] ? arg[1] + 1 : 0);" in c
    assert "#include \"p_ctl_a_params.h\"" in files["p_ctl.h"]
    rng = np.random.default_rng(4)
    for v in (*rng.normal(size=5), 0.0, -0.0, np.inf, np.nan):
        kv = np.array([rng.normal(), v])
        ref = a(0.7, kv)
        got = core(0.7, kv, params(kv))
        assert np.array_equal(_bits(ref), _bits(got))
    # without constants (or with the switch off) nothing is cut
    assert set(_emitted(staged, ())[2]) == {"p_ctl_a", "p_ctl_b"}


@pytest.fixture(scope="module")
def highway_model():
    return built_model(captured("highway")[0].model)


def test_the_sensed_stages_cut_bit_for_bit(highway_model):
    staged = highway_model.controller_stages
    _, sizes, emitted = _emitted(staged, ("pc", "pp"))
    stages = {s.name(): s for s in staged.stages}
    cut = sorted(n[len("p_controller_"):-len("_params")] for n in emitted
                 if n.endswith("_params"))
    assert cut == ["sensed_finish", "sensed_flight", "sensed_world"]
    assert sizes["n_params"] > 100
    constant = {"pc", "pp"} | {n for n, src, _, _ in staged.slices if src in ("pc", "pp")}
    rng = np.random.default_rng(5)
    for name in cut:
        f, core = stages[name], emitted[f"p_controller_{name}"]
        params = emitted[f"p_controller_{name}_params"]
        assert set(params.name_in()) <= constant
        idx = [f.name_in().index(n) for n in params.name_in()]
        libm = sum(op in _LIBM for op in _ops(f)) - sum(op in _LIBM for op in _ops(core))
        assert libm >= (40 if name == "sensed_flight" else 0)   # libm's calls left a tick
        for _ in range(4):
            args = [rng.normal(scale=2.0, size=f.nnz_in(i)) for i in range(f.n_in())]
            ref = f.call(args)
            got = core.call([*args, params.call([args[i] for i in idx])[0]])
            for r, g in zip(ref, got, strict=True):
                assert np.array_equal(_bits(r), _bits(g)), name


def _uncut(model, monkeypatch):
    monkeypatch.setattr(staged_c, "CUT_PARAMS", False)
    try:
        return CompiledLoop(dataclasses.replace(model, name=f"{model.name}_uncut"), "sampled")
    finally:
        monkeypatch.undo()


def _same(a, b) -> None:
    assert a.status == b.status
    for field in ("X", "R", "times", "x_end"):
        assert np.array_equal(_bits(getattr(a, field)), _bits(getattr(b, field))), field


@pytest.mark.slow
@pytest.mark.parametrize("scenario", ["highway", "ship"])
def test_the_compiled_flight_is_the_uncut_controller_s_to_the_bit(scenario, monkeypatch):
    cut, args, kwargs = captured(scenario)
    model = built_model(cut.model)
    files = simulator.simulator_sources(model, "sampled")
    assert f"qlsim_{model.name}_controller_sensed_flight_params.c" in files   # cut flown
    assert "controller_params(k.arg" in files[f"qlsim_{model.name}_sampled.c"]
    uncut = _uncut(model, monkeypatch)
    a = cut.sampled(*args, **kwargs)
    _same(a, uncut.sampled(*args, **kwargs))
    assert len(a.times) > 1000


@pytest.mark.slow
def test_a_second_flight_with_other_parameters_reads_its_own():
    # one simulator flies the default controller, then one with other guidance, estimator
    # and plant parameters: the second flight against the uncut build's on the same
    # arguments, bit for bit, and different from the first (the values of the parameters
    # alone are computed at each flight's start, not kept from the one before)
    cut, args, kwargs = captured("highway")
    model = built_model(cut.model)
    pc, pp = np.asarray(args[6], dtype=float).copy(), np.asarray(args[5], dtype=float).copy()
    pc[pc != np.round(pc)] *= 1.0 + 1e-3                  # gains and times, not flags,
    pp[pp != np.round(pp)] *= 1.0 + 1e-4                  # counts nor delays
    args_b = (*args[:5], pp, pc, *args[7:])
    first = cut.sampled(*args, **kwargs)
    second = cut.sampled(*args_b, **kwargs)
    with pytest.MonkeyPatch.context() as mp:
        uncut = _uncut(model, mp)
    _same(second, uncut.sampled(*args_b, **kwargs))
    assert not np.array_equal(_bits(first.X[:50]), _bits(second.X[:50]))
