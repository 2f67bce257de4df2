"""A campaign's start: its table checked without SciPy, its forkserver started early (issue 20).

``NORMAL_REACH`` stands for SciPy's ``-ndtri(U_EDGE)`` in the reach of a normal
dispersion's draws; checked here against SciPy itself, bit for bit, and the reach of every
normal and truncated normal dispersion of the shipped campaigns against the reach computed
from SciPy's value.
"""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest
import scipy.special

from quadland.campaign import local
from quadland.campaign.draws import NORMAL_REACH, U_EDGE, extremes
from quadland.campaign.execute import run_campaign
from quadland.campaign.spec import campaign_spec_of
from quadland.exceptions import ScenarioError
from quadland.scenario import load_scenario


def test_the_normal_reach_is_scipy_s_ndtri_bit_for_bit():
    assert NORMAL_REACH == -float(scipy.special.ndtri(U_EDGE))
    assert NORMAL_REACH.hex() == (-float(scipy.special.ndtri(U_EDGE))).hex()


def test_the_normal_reach_is_where_the_normal_tail_holds_u_edge():
    """Independently of SciPy: the standard normal's upper tail ``erfc(x / sqrt 2) / 2``
    at the reach is ``U_EDGE`` (its slope there is ``x`` per unit of ``x``, so one ulp of
    the reach moves it by 1.5e-14 relative), and the standard library's inverse CDF (a
    rational approximation of its own) is within one ulp of it."""
    from statistics import NormalDist

    tail = 0.5 * math.erfc(NORMAL_REACH / math.sqrt(2.0))
    assert abs(tail / U_EDGE - 1.0) < 5e-15
    assert abs(-NormalDist().inv_cdf(U_EDGE) - NORMAL_REACH) <= math.ulp(NORMAL_REACH)


@pytest.mark.parametrize("name", ["highway", "ship"])
def test_the_draws_at_the_cube_s_edges_reach_the_checked_extremes(name, monkeypatch):
    """The draws themselves (SciPy's inverse CDFs in the sampling) at the corners
    ``U_EDGE`` and ``1 - U_EDGE`` of the unit cube: a normal dispersion's values are its
    checked extremes bit for bit, a truncated one's lie within them."""
    from quadland.campaign import sampling

    spec = campaign_spec_of(load_scenario(name))
    numeric = [d for d in spec.dispersions if d.distribution in ("normal", "truncnorm")]
    assert any(d.distribution == "normal" for d in numeric)
    for side, edge in enumerate((U_EDGE, 1.0 - U_EDGE)):
        monkeypatch.setattr(sampling, "unit_samples",
                            lambda s, idx, runs=None, e=edge: np.full((len(list(idx)), s.dims), e))
        values = sampling.draws(spec, [0])[0].values
        for disp in numeric:
            (target,) = disp.targets               # the shipped ones: one target, offset
            assert disp.mode == "offset" and disp.dims == len(target.nominal)
            got = np.atleast_1d(values[target.key])
            for e, (nominal, (lo, hi)) in enumerate(zip(target.nominal, extremes(disp),
                                                        strict=True)):
                if disp.distribution == "normal":
                    assert got[e] == nominal + (lo, hi)[side], (disp.key, e)
                else:
                    assert nominal + lo <= got[e] <= nominal + hi, (disp.key, e)


@pytest.mark.parametrize("name", ["highway", "ship", "turning", "ship_ss5", "highway_100"])
def test_every_shipped_dispersion_reaches_what_scipy_s_value_gives(name, monkeypatch):
    """Each numeric dispersion's checked extremes with the constant are those with SciPy's
    ``-ndtri(U_EDGE)`` computed at the test's time in its place."""
    from quadland.campaign import draws as draws_module

    spec = campaign_spec_of(load_scenario(name))
    numeric = [d for d in spec.dispersions if d.distribution not in ("seed", "choice")]
    assert any(d.distribution in ("normal", "truncnorm") for d in numeric)
    shipped = [extremes(disp) for disp in numeric]
    monkeypatch.setattr(draws_module, "NORMAL_REACH", -float(scipy.special.ndtri(U_EDGE)))
    assert [extremes(disp) for disp in numeric] == shipped


def test_a_normal_dispersion_that_overflows_is_still_refused():
    import dataclasses

    base = load_scenario("highway")
    table = {**base.campaign_table,
             "dispersions": {"quadrotor.mass": {"distribution": "normal", "mean": 0.0,
                                                "std": 1e308}}}
    with pytest.raises(ScenarioError, match="overflow"):
        campaign_spec_of(dataclasses.replace(base, campaign_table=table))


def test_checking_a_campaign_imports_no_scipy():
    script = ("import sys\n"
              "from quadland.scenario import load_scenario\n"
              "from quadland.campaign.spec import campaign_spec_of\n"
              "from quadland.campaign.execute import run_campaign\n"
              "for name in ('highway', 'ship'):\n"
              "    campaign_spec_of(load_scenario(name))\n"
              "print(sorted(m for m in sys.modules if m.split('.')[0] == 'scipy'))\n")
    out = subprocess.run([sys.executable, "-c", script], check=True, capture_output=True,
                         text=True).stdout.strip()
    assert out == "[]"


def test_the_forkserver_runs_before_the_simulator_loads_and_the_runs_are_the_same(
        tmp_path, monkeypatch):
    """The pool's server is started once the campaign is checked (its imports beside the
    simulator's load); two workers still write the runs.csv of one."""
    from multiprocessing import forkserver

    from quadland.campaign import execute

    fast = ["simulation.duration=0.5"]
    serial = tmp_path / "one"
    run_campaign("paper", fast, runs=6, out=serial, workers=1)
    seen, warm = [], execute.warm_up

    def warm_up(base):
        seen.append(forkserver._forkserver._forkserver_pid)
        warm(base)

    monkeypatch.setattr(execute, "warm_up", warm_up)
    forkserver._forkserver._stop()              # none left running by an earlier test
    assert forkserver._forkserver._forkserver_pid is None
    pool = tmp_path / "two"
    run_campaign("paper", fast, runs=6, out=pool, workers=2)
    assert len(seen) == 1 and seen[0] is not None
    assert (pool / "runs.csv").read_bytes() == (serial / "runs.csv").read_bytes()
    assert local.start_pool_server().get_start_method() == "forkserver"


def _forkserver_pid():
    from multiprocessing import forkserver

    return forkserver._forkserver._forkserver_pid


def test_a_campaign_with_at_most_one_run_to_fly_or_refused_starts_no_forkserver(tmp_path):
    """Only a pool's campaign starts the server early: not one refused by its checks,
    nor a resumed one with nothing, or one run, left to fly (flown in this process)."""
    from multiprocessing import forkserver

    fast = ["simulation.duration=0.5"]
    folder = tmp_path / "c"
    run_campaign("paper", fast, runs=3, out=folder, workers=1)
    lines = (folder / "runs.csv").read_text().splitlines()
    forkserver._forkserver._stop()
    assert _forkserver_pid() is None
    done = run_campaign("paper", fast, runs=3, out=folder, workers=2)
    assert done.flown == 0 and _forkserver_pid() is None
    (folder / "runs.csv").write_text("\n".join(lines[:-1]) + "\n")     # one run lost
    again = run_campaign("paper", fast, runs=3, out=folder, workers=2)
    assert again.flown == 1 and _forkserver_pid() is None
    assert (folder / "runs.csv").read_text().splitlines() == lines
    with pytest.raises(Exception, match="another campaign"):
        run_campaign("paper", ["simulation.duration=0.4"], runs=3, out=folder, workers=2)
    assert _forkserver_pid() is None
