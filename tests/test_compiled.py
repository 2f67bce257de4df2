"""Compiled simulation against CasADi's virtual machine, and its fallback."""

import warnings

import numpy as np
import pytest

import quadland
from quadland.engine import compiled
from quadland.engine.compiled import QuadlandWarning

SHORT = ["simulation.duration=1.5", "disturbance.noise=false", "rbf.nodes=7"]


_warnings = []


def _vm(monkeypatch, scenario):
    """The same scenario on CasADi's virtual machine (as without a compiler)."""
    monkeypatch.setattr(compiled, "have_compiler", lambda: False)
    compiled.compiled_loop.cache_clear()
    compiled._warn_no_compiler.cache_clear()
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            _warnings.append(caught)
            res = quadland.simulate(scenario)
    finally:
        monkeypatch.undo()
        compiled.compiled_loop.cache_clear()
    return res, caught


@pytest.mark.parametrize("extra", [[], ["controller.rate_hz=200"],
                                   ["controller.rate_hz=5", "simulation.duration=10"]],
                         ids=["continuous", "sampled", "sampled-until-it-fails"])
def test_compiled_equals_the_virtual_machine(monkeypatch, extra):
    sc = quadland.load_scenario("paper", SHORT + extra)
    try:
        fast = quadland.simulate(sc)
    except quadland.SimulationError as exc:       # a 5 Hz loop fails: it must fail alike
        fast = exc.partial
        with pytest.raises(quadland.SimulationError) as info:
            _vm(monkeypatch, sc)
        assert str(info.value) == str(exc)
        slow, caught = info.value.partial, _warnings[-1]
    else:
        slow, caught = _vm(monkeypatch, sc)
    for name in ("z_e", "phi_e", "psi_e", "F_1", "Delta_hat_1", "norm_W_hat", "lyapunov_V1"):
        scale = max(1.0, np.abs(slow[name]).max())
        np.testing.assert_allclose(fast[name], slow[name], rtol=0, atol=1e-9 * scale,
                                   err_msg=name)
    (warning,) = [w for w in caught if issubclass(w.category, QuadlandWarning)]
    assert "no C compiler found" in str(warning.message)
    assert "\n" not in str(warning.message)


def test_one_rk4_step_per_hold_interval():
    """With the disturbance held over 10 ms, RK4 at h = 10 ms has a local error
    O(h^5): halving h once (two substeps) must change the result by ~1/16 of what
    the first halving changes, which fails if a stray extra step is taken."""
    runs = [quadland.simulate(quadland.load_scenario(
        "paper", SHORT + [f"simulation.rk_steps_per_interval={k}"]))["z_e"] for k in (1, 2, 4)]
    d1, d2 = np.abs(runs[0] - runs[1]).max(), np.abs(runs[1] - runs[2]).max()
    assert 12 < d1 / d2 < 20


def test_the_flight_code_flies_the_same_trajectory():
    base = SHORT + ["controller.rate_hz=500"]
    a = quadland.simulate(quadland.load_scenario("paper", base))
    b = quadland.simulate(quadland.load_scenario("paper", base + ["controller.backend=c"]))
    for name in ("z_e", "theta_e", "F_1", "M_z", "zeta_hat_2"):
        np.testing.assert_allclose(b[name], a[name], rtol=0, atol=1e-9, err_msg=name)


def test_the_flight_code_needs_a_compiler(monkeypatch):
    monkeypatch.setattr(compiled, "have_compiler", lambda: False)
    compiled.compiled_loop.cache_clear()
    try:
        sc = quadland.load_scenario("paper", SHORT + ["controller.rate_hz=200",
                                                      "controller.backend=c"])
        with pytest.raises(quadland.QuadlandError, match="no C compiler was found"):
            quadland.simulate(sc)
    finally:
        monkeypatch.undo()
        compiled.compiled_loop.cache_clear()
