"""The fixed costs of a command: BLAS threads, the build's cache key, lazy figures."""

from __future__ import annotations

import dataclasses
import json
import os
import subprocess
import sys

import casadi as ca
import pytest

from quadland.engine.build import have_compiler

_BLAS_THREADS = """
from quadland.__main__ import main
main(["scenarios"])
import json, numpy, scipy.linalg
from threadpoolctl import threadpool_info
print(json.dumps(sorted(i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas")))
"""


@pytest.mark.slow
@pytest.mark.parametrize("given, expected", [(None, 1), ("2", 2)])
def test_the_command_line_asks_blas_for_one_thread_unless_told(given, expected):
    """Both OpenBLAS libraries (NumPy's and SciPy's, loaded after the command
    started) run one thread; a count in the environment is kept."""
    env = {k: v for k, v in os.environ.items()
           if k not in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "OMP_NUM_THREADS")}
    if given is not None:
        env["OPENBLAS_NUM_THREADS"] = given
    out = subprocess.run([sys.executable, "-c", _BLAS_THREADS], capture_output=True, text=True,
                         env=env, check=True)
    counts = json.loads(out.stdout.strip().splitlines()[-1])
    assert counts and counts == [expected] * len(counts)


# --- the cache key of a compiled simulator ------------------------------------------

@pytest.fixture
def cache(tmp_path, monkeypatch):
    """A private build cache for the test."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    return tmp_path / "xdg" / "quadland"


def _key(model, part="continuous", flight=None):
    from quadland.engine.recall import recall_key

    return recall_key(model, part, flight, (), f"qlsim_{model.name}_{part}", "-O2", False)


@pytest.mark.skipif(not have_compiler(), reason="needs a C compiler")
def test_the_key_changes_whenever_the_generated_c_does(monkeypatch):
    """Models whose generated C differs (2 and 3 nodes; the same model with another
    constant), another generator or other flight files give other keys; the same
    model, rebuilt, the same key."""
    from quadland.engine import recall
    from quadland_symbolic.codegen import simulator_sources
    from quadland_symbolic.paper_loop import paper_loop

    two, three = paper_loop.__wrapped__(2), paper_loop.__wrapped__(3)
    assert simulator_sources(two, "continuous") != simulator_sources(three, "continuous")
    assert _key(two) != _key(three)
    assert _key(two) == _key(paper_loop.__wrapped__(2))
    assert _key(two) != _key(two, "sampled")
    assert _key(two, "sampled_flight", "one recipe") != _key(two, "sampled_flight", "another")
    scaled = dataclasses.replace(two, output_fn=_times_two(two.output_fn))
    assert simulator_sources(scaled, "continuous") != simulator_sources(two, "continuous")
    assert _key(scaled) != _key(two)
    before = _key(two)
    monkeypatch.setattr(recall, "generator_digest", lambda: "another generator")
    assert _key(two) != before


def _times_two(f):
    """``f`` with every output doubled, under the same name and signature."""
    args = f.sx_in()
    return ca.Function(f.name(), args, [2 * out for out in f.call(args)], f.name_in(),
                       f.name_out())


@pytest.mark.slow
@pytest.mark.skipif(not have_compiler(), reason="needs a C compiler")
def test_a_cached_simulator_loads_without_generating_its_c(cache, monkeypatch):
    """The second load finds the library its generated text was built into, without
    generating it; a damaged library is not recalled but generated and rebuilt."""
    from quadland.engine import compiled
    from quadland_symbolic.paper_loop import paper_loop

    model, generate = paper_loop(2), compiled.simulator_sources
    calls = []

    def counted(*args):
        calls.append(args)
        return generate(*args)

    monkeypatch.setattr(compiled, "simulator_sources", counted)
    first = compiled.CompiledLoop(model, "continuous").library
    good = first.read_bytes()
    assert len(calls) == 1 and first.is_relative_to(cache)
    assert compiled.CompiledLoop(model, "continuous").library == first
    assert len(calls) == 1
    damaged = first.with_name("damaged")          # a new file: this process maps the old one
    damaged.write_bytes(good[:1000])
    os.replace(damaged, first)
    assert compiled.CompiledLoop(model, "continuous").library == first
    assert len(calls) == 2 and first.read_bytes() == good


# --- a run's rows in small pages ------------------------------------------------------

def test_a_row_buffer_is_zeroed_and_leaves_numpy_s_huge_page_advice_as_it_was():
    """The buffer is the zeros NumPy would give; NumPy's process-wide switch is back
    where it was (either way) after each allocation."""
    import numpy as np

    from quadland.engine.runs import row_buffer

    switch = getattr(np._core.multiarray, "_set_madvise_hugepage", None)
    if switch is None:
        pytest.skip("this NumPy has no huge-page switch")
    initial = switch(True)
    try:
        for setting in (True, False, True):
            switch(setting)
            buf = row_buffer(1500, 700)                      # 8.4 MB: over NumPy's 4 MiB
            assert buf.shape == (1500, 700) and buf.dtype == np.float64
            assert buf.flags.c_contiguous and buf.flags.writeable and not buf.any()
            assert switch(setting) is setting
    finally:
        switch(initial)


def test_flight_code_is_keyed_by_what_it_is_generated_from():
    """Equal requests give equal flight code (one simulator per process) without
    generating it; another node count or another set of functions another recipe."""
    from quadland.kinds.landing.flight import flight_code as landing_flight
    from quadland.kinds.paper.flight import flight_code as paper_flight

    assert paper_flight(2) == paper_flight(2) and hash(paper_flight(2)) == hash(paper_flight(2))
    recipes = {paper_flight(2).recipe, paper_flight(3).recipe, landing_flight(2).recipe,
               landing_flight(2, sensed=True).recipe, landing_flight(3).recipe}
    assert len(recipes) == 5
    assert dict(paper_flight(2).files) != dict(paper_flight(3).files)


@pytest.mark.slow
@pytest.mark.skipif(not have_compiler(), reason="needs a C compiler")
def test_a_cached_flight_simulator_loads_without_generating_the_flight_code(cache):
    """The flight code's files are generated for the first build only."""
    from quadland.engine import compiled
    from quadland.kinds.paper.flight import flight_code
    from quadland_symbolic.paper_loop import paper_loop

    calls = []

    def counted():
        code = flight_code(2)
        return dataclasses.replace(code, make=lambda: calls.append(1) or code.make())

    first = compiled.CompiledLoop(paper_loop(2), "sampled_flight", flight=counted()).library
    assert calls == [1]
    again = compiled.CompiledLoop(paper_loop(2), "sampled_flight", flight=counted()).library
    assert again == first and calls == [1]
