"""The navigation figures: a landing's estimate, truth and 3-sigma band; the consistency.

The landing figure from a short flight on sensors: its lines are the recorded estimate,
the truth from the logged positions (at rows where the filter's horizon time is a row
time, no interpolation), the band three of the recorded standard deviations; a landing
on the true state has no estimate and no such figure. The consistency figure from a
Monte Carlo result made by hand: its lines are the averages, its bands the bounds.
"""

import numpy as np
import pytest

import quadland
from quadland.kinds.landing.consistency import NEES_GROUPS, ConsistencyResult, chi2_bounds
from quadland.plots import LANDING_FIGURES, NAVIGATION_FIGURES, consistency_plot, landing_figures
from quadland.plots.navigation import CONSISTENCY_TITLE
from quadland.scenario import Scenario
from quadland_symbolic.landing.guidance import TOUCHDOWN
from quadland_symbolic.landing.navigation import BLOCKS


@pytest.fixture(scope="module")
def flights():
    """3 s of the highway on its sensors (with a row at every control tick, so that every
    horizon time is a row's, and at the shipped 100 Hz) and on the true state."""
    def fly(*overrides):
        return quadland.simulate(quadland.load_scenario(
            "highway", ["simulation.duration=3.0", *overrides]))
    return {"true": fly("simulation.output_rate_hz=250.0"), "100 Hz": fly(),
            "false": fly("sensors.enabled=false")}


def _line(ax, label):
    (line,) = [ln for ln in ax.lines if ln.get_label() == label]
    return np.asarray(line.get_xdata(), float), np.asarray(line.get_ydata(), float)


def test_a_landing_on_sensors_adds_the_navigation_figure_and_one_on_the_truth_not(flights):
    sensed, true = landing_figures(flights["true"]), landing_figures(flights["false"])
    assert list(sensed) == [*LANDING_FIGURES, *NAVIGATION_FIGURES]
    assert list(true) == list(LANDING_FIGURES)
    fig = sensed["navigation.png"]
    assert fig.get_suptitle() == NAVIGATION_FIGURES["navigation.png"]
    assert any(t.get_text() == "scenario highway" for t in fig.texts)


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_the_navigation_figure_draws_estimate_truth_and_three_sigma(flights, axis):
    r = flights["true"]
    ax = landing_figures(r)["navigation.png"].axes[axis]
    a = "xyz"[axis]
    t_h, est = _line(ax, "estimate")
    # every row before touchdown whose horizon time is new, the first (t_h = 0) kept
    rows = np.flatnonzero((r["phase"] < TOUCHDOWN) & (np.r_[True, np.diff(r["t_h"]) > 0]))
    np.testing.assert_array_equal(t_h, r["t_h"][rows])
    np.testing.assert_array_equal(est, r[f"x_h_p_r_{a}"][rows])
    # the truth where the horizon time is a row's time: the logged p1 - p2 of that row
    t_truth, truth = _line(ax, "truth")
    np.testing.assert_array_equal(t_truth, t_h)
    k = np.searchsorted(r["t"], t_h - 1e-9)
    on_row = (k < len(r["t"])) & (np.abs(r["t"][np.minimum(k, len(r["t"]) - 1)] - t_h) < 1e-12)
    np.testing.assert_allclose(truth[on_row], (r[f"{a}1"] - r[f"{a}2"])[k[on_row]],
                               rtol=0, atol=1e-12)
    assert on_row.all()
    # at 100 Hz the horizon's times fall between rows: the truth between theirs
    r = flights["100 Hz"]
    t_h, truth = _line(landing_figures(r)["navigation.png"].axes[axis], "truth")
    k = np.searchsorted(r["t"], t_h)
    inside = (k > 0) & (k < len(r["t"]))
    before, after = ((r[f"{a}1"] - r[f"{a}2"])[k[inside] - d] for d in (1, 0))
    assert inside.sum() > 250
    assert np.all(truth[inside] >= np.minimum(before, after) - 1e-12)
    assert np.all(truth[inside] <= np.maximum(before, after) + 1e-12)
    r = flights["true"]
    # the band: the estimate +- 3 of the recorded standard deviations
    sigma = np.sqrt(r[f"P_h_{axis + 1}_{axis + 1}"][rows])
    (band,) = ax.collections
    y = band.get_paths()[0].vertices[:, 1]
    assert y.max() == pytest.approx(np.max(est + 3 * sigma), abs=1e-12)
    assert y.min() == pytest.approx(np.min(est - 3 * sigma), abs=1e-12)
    assert sigma[0] == pytest.approx(1.0)               # the handover's p0_position


def _by_hand(runs=4, times=30):
    """A Monte Carlo result of known averages; each block due at every other time."""
    rng = np.random.default_rng(3)
    t = np.arange(times) * 0.5
    nees = {g: rng.chisquare(T.shape[0], size=(runs, times)) for g, T in NEES_GROUPS.items()}
    nis = {}
    for b in BLOCKS:
        v = rng.chisquare(b.dim, size=(runs, times))
        v[:, 1::2] = np.nan
        v[0, ::4] = np.nan                        # one run short of a packet sometimes
        nis[b.name] = v
    sc = Scenario(name="byhand", source="<test>", data={})
    outliers = {b: np.full((runs, times), np.nan) for b in nis}
    return ConsistencyResult(sc, tuple(range(7, 7 + runs)), 2.0, t, nees, nis, outliers)


def test_the_consistency_figure_draws_the_averages_and_the_bounds():
    mc = _by_hand()
    fig = consistency_plot(mc)
    assert fig.get_suptitle() == CONSISTENCY_TITLE
    axes = fig.axes
    settled = mc.times >= 2.0
    for ax, g in zip(axes[:5], ("relative", "position", "velocity", "pad", "tilt"), strict=True):
        (line,) = ax.lines
        np.testing.assert_array_equal(line.get_xdata(), mc.times[settled])
        np.testing.assert_allclose(line.get_ydata(), mc.nees[g].mean(axis=0)[settled])
        lo, hi = chi2_bounds(NEES_GROUPS[g].shape[0], 4)
        y = ax.collections[0].get_paths()[0].vertices[:, 1]
        assert y.min() == pytest.approx(float(lo)) and y.max() == pytest.approx(float(hi))
    for ax, b in zip(axes[5:], BLOCKS, strict=True):
        (line,) = ax.lines
        due = settled & (np.arange(len(mc.times)) % 2 == 0)
        v = mc.nis[b.name][:, due]
        np.testing.assert_array_equal(line.get_xdata(), mc.times[due])
        np.testing.assert_allclose(line.get_ydata(), np.nanmean(v, axis=0))
        counts = np.sum(np.isfinite(v), axis=0)
        assert set(counts) == {3, 4}
        lo, hi = chi2_bounds(b.dim, counts)
        y = ax.collections[0].get_paths()[0].vertices[:, 1]
        assert y.min() == pytest.approx(lo.min()) and y.max() == pytest.approx(hi.max())
    assert any(t.get_text() == "scenario byhand: 4 hovers, seeds 7-10" for t in fig.texts)
