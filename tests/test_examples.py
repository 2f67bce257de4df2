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
    for name, (theirs, ours) in _load("margins_with_python_control").main().items():
        assert theirs == pytest.approx(ours, abs=1e-6), name


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
