"""Margin figures: each draws the report's loops, checked against python-control.

The loops are rebuilt from the exported models with python-control alone
(``control.feedback`` closing every other channel), and the figures' marks
against closed forms: the M-circles' ``|l / (1 + l)| = M``, the disk
margin's excluded circle touched by the loop at the disk's frequency.
"""

import math
import sys

import control
import numpy as np
import pytest
from matplotlib.figure import Figure
from matplotlib.patches import Circle
from threadpoolctl import threadpool_limits

import quadland
from quadland.margins import margin_report
from quadland.plots import (
    MARGIN_FIGURES,
    bode_plot,
    margin_figures,
    nichols_plot,
    nyquist_plot,
    pole_plot,
    sigma_plot,
)
from quadland.plots.margins import M_CIRCLES_DB
from quadland.plots.sensitivity import SIGMA_FLOOR_DB


def _report(*overrides):
    with threadpool_limits(1):
        return margin_report(quadland.load_scenario("paper", ["rbf.nodes=5", *overrides]))


@pytest.fixture(scope="module")
def report():
    """The paper's loop with a 50 Hz controller: a continuous and a sampled loop."""
    return _report("controller.rate_hz=50")


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


def _loop(L, i):
    """Loop ``i`` broken with the others closed, by python-control alone."""
    K = np.eye(L.ninputs)
    K[i, i] = 0.0
    return control.feedback(L, K)[i, i]


def _at(sys_, w):
    """python-control's value of ``sys_`` at ``j w`` (or ``exp(j w dt)``)."""
    x = np.exp(1j * w * sys_.dt) if sys_.dt else 1j * w
    return complex(np.squeeze(sys_(x)))


def _data(line):
    return np.asarray(line.get_xdata(), dtype=float), np.asarray(line.get_ydata(), dtype=float)


def _by_gid(ax, gid):
    (line,) = [x for x in ax.lines if x.get_gid() == gid]
    return line


def _by_label(ax, label):
    return [x for x in ax.lines if x.get_label() == label]


def _models(report, kind):
    return report.models if kind == "continuous" else report.sampled_models


def _margins(report, kind):
    return report.continuous if kind == "continuous" else report.sampled


def test_margin_figures(figures):
    assert list(figures) == list(MARGIN_FIGURES)
    assert all(isinstance(f, Figure) for f in figures.values())
    assert [len(f.axes) for f in figures.values()] == [8, 4, 4, 2, 3]


@pytest.mark.parametrize("kind", ["continuous", "sampled"])
def test_bode_is_the_loop_with_the_others_closed(report, figures, kind):
    fig = figures["bode.png"]
    top, bottom = fig.axes[:4], fig.axes[4:]
    L = _models(report, kind).loop_input
    for i, (mag, phase) in enumerate(zip(top, bottom, strict=True)):
        name = report.continuous.loops[i].name
        assert mag.get_title() == f"{name} loop (others closed)"
        (curve,) = _by_label(mag, kind)
        w, db = _data(curve)
        li = np.array([_at(_loop(L, i), x) for x in w[::10]])
        # a sampled loop's integrators near z = 1 (|z - 1| = w dt) leave either
        # evaluation eps / (w dt)^k of its own (k = 3 here: 2e-7 at w dt = 1e-3): compare
        # where w dt > 3e-3
        ok = w[::10] * (L.dt or 1.0) > 3e-3 if kind == "sampled" else slice(None)
        np.testing.assert_allclose(db[::10][ok], 20 * np.log10(np.abs(li[ok])), rtol=0,
                                   atol=1e-6)
        (ph,) = [x for x in phase.lines if x.get_linestyle() == curve.get_linestyle()
                 and x.get_gid() is None and len(x.get_xdata()) == len(w)]
        np.testing.assert_allclose(np.exp(1j * np.radians(_data(ph)[1][::10]))[ok],
                                   (li / np.abs(li))[ok], atol=1e-6)
        if kind == "sampled":
            assert curve.get_linestyle() == "--" and w[-1] < math.pi * 50


