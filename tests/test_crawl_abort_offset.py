"""``crawl_abort_offset``: the crawl's out-of-limits abort is also started past this estimated
horizontal offset, below the judge's ``max_offset`` (symbolic/landing/abort_floor.py), by hand
on one guidance step: the abort sends the phase back to align, counts one abort and resets the
reference to the hover height; otherwise the committed crawl falls on at ``touchdown_speed``.
The default, 1000 m, leaves ``max_offset`` the only bound (the guidance of before)."""

import ctypes

import numpy as np
import pytest
from crawl_step import CRAWLED, aborted, crawl_step
from reference import GUIDANCE_P, have_compiler

from quadland.kinds.landing.flight import load_landing_api
from quadland.scenario import load_scenario, scenario_names
from quadland_symbolic.landing.guidance import ALIGN, DESCEND


def _step(offset, gap=0.1, **params):
    """One committed crawl step (:func:`crawl_step.crawl_step`) with the estimated
    horizontal offset ``offset`` along x and the gear ``gap`` above the contact."""
    return crawl_step(gap, offset, **params)


#: By hand: the abort (:func:`crawl_step.aborted`) and the crawl going on.
ABORTED = aborted()


def _check(got, want):
    assert got[:2] == want[:2]
    assert got[2] == pytest.approx(want[2], rel=1e-12)


def test_the_default_bounds_by_max_offset_only():
    """1000 m: 0.15 m off (inside max_offset 0.2) crawls on, 0.25 m aborts, as before the key."""
    assert GUIDANCE_P["crawl_abort_offset"] == 1e3 and GUIDANCE_P["max_offset"] == 0.2
    _check(_step(0.15), CRAWLED)
    _check(_step(0.25), ABORTED)


def test_past_the_key_the_crawl_aborts():
    """0.1 m: 0.15 m off aborts, 0.09 m crawls on; a key above max_offset loosens nothing
    (0.5 m: 0.25 m off still aborts on max_offset)."""
    _check(_step(0.15, crawl_abort_offset=0.1), ABORTED)
    _check(_step(0.09, crawl_abort_offset=0.1), CRAWLED)
    _check(_step(0.25, crawl_abort_offset=0.5), ABORTED)


def test_at_the_key_no_abort_and_just_above_it_one():
    """'Past': with binary-exact figures (the key 0.125 m) 0.125 m off crawls on and
    0.125 + 2^-20 m aborts."""
    assert _step(0.125, crawl_abort_offset=0.125)[:2] == (DESCEND, 0.0)
    assert _step(0.125 + 2.0 ** -20, crawl_abort_offset=0.125)[:2] == (ALIGN, 1.0)


def test_the_abort_floor_still_holds():
    """With abort_floor 0.06 m the same 0.15 m abort is not started with the gear 1 cm over
    the deck, and is 10 cm over it."""
    _check(_step(0.15, gap=0.01, crawl_abort_offset=0.1, abort_floor=0.06), CRAWLED)
    _check(_step(0.15, gap=0.10, crawl_abort_offset=0.1, abort_floor=0.06), ABORTED)


def test_the_budget_bounds_the_windows_the_key_holds():
    """``crawl_abort_budget`` 3: after two aborted descents the 0.15 m abort past a 0.1 m key
    is started (the count goes to 3); after three the key no longer holds and the crawl falls
    on at 0.15 m off, while 0.25 m still aborts on ``max_offset``. The default (1e6) holds the
    key after 50 aborts; 0 never holds it."""
    def step(offset, n, **p):
        return crawl_step(0.1, offset, aborts=float(n), crawl_abort_offset=0.1, **p)
    hover = ABORTED[2]
    _check(step(0.15, 2, crawl_abort_budget=3.0), (ALIGN, 3.0, hover))
    _check(step(0.15, 3, crawl_abort_budget=3.0), (DESCEND, 3.0, CRAWLED[2]))
    _check(step(0.25, 3, crawl_abort_budget=3.0), (ALIGN, 4.0, hover))
    assert GUIDANCE_P["crawl_abort_budget"] == 1e6
    _check(step(0.15, 50), (ALIGN, 51.0, hover))
    _check(step(0.15, 0, crawl_abort_budget=0.0), (DESCEND, 0.0, CRAWLED[2]))


def test_the_schema_default_and_the_shipped_scenarios():
    """Both keys are optional (1000 m, no tighter bound; a budget of 1e6, always) and no
    shipped scenario sets them (``ship_ss5`` with 0.15 m over three windows lost seed 13's
    run 22: docs/landing.md, "ship_ss5 out of sample: the gust's drift in the crawl, and an
    abort at 0.15 m")."""
    for name in scenario_names():
        sc = load_scenario(name)
        if sc.model == "landing":
            assert sc["landing.crawl_abort_offset"] == 1e3
            assert sc["landing.crawl_abort_budget"] == 1e6
    for bad in ("-0.1", "0", "nan", "1001"):
        with pytest.raises(Exception, match="crawl_abort_offset"):
            load_scenario("ship", [f"landing.crawl_abort_offset={bad}"])
    for bad in ("-1", "nan", "inf", "1000001", "abc"):
        with pytest.raises(Exception, match="crawl_abort_budget"):
            load_scenario("ship", [f"landing.crawl_abort_budget={bad}"])


@pytest.mark.skipif(not have_compiler(), reason="no C compiler")
@pytest.mark.parametrize("precision", ["double", "float"])
def test_the_flight_code_refuses_what_the_schema_refuses(precision):
    """Review: 0 m would abort every crawl with any offset (elsewhere 0 turns a key off), so
    the range is (0, 1000] as ``max_offset``'s is open at 0. ``ql_check_guidance_params``
    names the key for 0, -0.0, -1, NaN and an infinity, takes the smallest positive value and
    1000 (``tests/test_fuzz_landing_step.py`` draws the rest against the same range)."""
    api = load_landing_api(10, precision)
    gp = api.GuidanceParams()
    api.lib.ql_guidance_params_init(ctypes.byref(gp))
    bad = ctypes.c_char_p()
    tiny = np.finfo(np.float64 if precision == "double" else np.float32).tiny
    for value, refused in ((0.0, True), (-0.0, True), (-1.0, True), (np.nan, True),
                           (np.inf, True), (tiny, False), (1e3, False), (0.1, False)):
        gp.crawl_abort_offset = value
        status = api.lib.ql_check_guidance_params(ctypes.byref(gp), ctypes.byref(bad))
        assert (status != 0, bad.value) == ((True, b"crawl_abort_offset") if refused
                                            else (False, None)), value
    api.lib.ql_guidance_params_init(ctypes.byref(gp))
    for value, refused in ((-1.0, True), (np.nan, True), (np.inf, True), (0.0, False),
                           (3.0, False), (1e6, False)):
        gp.crawl_abort_budget = value
        status = api.lib.ql_check_guidance_params(ctypes.byref(gp), ctypes.byref(bad))
        assert (status != 0, bad.value) == ((True, b"crawl_abort_budget") if refused
                                            else (False, None)), value
