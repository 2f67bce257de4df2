"""Campaign figures: failures.png claims no correlation when nothing failed (issue 21)."""

import numpy as np

from quadland.plots.campaign import failures_figure


def _texts(ax):
    legend = ax.get_legend()
    return [] if legend is None else [t.get_text() for t in legend.get_texts()]


def test_no_failures_says_so_and_draws_no_comparison(rng):
    x = rng.normal(size=40)
    severity = 0.5 + 0.1 * x                     # follows x exactly: no failure all the same
    fig = failures_figure(x, severity, np.zeros(40, dtype=bool), "deck.speed")
    left, right = fig.axes
    assert fig.get_suptitle() == "No failures: the runs against deck.speed"
    assert [t.get_text() for t in right.texts] == ["no failures\n(40 of 40 runs succeeded)"]
    assert len(right.lines) == 0 and right.get_legend() is None
    assert "failure" not in _texts(left) and "success" in _texts(left)
    (dots,) = left.collections                    # the successes only
    np.testing.assert_array_equal(dots.get_offsets(), np.column_stack([x, severity]))


def test_failures_compare_the_parameter_in_both_groups(rng):
    x = rng.normal(size=40)
    failed = x > 1.0                             # a threshold: the parameter separates them
    severity = np.where(failed, 1.5, 0.5)
    fig = failures_figure(x, severity, failed, "deck.speed")
    left, right = fig.axes
    assert len(right.texts) == 0
    assert _texts(right) == [f"successes ({int((~failed).sum())})",
                             f"failures ({int(failed.sum())})"]
    # each group's empirical CDF reaches 1 at its largest value
    for line, group in zip(right.lines, (~failed, failed), strict=True):
        xs, ps = line.get_xdata(), line.get_ydata()
        assert ps[-1] == 1.0 and xs[-1] == x[group].max()
    assert "failure" in _texts(left)