def test_crossover_marker_is_python_controls(report, figures):
    """The marked gain crossover is python-control's, its phase bar -180 + PM deg."""
    fig = figures["bode.png"]
    for i, (mag, phase) in enumerate(zip(fig.axes[:4], fig.axes[4:], strict=True)):
        _, pm, _, _, wgc, _ = control.stability_margins(_loop(report.models.loop_input, i))
        (wm,), (zero,) = _data(_by_gid(mag, "continuous-crossover"))
        assert wm == pytest.approx(wgc, rel=1e-6) and zero == 0.0
        bar_w, bar_deg = _data(_by_gid(phase, "continuous-phase-margin"))
        np.testing.assert_allclose(bar_w, wgc, rtol=1e-6)
        assert bar_deg[0] == -180.0
        assert bar_deg[1] == pytest.approx(-180.0 + pm, abs=0.05)   # interpolated on the grid


@pytest.mark.parametrize("kind", ["continuous", "sampled"])
def test_phase_convention_puts_the_crossover_in_one_turn_below_zero(report, figures, kind):
    """Every loop's drawn phase at its crossover lies in [-360, 0): -180 + PM."""
    fig = figures["bode.png"]
    L = _models(report, kind).loop_input
    for i, (mag, phase) in enumerate(zip(fig.axes[:4], fig.axes[4:], strict=True)):
        (wc,), _ = _data(_by_gid(mag, f"{kind}-crossover"))
        li = _at(_loop(L, i), wc)
        assert abs(li) == pytest.approx(1.0, abs=1e-6)
        _, (low, drawn) = _data(_by_gid(phase, f"{kind}-phase-margin"))
        assert -360.0 <= drawn < 0.0
        # the drawn phase is python-control's angle, turned by whole turns
        turns = (drawn - math.degrees(np.angle(li))) / 360.0
        assert turns == pytest.approx(round(turns), abs=2e-3)
        assert drawn - low == pytest.approx(_margins(report, kind).loops[i].phase_margin_deg,
                                            abs=0.05)


def test_gain_margin_bars_end_on_the_loops_magnitude(report, figures):
    """A gain margin's bar runs from 0 dB to |l| where python-control's phase is -180."""
    fig = figures["bode.png"]
    found = 0
    for kind in ("continuous", "sampled"):
        L = _models(report, kind).loop_input
        for i, (mag, phase) in enumerate(zip(fig.axes[:4], fig.axes[4:], strict=True)):
            m = _margins(report, kind).loops[i]
            for side, gm in (("up", m.gain_margin_up_db), ("down", m.gain_margin_down_db)):
                bars = [x for x in mag.lines if x.get_gid() == f"{kind}-gain-margin-{side}"]
                if not math.isfinite(gm):
                    assert bars == []
                    continue
                (w, _), (zero, db) = _data(bars[0])
                li = _at(_loop(L, i), w)
                assert np.angle(li) == pytest.approx(math.pi, abs=1e-5) or \
                    np.angle(li) == pytest.approx(-math.pi, abs=1e-5)
                assert zero == 0.0 and -20 * math.log10(abs(li)) == pytest.approx(gm, abs=0.05)
                (_, (deg,)) = _data(_by_gid(phase, f"{kind}-phase-crossover-{side}"))
                assert (deg + 180.0) / 360.0 == pytest.approx(round((deg + 180.0) / 360.0),
                                                              abs=1e-3)
                found += 1
    assert found >= 5


def test_nyquist_labels_and_the_critical_point(figures):
    for a in figures["nyquist.png"].axes:
        assert (a.get_xlabel(), a.get_ylabel()) == ("Re l", "Im l")
        labels = [t.get_text() for t in a.get_legend().get_texts()]
        assert {"continuous, w > 0", "sampled, w > 0", "unit circle", "-1"} <= set(labels)
        (minus_one,) = _by_label(a, "-1")
        assert _data(minus_one) == ([-1.0], [0.0])


