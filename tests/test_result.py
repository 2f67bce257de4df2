"""SimulationResult as pandas sees it: ``pd.DataFrame(result)`` and ``result.to_pandas()``
against the ``trajectory.csv`` that ``quadland simulate`` writes for the same scenario
(issue 21), and a result's read-only dict."""

import copy
import pickle

import numpy as np
import pytest

from quadland.cli import main
from quadland.scenario import load_scenario
from quadland.simulation import simulate

pd = pytest.importorskip("pandas")

#: A paper run (every signal in its CSV) and a whole landing on the highway: approach,
#: descent, the first contact's row, the ride on the deck (its CSV a selection).
CASES = {"paper": ["simulation.duration=1.0"], "highway": []}


@pytest.fixture(scope="module")
def flown(tmp_path_factory):
    """``flown(name)``: the result of ``quadland.simulate`` and the CSV the command line
    wrote for it, each case flown once."""
    cache = {}

    def fly(name):
        if name not in cache:
            overrides = CASES[name]
            out = tmp_path_factory.mktemp(name) / "out"
            args = ["simulate", "--scenario", name, "--no-plots", "--out", str(out)]
            for o in overrides:
                args += ["--set", o]
            assert main(args) == 0
            cache[name] = (simulate(load_scenario(name, overrides)),
                           pd.read_csv(out / "trajectory.csv"))
        return cache[name]
    return fly


@pytest.fixture(params=sorted(CASES))
def run_and_csv(request, flown):
    return flown(request.param)


def test_pd_dataframe_of_a_result_is_one_column_per_signal(run_and_csv):
    res, csv = run_and_csv
    frame = pd.DataFrame(res)
    # every signal the result holds, as columns in its order, one row per time
    assert list(frame.columns) == list(res) and frame.shape == (len(res["t"]), len(res))
    assert set(csv.columns) <= set(frame.columns)
    # the CSV's numbers (written to 12 significant digits) in the same rows
    np.testing.assert_allclose(frame[list(csv.columns)].to_numpy(), csv.to_numpy(),
                               rtol=1e-11, atol=1e-300)
    # pandas copied the arrays: the frame is writable, the result untouched
    before = float(res["t"][1])
    frame.loc[1, "t"] = -1.0
    assert res["t"][1] == before
    # pandas' own column selection of a dict works too
    picked = pd.DataFrame(res, columns=["t", "z_e"])
    np.testing.assert_array_equal(picked["z_e"].to_numpy(), res["z_e"])


def test_to_pandas_is_the_csv_with_its_units(run_and_csv):
    res, csv = run_and_csv
    frame = res.to_pandas()
    assert list(frame.columns) == list(csv.columns)
    np.testing.assert_allclose(frame.to_numpy(), csv.to_numpy(), rtol=1e-11, atol=1e-300)
    assert frame.attrs["units"]["t"] == "s" and frame.attrs["units"]["z_e"] == "m"
    # the same numbers as pd.DataFrame(result) gives for those columns
    pd.testing.assert_frame_equal(frame, pd.DataFrame(res)[list(csv.columns)],
                                  check_like=False, check_flags=False, check_exact=True)


def test_a_landing_frame_has_its_first_contact_and_the_ride(flown):
    res, csv = flown("highway")
    frame = pd.DataFrame(res)
    # the first contact's row sits between two output ticks (not on the 10 ms grid),
    # and from it on ``touched`` is 1 (the signals only the result holds, not the CSV)
    k = int(np.argmax(frame["touched"].to_numpy() == 1.0))
    t_ev = frame["t"][k]
    assert abs(t_ev * 100 - round(t_ev * 100)) > 1e-6
    assert frame["touched"][:k].eq(0.0).all() and frame["touched"][k:].eq(1.0).all()
    assert csv["t"][k] == pytest.approx(t_ev, rel=1e-11)
    assert "touched" not in csv.columns


def test_a_result_stays_read_only():
    res = simulate(load_scenario("paper", ["simulation.duration=0.05"]))
    for change in (lambda r: r.__setitem__("z_e", np.zeros(6)), lambda r: r.pop("z_e"),
                   lambda r: r.update(z_e=np.zeros(6)), lambda r: r.clear(),
                   lambda r: r.setdefault("new", 1), lambda r: r.popitem(),
                   lambda r: r.__delitem__("t")):
        with pytest.raises(TypeError, match="SimulationResult is read-only"):
            change(res)
    with pytest.raises(TypeError, match="read-only"):
        res |= {"z_e": np.zeros(6)}
    with pytest.raises(ValueError, match="read-only"):
        res["z_e"][0] = 1.0
    assert len(res) == len(res.columns) and list(res) == list(res.columns)
    # a copy by pickle (a campaign's worker) or copy is a result again, as read-only
    for other in (pickle.loads(pickle.dumps(res)), copy.deepcopy(res), copy.copy(res)):
        assert type(other) is type(res) and list(other) == list(res)
        np.testing.assert_array_equal(other["z_e"], res["z_e"])
        assert not other["z_e"].flags.writeable
    # dict(result) is a plain dict to change
    plain = dict(res)
    plain["z_e"] = np.zeros(6)
    assert res["z_e"][0] != 0.0
