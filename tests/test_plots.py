"""Figures: each plot function returns a Figure that draws the result's own data."""

import math
import subprocess
import sys

import control
import numpy as np
import pytest
from matplotlib.figure import Figure
from threadpoolctl import threadpool_limits

import quadland
from quadland.margins import margin_report
from quadland.plots import (
    MARGIN_FIGURES,
    SIMULATION_FIGURES,
    bode_plot,
    control_inputs_plot,
    ground_track_plot,
    margin_figures,
    nyquist_plot,
    pole_plot,
    relative_errors_plot,
    sigma_plot,
    simulation_figures,
    uncertainty_plot,
    velocity_errors_plot,
)


@pytest.fixture(scope="module")
def result():
    return quadland.simulate(quadland.load_scenario("paper", ["simulation.duration=0.5"]))


def _report(*overrides):
    with threadpool_limits(1):
        return margin_report(quadland.load_scenario("paper", ["rbf.nodes=5", *overrides]))


@pytest.fixture(scope="module")
def report():
    return _report()


@pytest.fixture(scope="module")
def figures(report):
    return margin_figures(report)


@pytest.fixture(autouse=True)
def _nothing_written(tmp_path, monkeypatch):
    """Drawing writes no file and leaves no pyplot figure behind."""
    monkeypatch.chdir(tmp_path)
    yield
    assert list(tmp_path.iterdir()) == []
    if "matplotlib.pyplot" in sys.modules:
        assert sys.modules["matplotlib.pyplot"].get_fignums() == []


def _loop_gains(L, omega):
    """l_i(j w) = 1 / [(I + L)^-1]_ii - 1, from python-control's own evaluation."""
    G = np.stack([np.asarray(L(1j * w), dtype=complex) for w in omega])
    S = np.linalg.inv(np.eye(G.shape[-1]) + G)
    return 1.0 / np.diagonal(S, axis1=1, axis2=2) - 1.0, G


def _data(line):
    return np.asarray(line.get_xdata(), dtype=float), np.asarray(line.get_ydata(), dtype=float)


# simulation


def test_simulation_figures(result):
    figs = simulation_figures(result)
    assert list(figs) == list(SIMULATION_FIGURES)
    for name, fig in figs.items():
        assert isinstance(fig, Figure)
        title = fig.get_suptitle() or fig.axes[0].get_title()
        assert title == SIMULATION_FIGURES[name]
        assert any(t.get_text() == "scenario paper" for t in fig.texts)


@pytest.mark.parametrize("plot, first, rest", [
    (relative_errors_plot, "z_e", ("phi_e", "theta_e", "psi_e")),
    (velocity_errors_plot, "dz_e", ("p_e", "q_e", "r_e")),
])
def test_error_figures_plot_the_columns(result, plot, first, rest):
    fig = plot(result)
    assert isinstance(fig, Figure) and len(fig.axes) == 4
    expected = [result[first]] + [np.rad2deg(result[n]) for n in rest]
    for a, name, y in zip(fig.axes, (first, *rest), expected, strict=True):
        (line,) = a.lines
        x, yy = _data(line)
        np.testing.assert_array_equal(x, result["t"])
        np.testing.assert_allclose(yy, y, rtol=1e-15, atol=0)
        assert a.get_ylabel().startswith(name + " [")
    assert fig.axes[-1].get_xlabel() == "t [s]"
    assert "deg" in fig.axes[1].get_ylabel()


def test_control_inputs_plot(result):
    fig = control_inputs_plot(result)
    assert len(fig.axes) == 4
    for k, a in enumerate(fig.axes, start=1):
        (line,) = a.lines
        np.testing.assert_array_equal(_data(line)[1], result[f"u_{k}"])
        assert a.get_ylabel().startswith(f"u_{k} [")


@pytest.mark.parametrize("nominal", [False, True])
def test_uncertainty_plot(result, nominal):
    res = result if not nominal else quadland.simulate(quadland.load_scenario(
        "paper", ["simulation.duration=0.2", "controller.nominal_model=true"]))
    fig = uncertainty_plot(res)
    assert len(fig.axes) == 4
    for k, a in enumerate(fig.axes, start=1):
        names = [f"Delta_{k}"] + ([f"Delta_target_{k}"] if nominal else []) + [f"Delta_hat_{k}"]
        assert len(a.lines) == len(names)
        for line, name in zip(a.lines, names, strict=True):
            np.testing.assert_array_equal(_data(line)[1], res[name])
        assert a.lines[-1].get_linestyle() == "--"
    assert [t.get_text() for t in fig.axes[0].get_legend().get_texts()][-1] == "W_hat^T Psi"


def test_ground_track_plot(result):
    fig = ground_track_plot(result)
    (a,) = fig.axes
    vehicle, quad, start = a.lines
    np.testing.assert_array_equal(_data(vehicle)[0], result["x2"])
    np.testing.assert_array_equal(_data(vehicle)[1], result["y2"])
    np.testing.assert_array_equal(_data(quad)[0], result["x1"])
    np.testing.assert_array_equal(_data(quad)[1], result["y1"])
    assert _data(start)[0][0] == result["x2"][0] and _data(start)[1][0] == result["y2"][0]


# margins