@pytest.mark.parametrize("kind", ["continuous", "sampled"])
def test_nyquist_exclusion_disk_is_touched_at_the_disk_frequency(report, figures, kind):
    """The shaded disk holds -1, and the loop reaches its edge at the disk margin's
    frequency: a balanced disk margin alpha is where l first meets it."""
    L = _models(report, kind).loop_input
    for i, a in enumerate(figures["nyquist.png"].axes):
        (disk,) = [p for p in a.patches if p.get_gid() == f"{kind}-exclusion"]
        assert isinstance(disk, Circle) and disk.get_fill()
        (cx, cy), r = disk.center, disk.radius
        assert cy == 0.0 and abs(-1.0 - cx) < r
        d = _margins(report, kind).loops[i].disk
        # the gain interval's critical points -1/g_low, -1/g_high are its diameter
        lo, hi = d.gain_margin
        assert cx - r == pytest.approx(-1.0 / lo, rel=1e-9)
        assert cx + r == pytest.approx(-1.0 / hi, rel=1e-9)
        li = _at(_loop(L, i), d.frequency)
        assert abs(li - cx) == pytest.approx(r, rel=1e-5)
        (curve,) = _by_label(a, f"{kind}, w > 0")
        re, im = _data(curve)
        assert np.min(np.hypot(re - cx, im) - r) > -1e-6 * r     # never inside


def test_nichols_m_circles_are_closed_loop_gain_contours(figures):
    for a in figures["nichols.png"].axes:
        for m_db in M_CIRCLES_DB:
            ph, db = _data(_by_gid(a, f"M {m_db:g} dB"))
            l_ = 10 ** (db / 20) * np.exp(1j * np.radians(ph))
            np.testing.assert_allclose(20 * np.log10(np.abs(l_ / (1 + l_))), m_db, atol=1e-9)
            assert ph.min() >= -360.0 and ph.max() <= 0.0
        assert a.get_xlim() == (-360.0, 0.0)
        assert _data(_by_label(a, "critical point")[0]) == ([-180.0], [0.0])


def test_nichols_is_the_bode_curves(figures):
    bode, nichols = figures["bode.png"], figures["nichols.png"]
    for i, a in enumerate(nichols.axes):
        for kind in ("continuous", "sampled"):
            (mag,) = _by_label(bode.axes[i], kind)
            (curve,) = _by_label(a, kind)
            np.testing.assert_array_equal(_data(curve)[1], _data(mag)[1])


def test_sigma_is_of_S_and_T_with_its_peaks(report, figures):
    S_axis, T_axis = figures["sigma.png"].axes
    for kind in ("continuous", "sampled"):
        L = _models(report, kind).loop_input
        (s_line,) = _by_label(S_axis, kind)
        (t_line,) = _by_label(T_axis, kind)
        w, s_db = _data(s_line)
        G = np.stack([np.asarray(L(np.exp(1j * x * L.dt) if L.dt else 1j * x), dtype=complex)
                      for x in w])
        eye = np.eye(4)
        smin = np.linalg.svd(eye + G, compute_uv=False)[:, -1]  # sigma_max(S) = 1/sigma_min
        np.testing.assert_allclose(s_db, -20 * np.log10(smin), atol=1e-6)
        T = G @ np.linalg.inv(eye + G)
        t_db = 20 * np.log10(np.linalg.svd(T, compute_uv=False)[:, 0])
        np.testing.assert_allclose(_data(t_line)[1], t_db, atol=1e-6)
        for a, db, peak in ((S_axis, s_db, "Ms"), (T_axis, t_db, "Mt")):
            (pw,), (pdb,) = _data(_by_gid(a, f"{kind}-{peak}"))
            assert pdb == pytest.approx(db.max(), abs=1e-6) and pw == w[np.argmax(db)]
            bottom, top = a.get_ylim()
            assert bottom == SIGMA_FLOOR_DB and top >= pdb + 6.0


def test_poles_continuous_and_sampled(report, figures):
    full, zoom, zplane = figures["poles.png"].axes
    re, im = _data(full.lines[0])
    reference = control.feedback(report.models.loop_input, np.eye(4)).poles()
    assert len(reference) == len(re)
    for p in reference:
        assert np.min(np.abs(re + 1j * im - p)) < 1e-8 * max(1.0, abs(p))
    zd = control.feedback(report.sampled_models.loop_input, np.eye(4)).poles()
    (zline,) = _by_label(zplane, f"sampled ({zd.size})")
    zr, zi = _data(zline)
    for p in zd:
        assert np.min(np.abs(zr + 1j * zi - p)) < 1e-8
    assert zoom.get_xlim() == (-0.5, 0.05)


