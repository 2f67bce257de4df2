"""A campaign in which nothing failed: failures.png says so instead of pointing at a
correlation (issue 21)."""

import csv

import pytest

import quadland.plots.campaign as campaign_plots
from quadland.campaign import run_campaign
from quadland.campaign.summary import (
    campaign_figures,
    counted_text,
    summarize_campaign,
    summary_counts,
)
from quadland.scenario import load_scenario


@pytest.mark.slow
def test_failures_figure_of_a_campaign_without_failures(tmp_path, monkeypatch):
    """Three highway landings, kept to those that succeeded: the summary has no
    separation to show, and the failures figure's title says no run failed."""
    out = tmp_path / "hw"
    run_campaign("highway", runs=3, out=out, workers=1, plots=False, progress=False)
    with open(out / "runs.csv", newline="") as fh:
        header, *rows = list(csv.reader(fh))
    rows = [r for r in rows if r[header.index("success")] == "true"]
    assert rows, "no highway run of this campaign succeeded"
    base = load_scenario(out / "scenario.toml")
    summary = summarize_campaign(base, header, rows)
    assert summary["success_rate"] == 1.0 and summary["separation"] is None
    # the 0/1 flags are counted (review of issue 17: only their quantiles were, so one false
    # touchdown and five read the same): mark the first run's by hand
    ft, tip = header.index("false_touchdown"), header.index("tipped")
    marked = [list(r) for r in rows]
    marked[0][ft], marked[-1][tip] = "1.0", "1.0"
    counts = summarize_campaign(base, header, marked)["metrics"]
    assert counts["false_touchdown"]["count"] == 1 and counts["tipped"]["count"] == 1
    assert summary["metrics"]["false_touchdown"]["count"] == 0
    assert counted_text("landing", summary_counts(summary)) == "; false touchdowns 0, tipped over 0"
    titles = []
    draw = campaign_plots.failures_figure
    monkeypatch.setattr(campaign_plots, "failures_figure",
                        lambda *a: titles.append(a[4]) or draw(*a))
    files = campaign_figures(base, header, rows, summary)
    assert "failures.png" in files and files["failures.png"][:8] == b"\x89PNG\r\n\x1a\n"
    name = summary["most_correlated"]["parameter"]
    assert titles == [f"No failures in {len(rows)} runs: the severity against {name}"]
