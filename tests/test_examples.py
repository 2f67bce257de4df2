"""The scripts of examples/ run, and say what they claim (issue 21)."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _load(name):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_margins_with_python_control_agree():
    """python-control's stability_margins on the exported state-space models against
    quadland's table (its own crossings on its own frequency grid): the same phase and
    gain margins at the same frequencies."""
    loops = _load("margins_with_python_control").main()
    assert list(loops) == ["altitude", "roll", "pitch", "yaw"]
    for name, pairs in loops.items():
        theirs, ours = pairs["phase margin deg"]
        assert theirs == pytest.approx(ours, abs=1e-6), name
        theirs, ours = pairs["gain margin dB"]
        assert np.isfinite(theirs) and theirs == pytest.approx(ours, abs=1e-6), name
        theirs, ours = pairs["gain margin rad/s"]
        assert theirs == pytest.approx(ours, rel=1e-9), name


@pytest.mark.slow
def test_a_softer_gain_buys_phase_margin():
    rows = _load("tune_a_gain").main((1.0, 2.0))
    (k_soft, roll_soft, pitch_soft, _, ok_soft), (k_hard, roll_hard, pitch_hard, _, ok_hard) = rows
    assert roll_soft > roll_hard and pitch_soft > pitch_hard
    assert ok_soft and ok_hard


@pytest.mark.slow
def test_a_campaign_reads_into_pandas(tmp_path):
    import json

    runs = _load("campaign_in_pandas").main(tmp_path / "hw", runs=6)
    summary = json.loads((tmp_path / "hw" / "summary.json").read_text())
    assert len(runs) == 6
    assert runs["success"].astype(str).str.lower().eq("true").mean() == summary["success_rate"]


@pytest.mark.slow
def test_flight_code_for_a_heavier_quadrotor_carries_its_weight(tmp_path):
    forces = _load("flight_code_for_another_quadrotor").main(tmp_path / "tree", mass=3.0)
    np.testing.assert_allclose(forces[:4], 3.0 * 9.8 / 4, rtol=1e-12)
    assert forces[4] == pytest.approx(3.0 * 9.8, rel=1e-12)


@pytest.mark.slow
def test_the_notebook_runs_and_shows_its_results_inline(tmp_path):
    """The notebook runs top to bottom in a Jupyter kernel: importing quadland leaves the
    inline backend in place, each figure cell shows a PNG, a result shows in one line."""
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    import quadland

    nb = nbformat.read(EXAMPLES / "quadland_in_a_notebook.ipynb", as_version=4)
    nbclient.NotebookClient(nb, timeout=600, kernel_name="python3",
                            resources={"metadata": {"path": str(tmp_path)}}).execute()
    outputs = [o for c in nb.cells if c.cell_type == "code" for o in c.outputs]
    assert not [o for o in outputs if o.output_type == "error"]
    results = [o.data for o in outputs if o.output_type == "execute_result"]
    assert results[0]["text/plain"] == "'module://matplotlib_inline.backend_inline'"
    assert results[1]["text/plain"] == ("<SimulationResult of 'paper': 301 rows over 0..3 s, "
                                        "57 columns (list(result)), 422 states; .to_pandas()>")
    frame = results[2]                  # pd.DataFrame(res): a table, one column per signal
    assert "text/html" in frame and frame["text/plain"].split("\n")[0].split() == [
        "t", "z_e", "phi_e", "u_1"]
    figures = [r for r in results if r["text/plain"].startswith("<Figure size")]
    assert len(figures) == 4 and all(r["image/png"] for r in figures)    # shown inline
    paper = quadland.load_scenario("paper")
    assert results[-1]["text/plain"] == repr(("slow_paper", (1.5, 5.0, 10.0, 10.0),
                                              paper["rbf.nodes"]))
    printed = "".join(o.text for o in outputs if o.output_type == "stream")
    assert "sampled-data controller, zero-order hold at 50 Hz" in printed
    assert list(tmp_path.iterdir()) == []         # the notebook writes nothing where it runs