def test_the_z_plane_title_tells_the_largest_pole_from_the_unit_circle(report, figures):
    """The title's max |z| is closer to python-control's largest pole modulus than that
    is to 1: a slow pole (here the adaptive ones) no longer reads "1.0000", as if on the
    unit circle (review of issue 21: highway's 0.99996 did)."""
    import re as regex

    zd = control.feedback(report.sampled_models.loop_input, np.eye(4)).poles()
    m = float(np.max(np.abs(zd)))
    assert 0 < 1 - m < 1e-3                     # the case: within 1e-3 of the circle
    title = figures["poles.png"].axes[2].get_title()
    near = regex.search(r"max \|z\| = 1 ([-+]) ([0-9.e+-]+)$", title)
    assert near is not None, title
    shown = 1 + (1 if near.group(1) == "+" else -1) * float(near.group(2))
    assert abs(shown - m) < 0.1 * abs(1 - m)


@pytest.mark.slow
def test_single_plots_equal_the_set(report, figures):
    for plot, name in ((bode_plot, "bode.png"), (nyquist_plot, "nyquist.png"),
                       (nichols_plot, "nichols.png"), (sigma_plot, "sigma.png"),
                       (pole_plot, "poles.png")):
        fig = plot(report)
        for a, b in zip(fig.axes, figures[name].axes, strict=True):
            assert len(a.lines) == len(b.lines)
            for la, lb in zip(a.lines, b.lines, strict=True):
                np.testing.assert_array_equal(la.get_xydata(), lb.get_xydata())


def test_two_reports_overlay_on_one_figure(report):
    """``ax=``: a second report drawn into the first one's axes adds its lines there, its
    labels tagged with its ``label=`` and its curves in the next colours, and each legend
    is redrawn with one entry per label (the critical point, the unit circle once)."""
    other = _report("controller.rate_hz=50", "controller.k1=[2.0, 5.0, 10.0, 10.0]")
    for plot, label in ((bode_plot, "continuous"), (nyquist_plot, "continuous, w > 0"),
                        (nichols_plot, "continuous"), (sigma_plot, "continuous")):
        fig = plot(report)
        axes = np.array(fig.axes)
        again = plot(other, ax=axes.reshape(2, 4) if plot is bode_plot else axes,
                     label="k1 = 2, 50 Hz")
        assert again is fig and len(fig.axes) == axes.size
        mine, theirs = _by_label(fig.axes[0], label), _by_label(fig.axes[0], label.replace(
            "continuous", "continuous (k1 = 2, 50 Hz)"))
        assert len(mine) == 1 and len(theirs) == 1
        assert mine[0].get_color() != theirs[0].get_color()
        assert not np.array_equal(mine[0].get_ydata(), theirs[0].get_ydata())
        for a in fig.axes:
            legend = a.get_legend()
            if legend is None:
                continue
            texts = [t.get_text() for t in legend.get_texts()]
            assert len(texts) == len(set(texts))
            assert any("k1 = 2, 50 Hz" in t for t in texts)
    fig = pole_plot(report)
    pole_plot(other, ax=fig.axes, label="k1 = 2, 50 Hz")
    texts = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert any(t.startswith("continuous (") for t in texts)
    assert any(t.startswith("continuous (k1 = 2, 50 Hz) (") for t in texts)


#: highway's law before its observer on z (docs/landing.md, "the bias estimates' slow
#: tail"), for the two figure checks below: with the observer on z the thrust loop's gain at
#: the figure's floor (4.7e-3 rad/s) is 154 dB and its sampled and continuous curves there
#: differ by 0.19 dB (0.001 dB without it), and the filtered loop's dense solve above
#: 0.1 rad/s meets the drawn curve to 8.5e-8 instead of 1e-8: the figures' premises, not
#: their code, which these tests check. Not analysed further.
FIGURE_LAW = "controller.observer_frequency=[12.0, 12.0, 0.0]"


