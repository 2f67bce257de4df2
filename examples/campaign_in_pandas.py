"""Run a small campaign and read its results with pandas.

A campaign writes runs.csv (one row per dispersed landing: its draws, its
touchdown figures, success) and summary.json (the success rate with its
confidence interval). pandas reads both as they are.

Run: python examples/campaign_in_pandas.py [OUT]
"""

import json
import sys
import tempfile
from pathlib import Path

import pandas as pd

import quadland


def main(out: Path, runs: int = 20) -> pd.DataFrame:
    result = quadland.run_campaign("highway", runs=runs, out=out, workers=1, plots=False,
                                   progress=False)
    runs_csv = pd.read_csv(result.folder / "runs.csv")
    summary = json.loads((result.folder / "summary.json").read_text())
    low, high = summary["confidence"]["interval"]
    print(f"{summary['success_rate']:.1%} of {len(runs_csv)} landings within limits "
          f"(95 % interval {low:.1%} to {high:.1%})")
    print(runs_csv[["sink_rate", "offset", "touchdown_time"]].describe().round(3))
    # the draws beside the outcome: which dispersion goes with a slow touchdown?
    draws = [c for c in runs_csv.columns if "." in c]
    corr = runs_csv[draws].corrwith(runs_csv["touchdown_time"]).dropna()
    print("strongest correlation with the touchdown time:",
          corr.abs().idxmax(), f"{corr[corr.abs().idxmax()]:+.2f}")
    return runs_csv


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp()) / "hw")