def test_margin_figures(figures):
    assert list(figures) == list(MARGIN_FIGURES)
    assert all(isinstance(f, Figure) for f in figures.values())
    assert [len(f.axes) for f in figures.values()] == [8, 4, 2, 2]


def test_bode_is_the_loop_with_the_others_closed(report, figures):
    fig = figures["bode.png"]
    top, bottom = fig.axes[:4], fig.axes[4:]
    names = [m.name for m in report.continuous.loops]
    for i, (mag, phase, name) in enumerate(zip(top, bottom, names, strict=True)):
        assert mag.get_title() == f"{name} loop (others closed)"
        w, db = _data(mag.lines[0])
        w2, deg = _data(phase.lines[0])
        np.testing.assert_array_equal(w, w2)
        assert w[0] < 1e-2 and w[-1] > 1e2
        li, _ = _loop_gains(report.models.loop_input, w)
        np.testing.assert_allclose(db, 20 * np.log10(np.abs(li[:, i])), rtol=0, atol=1e-6)
        np.testing.assert_allclose(np.exp(1j * np.radians(deg)), li[:, i] / np.abs(li[:, i]),
                                   atol=1e-6)
        # |l| crosses 0 dB at the reported crossover
        m = report.continuous.loop(name)
        assert np.interp(math.log(m.crossover_frequency), np.log(w), db) == \
            pytest.approx(0.0, abs=0.05)
        assert len(mag.lines) == 2                # the curve and the 0 dB line, no sampled loop
    assert [t.get_text() for t in top[0].get_legend().get_texts()] == ["continuous"]


def test_nyquist_matches_bode(figures):
    bode, nyq = figures["bode.png"], figures["nyquist.png"]
    for i, a in enumerate(nyq.axes):
        _, db = _data(bode.axes[i].lines[0])
        re, im = _data(a.lines[0])
        re_m, im_m = _data(a.lines[1])
        np.testing.assert_allclose(20 * np.log10(np.hypot(re, im)), db, atol=1e-9)
        np.testing.assert_array_equal(re_m, re)
        np.testing.assert_array_equal(im_m, -im)
        assert (_data(a.lines[-1])[0][0], _data(a.lines[-1])[1][0]) == (-1.0, 0.0)


def test_sigma_is_of_S_and_T(report, figures):
    fig = figures["sigma.png"]
    S_axis, T_axis = fig.axes
    assert len(S_axis.lines) == len(T_axis.lines) == 4
    w = _data(S_axis.lines[0])[0]
    _, G = _loop_gains(report.models.loop_input, w)
    eye = np.eye(4)
    # sigma_max((I + L)^-1) = 1 / sigma_min(I + L)
    smin = np.linalg.svd(eye + G, compute_uv=False)[:, -1]
    np.testing.assert_allclose(_data(S_axis.lines[0])[1], -20 * np.log10(smin), atol=1e-6)
    T = G @ np.linalg.inv(eye + G)
    smax = np.linalg.svd(T, compute_uv=False)[:, 0]
    np.testing.assert_allclose(_data(T_axis.lines[0])[1], 20 * np.log10(smax), atol=1e-6)


def test_poles_are_the_closed_loop_eigenvalues(report, figures):
    full, zoom = figures["poles.png"].axes
    re, im = _data(full.lines[0])
    np.testing.assert_array_equal(re, report.poles.real)
    L = report.models.loop_input
    reference = control.feedback(L, np.eye(4)).poles()
    assert len(reference) == len(re)
    for p in reference:
        assert np.min(np.abs(re + 1j * im - p)) < 1e-8 * max(1.0, abs(p))
    assert full.get_title() == f"closed-loop poles ({report.poles.size})"
    assert zoom.get_xlim() == (-0.5, 0.05)


@pytest.mark.slow
def test_single_plots_equal_the_set(report, figures):
    for plot, name in ((bode_plot, "bode.png"), (nyquist_plot, "nyquist.png"),
                       (sigma_plot, "sigma.png"), (pole_plot, "poles.png")):
        fig = plot(report)
        assert isinstance(fig, Figure)
        for a, b in zip(fig.axes, figures[name].axes, strict=True):
            assert len(a.lines) == len(b.lines)
            for la, lb in zip(a.lines, b.lines, strict=True):
                np.testing.assert_array_equal(la.get_xydata(), lb.get_xydata())


@pytest.mark.slow
def test_sampled_loop_is_dashed_up_to_nyquist():
    report = _report("controller.rate_hz=50")
    fig = bode_plot(report)
    mag = fig.axes[0]
    cont, sampled, _ = mag.lines                  # curve, sampled curve, 0 dB line
    assert sampled.get_linestyle() == "--"
    w = _data(sampled)[0]
    assert w[-1] < math.pi * 50 <= _data(cont)[0][-1]
    np.testing.assert_array_equal(w, _data(cont)[0][:len(w)])
    nyq = nyquist_plot(report)
    assert len(nyq.axes[0].lines) == 6            # two curves and their mirrors, circle, -1


@pytest.mark.slow
def test_import_chooses_no_backend():
    code = ("import matplotlib; matplotlib.use('svg'); import quadland.plots.simulation, "
            "quadland.plots.margins; print(matplotlib.get_backend())")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "svg"