def test_bode_starts_two_decades_below_the_lowest_crossover_where_sampled_meets_continuous():
    """The figures start DECADES_BELOW decades under the lowest gain or phase crossover of
    any loop. There a sampled loop's zero-order hold and delay are a phase of w dt
    (1e-4 rad at 250 Hz and w ~ 2e-2 rad/s) and a magnitude of (w dt)^2, so the sampled
    curve lies on the continuous one; below 1e-4 rad/s on highway the sampled roll curve
    was 59 dB off (z - 1 ~ 4e-9)."""
    from quadland.plots.frequency import DECADES_BELOW, figure_floor, loop_curves

    with threadpool_limits(1):
        rep = margin_report(quadland.load_scenario("highway", [FIGURE_LAW]))
    freqs = [f for lm in rep.continuous.loops
             for f in (lm.crossover_frequency, lm.gain_margin_up_frequency,
                       lm.gain_margin_down_frequency) if f is not None and math.isfinite(f)]
    floor = figure_floor(rep)
    assert floor == pytest.approx(min(freqs) * 10.0 ** -DECADES_BELOW, rel=1e-12)
    continuous, sampled, filtered = loop_curves(rep)
    assert filtered.label == "filtered" and filtered.omega[0] == continuous.omega[0]
    assert continuous.omega[0] >= floor and continuous.omega[0] < floor * 10 ** 0.1
    lo = sampled.omega[0]
    np.testing.assert_allclose(20 * np.log10(np.abs(sampled.loops[0])),
                               20 * np.log10(np.abs(continuous.loops[0])), atol=0.01)
    assert lo == continuous.omega[0]


def test_the_filtered_loop_is_drawn_from_its_own_model():
    """highway's figures draw the loop with the navigation filter in it (dotted): its
    curves are the filtered model's loop at a time, against a dense solve of that model's
    realization at a few of the drawn frequencies from 0.1 rad/s up (below, the
    integrators' 1e11 gains leave S_ii to the solver's rounding), its markers the filtered
    section's margins, and the singular value figure has its curves."""
    from quadland.plots.frequency import loop_curves
    from quadland.plots.sensitivity import sigma_plot

    with threadpool_limits(1):
        rep = margin_report(quadland.load_scenario("highway", [FIGURE_LAW]))
        curves = loop_curves(rep)
    (flown,) = [c for c in curves if c.label == "filtered"]
    assert flown.style == ":" and flown.margins == rep.filtered.loops
    L = rep.filtered_models.realizations["loop_input"]
    assert flown.omega[-1] < np.pi / L.dt
    n = L.A.shape[0]
    for k in np.flatnonzero(flown.omega > 0.1)[::40]:
        z = np.exp(1j * flown.omega[k] * L.dt)
        G = L.C @ np.linalg.solve(z * np.eye(n) - L.A, L.B) + L.D
        S = np.linalg.inv(np.eye(4) + G)
        np.testing.assert_allclose(flown.loops[k], 1 / np.diag(S) - 1, rtol=1e-8)
    fig = bode_plot(rep)
    for i, lm in enumerate(rep.filtered.loops):
        (wc,), _ = _data(_by_gid(fig.axes[i], "filtered-crossover"))
        assert wc == lm.crossover_frequency
    fig = sigma_plot(rep)
    texts = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert any(t.startswith("filtered Ms ") for t in texts)


def test_the_figures_evaluate_each_loops_response_once_and_draw_its_own_values(report):
    """The loop figures and the singular value figure read one grid per loop: each
    response is evaluated once for the five figures, and each drawn loop is still the
    loop at a time of a dense solve of its realization at the drawn frequencies."""
    from quadland.analysis import response_of
    from quadland.analysis.response import FrequencyResponse
    from quadland.plots.frequency import loop_curves

    loops = [report.models.realizations["loop_input"],
             report.sampled_models.realizations["loop_input"]]
    for L in loops:
        response_of(L)._grids.clear()           # nothing kept from the review or other tests
    evaluated = []
    grid = FrequencyResponse._grid

    def counted(self, omega):
        if omega.size > 1:                      # not the grid's probes of its top end
            evaluated.append(id(self))
        return grid(self, omega)

    FrequencyResponse._grid = counted
    try:
        margin_figures(report)
    finally:
        FrequencyResponse._grid = grid
    assert sorted(evaluated) == sorted(id(response_of(L)) for L in loops)
    for curves, L in zip(loop_curves(report), loops, strict=True):
        n = L.A.shape[0]
        for k in range(0, curves.omega.size, 25):
            w = curves.omega[k]
            x = np.exp(1j * w * L.dt) if L.dt else 1j * w
            G = L.C @ np.linalg.solve(x * np.eye(n) - L.A, L.B) + L.D
            S = np.linalg.inv(np.eye(L.B.shape[1]) + G)
            np.testing.assert_allclose(curves.loops[k], 1 / np.diag(S) - 1, rtol=1e-8)
