"""Seeded, bounded fuzzing of the navigation filter's generated C against its contract.

The contract is ``quadland_estimator.h``'s (docs/codegen.md, "The navigation filter's
API"): every call of ``ql_estimator_step`` returns a documented status; NULL
pointers, a non-finite memory, parameter, ``dt`` or ``t``, ``dt <= 0``, a FIFO count
that is not a whole number in ``[0, depth]`` and a parameter outside its documented
range are errors, in that order (a non-finite ``eta_hat`` or ``omega`` of the IMU with
the memory's: they pass on to ``y``); on an error the memory is left bit for bit
untouched and ``y`` and ``diag`` are zero; on ``QL_OK`` the new memory keeps the FIFO
invariant and is finite, ``diag`` and ``y`` are finite, ``y.eta1`` and ``y.Omega1`` the
IMU's ``eta_hat`` and ``omega`` bit for bit. Packets and the specific force are never
errors, whatever they hold. In double every call is also
compared with the CasADi function: ``QL_OK`` exactly when its outputs are finite,
and then the same bits. ``ql_check_estimator_params`` rejects exactly the parameters
outside their documented ranges (tests/test_estimator_flight_code.py's table) and
names the first.

Each call starts from a random memory (a handover, then random buffered inputs,
FIFO contents and counts, counters and broadcast), random packets (fresh or not,
due, late, old or from the future) and a random IMU sample, then overwrites a few
entries with extreme (huge, tiny, subnormal, negative zero), non-finite or raw-bit
values; one call in twenty holds a covariance entry at the largest finite value,
whose products overflow (``QL_ERR_NONFINITE_OUTPUT`` by design, not by chance).
Two campaigns per precision, as tests/test_fuzz_landing_step.py: through ``ctypes``
(:data:`CALLS` calls, the oracle above) and, where the compiler has
AddressSanitizer and UndefinedBehaviorSanitizer, a C driver built with them
(:data:`SANITIZED_CALLS` calls). ``python tests/test_fuzz_estimator_step.py N [SEED]``
runs a longer ctypes campaign and prints the outcomes.
"""

from __future__ import annotations

import collections
import math
import sys

import numpy as np
import pytest
from estimator_c import Call, files, load, sources
from reference import C_RANDOM, extreme, have_compiler
from reference import run as _run
from reference import sanitized_drivers as build_sanitized
from test_estimator_flight_code import first_bad

from quadland_symbolic.codegen import STATUS_CODES
from quadland_symbolic.codegen.estimator_api import flight_memory
from quadland_symbolic.landing.controller import LANDING_MEASUREMENT
from quadland_symbolic.landing.estimator import (
    FLIGHT_COUPLING,
    FLIGHT_DEPTH,
    N_HIST,
    estimator_step_function,
)
from quadland_symbolic.landing.navigation import NAV, NAV_PACKETS, SENSORS, estimator_params

pytestmark = pytest.mark.skipif(not have_compiler(), reason="no C compiler")

SEED = 1729
#: ctypes calls per precision (about 5 s in double, with the CasADi oracle).
CALLS = 2000
#: Calls of the sanitized C driver per precision.
SANITIZED_CALLS = 20000
STATUS = {name: value for name, value, _ in STATUS_CODES}
MEM = flight_memory()
DT = 0.004
COUNTS = [MEM.slice(f"count_{s}").start for s in SENSORS]
RANGE_MIN_COS = estimator_params().slice("range_min_cos").start
P_H = MEM.offsets()["P_h"]
Y_IMU = np.r_[np.arange(*LANDING_MEASUREMENT.offsets()["eta1"]),
              np.arange(*LANDING_MEASUREMENT.offsets()["Omega1"])]
Y_FILTER = np.setdiff1d(np.arange(LANDING_MEASUREMENT.size), Y_IMU)
#: The IMU's entries passed on to y: the attitude estimate (0-2) and the rates (6-8).
IMU_PASSED = np.r_[0:3, 6:9]


def _counts_valid(mem) -> bool:
    c = mem[COUNTS].astype(float)
    return bool(np.all((c >= 0) & (c <= FLIGHT_DEPTH) & (c == np.floor(c))))


class _Harness:
    """One build's filter API and a random operating point per call."""

    def __init__(self, precision: str):
        self.c = Call(load(precision))
        self.dtype = self.c.api.dtype
        self.p0 = self.c.v["params"].copy()

    def draw(self, rng):
        """Fill the arguments; return dt, t and the pointer arguments to pass as NULL."""
        c, v = self.c, self.c.v
        t0 = rng.uniform(-10, 1000)
        assert c.init(rng.normal(size=NAV.size), rng.uniform(0, 2, NAV.size),
                      rng.normal(size=9) * 0.2,
                      t0) == STATUS["QL_OK"]
        mem = MEM.unpack(v["mem"].astype(float))
        k = rng.integers(N_HIST + 1)                   # periods flown since the handover
        hist = mem["hist"].copy()
        hist[0:3, N_HIST - k:] = rng.normal(size=(3, k)) * 2
        hist[3, N_HIST - k:] = DT
        mem["hist"] = hist
        for s, depth in zip(SENSORS, FLIGHT_DEPTH, strict=True):
            n = rng.integers(depth + 1)
            fifo = mem[f"fifo_{s}"].copy()
            fifo[:, :n] = rng.normal(size=(fifo.shape[0], n))
            fifo[0, :n] = np.sort(t0 + rng.uniform(-0.1, 0.3, n))
            mem[f"fifo_{s}"], mem[f"count_{s}"] = fifo, float(n)
        for name in ("n_fused", "n_rejected", "n_discarded", "n_dropped", "n_held",
                     "n_imu_invalid"):
            mem[name] = rng.integers(0, 1000, size=np.size(mem[name])).astype(float)
        v["mem"][:] = MEM.pack(mem)
        v["params"][:] = self.p0
        if rng.uniform() < 0.3:                        # a valid retune
            v["params"][:] *= 10 ** rng.uniform(-1, 1, size=v["params"].size)
            v["params"][RANGE_MIN_COS] = rng.uniform(0.2, 1.0)
        t = t0 + DT * (k + 1)
        for layout in NAV_PACKETS:
            p = v[layout.name]
            p[:] = rng.normal(size=p.size) * rng.choice((0.1, 3.0, 1e3))
            p[0] = float(rng.uniform() < 0.7)
            p[1] = t - rng.choice((0.0, 0.1, 0.2, 0.25, 0.5, -0.05)) + rng.normal() * 0.01
        v["imu"][:] = rng.normal(size=9) * [0.3, 0.3, 3, 1, 1, 10, 1, 1, 1]
        dt = DT if rng.uniform() < 0.9 else 10 ** rng.uniform(-6, 1)
        if rng.uniform() < 0.05:                       # finite, but overflows: no output
            v["mem"][rng.integers(*P_H)] = np.finfo(self.dtype).max
        if rng.uniform() < 0.05:                       # a corrupted FIFO count
            v["mem"][COUNTS[rng.integers(4)]] = rng.choice((-1.0, 0.5, 27.0, 9.0, 5.0))
        if rng.uniform() < 0.3:
            return float(self.dtype(dt)), float(self.dtype(t)), ()
        targets = (v["mem"], v["params"], v["imu"], *[v[s] for s in SENSORS], "dt", "t")
        for _ in range(rng.integers(1, 4)):
            target = targets[rng.integers(len(targets))]
            value = extreme(rng, self.dtype)
            if isinstance(target, str) and target == "dt":
                dt = value
            elif isinstance(target, str):
                t = value
            else:
                target[rng.integers(target.size)] = value
        null = () if rng.uniform() > 0.02 else (Call.ARGS[rng.integers(len(Call.ARGS))],)
        return float(self.dtype(dt)), float(self.dtype(t)), null


def _check(h, rng, counts, oracle):
    dt, t, null = h.draw(rng)
    c, v = h.c, h.c.v
    bad = first_bad(v["params"])
    assert c.check() == ((STATUS["QL_ERR_PARAM"], bad) if bad else (STATUS["QL_OK"], None))
    args = [v[n].astype(float) for n in ("mem", "imu", *SENSORS, "params")]
    before = bytes(c.s["mem"])
    v["y"][:] = 7.0
    v["diag"][:] = 7.0
    status = c.step(dt, t, null)
    counts[status] += 1
    assert status in STATUS.values()
    mem = args[0]
    if null:
        assert status == STATUS["QL_ERR_NULL"]
    elif not (np.all(np.isfinite(mem)) and np.all(np.isfinite(args[-1])) and math.isfinite(dt)
              and math.isfinite(t) and np.all(np.isfinite(args[1][IMU_PASSED]))):
        assert status == STATUS["QL_ERR_NONFINITE_INPUT"]
    elif not (dt > 0 and _counts_valid(mem)):
        assert status == STATUS["QL_ERR_INVALID"]
    elif bad:
        assert status == STATUS["QL_ERR_PARAM"]
    else:
        assert status in (STATUS["QL_OK"], STATUS["QL_ERR_NONFINITE_OUTPUT"])
        if oracle is not None:
            want = [np.asarray(o, dtype=float).ravel() for o in oracle(*args, dt, t)]
            finite = (np.all(np.isfinite(want[0])) and np.all(np.isfinite(want[1][Y_FILTER]))
                      and np.all(np.isfinite(want[2])))
            assert status == (STATUS["QL_OK"] if finite else STATUS["QL_ERR_NONFINITE_OUTPUT"])
            if finite:
                for got, w in zip((v["mem"], v["y"], v["diag"]), want, strict=True):
                    np.testing.assert_array_equal(got.view(np.uint64), w.view(np.uint64))
    if status != STATUS["QL_OK"]:
        assert bytes(c.s["mem"]) == before, "the memory is untouched on error"
        if "y" not in null:
            assert not np.any(v["y"]), "y is zero on error"
        if "diag" not in null:
            assert not np.any(v["diag"]), "diag is zero on error"
        return
    assert np.all(np.isfinite(v["mem"])) and _counts_valid(v["mem"])
    assert np.all(np.isfinite(v["diag"])) and np.all(np.isfinite(v["y"]))
    imu = args[1]
    np.testing.assert_array_equal(v["y"][Y_IMU].view(np.uint32 if h.dtype == np.float32
                                                     else np.uint64),
                                  np.r_[imu[0:3], imu[6:9]].astype(h.dtype).view(
                                      np.uint32 if h.dtype == np.float32 else np.uint64))
    counts["imu_invalid"] += not np.all(np.isfinite(imu[3:6]))


def _campaign(precision, calls, seed=SEED):
    h = _Harness(precision)
    rng = np.random.default_rng([seed, precision == "float"])
    oracle = estimator_step_function(N_HIST, FLIGHT_DEPTH, FLIGHT_COUPLING) \
        if precision == "double" else None
    counts = collections.Counter()
    for _ in range(calls):
        _check(h, rng, counts, oracle)
    return counts


@pytest.mark.slow
@pytest.mark.parametrize("precision", ["double", "float"])
def test_random_calls_keep_the_contract(precision):
    counts = _campaign(precision, CALLS)
    for name in STATUS:
        if name != "QL_ERR_TILT":                    # the filter has no tilt
            assert counts[STATUS[name]] >= 5, (name, counts)
    assert counts[STATUS["QL_OK"]] >= CALLS // 4
    assert counts[STATUS["QL_ERR_TILT"]] == 0
    assert counts["imu_invalid"] >= 5


# --- the sanitized build -----------------------------------------------------

#: A C driver of seeded random calls that checks the contract's C-visible part and
#: counts the outcomes.
DRIVER = r"""
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "quadland_estimator.h"

#define N_REALS(s) ((int)(sizeof(s) / sizeof(ql_real)))

/* RANDOM */

static int fail(long k, const char *what, int status)
{
    printf("call %ld: %s (status %d)\n", k, what, status);
    return 1;
}

static int all_finite(const ql_real *v, int n)
{
    int i;
    for (i = 0; i < n; ++i) {
        if (!isfinite(v[i])) return 0;
    }
    return 1;
}

static int counts_valid(const ql_estimator_memory *m)
{
    const ql_real c[4] = {m->count_vision, m->count_gnss, m->count_range, m->count_datalink};
    const int d[4] = {QL_ESTIMATOR_DEPTH_VISION, QL_ESTIMATOR_DEPTH_GNSS,
                      QL_ESTIMATOR_DEPTH_RANGE, QL_ESTIMATOR_DEPTH_DATALINK};
    int i;
    for (i = 0; i < 4; ++i) {
        if (!(c[i] >= 0 && c[i] <= d[i] && c[i] == (ql_real)(int)c[i])) return 0;
    }
    return 1;
}

static void fill(ql_real *v, int n, double scale)
{
    int i;
    for (i = 0; i < n; ++i) v[i] = (ql_real)(scale * (2 * uniform() - 1));
}

int main(int argc, char **argv)
{
    static ql_estimator_memory mem, before;
    ql_estimator_params defaults, params;
    ql_estimator_diagnostics diag;
    ql_landing_measurement y;
    ql_nav_state x0;
    ql_deck_init deck0;
    ql_imu imu;
    ql_vision_packet vision;
    ql_gnss_packet gnss;
    ql_range_packet range;
    ql_datalink_packet datalink;
    ql_real P0[QL_NAV_SIZE], dt, t, *targets[9], *packets[4];
    int sizes[9], psizes[4], i, j;
    long k, n = argc > 1 ? atol(argv[1]) : 1000, counts[8] = {0};
    const char *bad;

    seed = argc > 2 ? strtoull(argv[2], NULL, 10) : 1;
    if (seed == 0) {
        seed = 1;   /* xorshift stays at 0 */
    }
    ql_estimator_params_init(&defaults);
    packets[0] = (ql_real *)&vision; psizes[0] = N_REALS(vision);
    packets[1] = (ql_real *)&gnss; psizes[1] = N_REALS(gnss);
    packets[2] = (ql_real *)&range; psizes[2] = N_REALS(range);
    packets[3] = (ql_real *)&datalink; psizes[3] = N_REALS(datalink);
    for (k = 0; k < n; ++k) {
        int status, check;
        fill((ql_real *)&x0, QL_NAV_SIZE, 3);
        for (i = 0; i < QL_NAV_SIZE; ++i) P0[i] = (ql_real)(2 * uniform());
        fill((ql_real *)&deck0, N_REALS(deck0), 0.2);
        t = (ql_real)(1000 * uniform());
        if (ql_estimator_init(&x0, P0, &deck0, t, &mem) != QL_OK) {
            return fail(k, "ql_estimator_init refused valid input", -1);
        }
        /* some periods flown: buffered inputs, queued packets, counters */
        j = (int)(next() % (QL_ESTIMATOR_N_HIST + 1));
        for (i = QL_ESTIMATOR_N_HIST - j; i < QL_ESTIMATOR_N_HIST; ++i) {
            fill(mem.hist[i], 3, 3);
            mem.hist[i][3] = (ql_real)0.004;
        }
        fill(mem.fifo_vision[0], N_REALS(mem.fifo_vision), 3);
        fill(mem.fifo_gnss[0], N_REALS(mem.fifo_gnss), 3);
        fill(mem.fifo_range[0], N_REALS(mem.fifo_range), 3);
        fill(mem.fifo_datalink[0], N_REALS(mem.fifo_datalink), 3);
        mem.count_vision = (ql_real)(next() % (QL_ESTIMATOR_DEPTH_VISION + 1));
        mem.count_gnss = (ql_real)(next() % (QL_ESTIMATOR_DEPTH_GNSS + 1));
        mem.count_range = (ql_real)(next() % (QL_ESTIMATOR_DEPTH_RANGE + 1));
        mem.count_datalink = (ql_real)(next() % (QL_ESTIMATOR_DEPTH_DATALINK + 1));
        if (next() % 20 == 0) mem.count_range = (ql_real)(0.5 + (double)(next() % 30));
        t += (ql_real)(0.004 * (j + 1));
        for (i = 0; i < 4; ++i) {
            fill(packets[i], psizes[i], next() % 2 ? 3 : 1e3);
            packets[i][0] = (ql_real)(next() % 4 != 0);
            packets[i][1] = t - (ql_real)(0.5 * uniform() - 0.05);
        }
        fill((ql_real *)&imu, N_REALS(imu), 3);
        imu.f_b[2] += 9.8f;
        params = defaults;
        dt = (ql_real)0.004;
        targets[0] = (ql_real *)&mem; sizes[0] = N_REALS(mem);
        targets[1] = (ql_real *)&params; sizes[1] = N_REALS(params);
        targets[2] = (ql_real *)&imu; sizes[2] = N_REALS(imu);
        for (i = 0; i < 4; ++i) {
            targets[3 + i] = packets[i]; sizes[3 + i] = psizes[i];
        }
        targets[7] = &dt; sizes[7] = 1;
        targets[8] = &t; sizes[8] = 1;
        for (j = (int)(next() % 4); j > 0; --j) {
            i = (int)(next() % 9);
            targets[i][next() % (unsigned long long)sizes[i]] = extreme();
        }
        check = ql_check_estimator_params(&params, &bad);
        if (!(check == QL_OK ? bad == NULL : check == QL_ERR_PARAM && bad != NULL)) {
            return fail(k, "ql_check_estimator_params: status and bad_field disagree", check);
        }
        memcpy(&before, &mem, sizeof mem);
        status = ql_estimator_step(&imu, &vision, &gnss, &range, &datalink, &params, dt, t,
                                   &mem, &y, &diag);
        if (status < QL_OK || status > QL_ERR_PARAM || status == QL_ERR_TILT) {
            return fail(k, "undocumented status", status);
        }
        ++counts[status];
        if (status != QL_OK) {
            if (memcmp(&before, &mem, sizeof mem) != 0) {
                return fail(k, "memory changed on error", status);
            }
            for (i = 0; i < N_REALS(y); ++i) {
                if (((ql_real *)&y)[i] != 0) return fail(k, "y not zero on error", status);
            }
            for (i = 0; i < N_REALS(diag); ++i) {
                if (((ql_real *)&diag)[i] != 0) return fail(k, "diag not zero on error", status);
            }
            continue;
        }
        if (check != QL_OK || !(dt > 0)) {
            return fail(k, "QL_OK for refused parameters or dt", status);
        }
        if (!all_finite((ql_real *)&mem, N_REALS(mem)) || !counts_valid(&mem)) {
            return fail(k, "memory not finite or a FIFO count out of its range", status);
        }
        if (!all_finite((ql_real *)&diag, N_REALS(diag))
            || !all_finite((ql_real *)&y, N_REALS(y))) {
            return fail(k, "non-finite output", status);
        }
        if (memcmp(y.eta1, imu.eta_hat, sizeof y.eta1) != 0
            || memcmp(y.Omega1, imu.omega, sizeof y.Omega1) != 0) {
            return fail(k, "the IMU's attitude and rates not passed through", status);
        }
    }
    for (i = 0; i <= QL_ERR_PARAM; ++i) {
        printf("%s%ld", i ? " " : "", counts[i]);
    }
    printf("\n");
    return 0;
}
""".replace("/* RANDOM */\n", C_RANDOM.lstrip("\n"))


@pytest.fixture(scope="module")
def sanitized_drivers(tmp_path_factory):
    """The driver with the filter's C, both precisions, compiled in parallel."""
    return build_sanitized(tmp_path_factory, "estimator", files, sources(), DRIVER)


@pytest.mark.slow
@pytest.mark.parametrize("precision", ["double", "float"])
def test_sanitized_random_calls(sanitized_drivers, precision):
    res = _run([str(sanitized_drivers[precision]), str(SANITIZED_CALLS), str(SEED)])
    assert res.returncode == 0, res.stdout + res.stderr
    counts = [int(v) for v in res.stdout.split()]
    assert sum(counts) == SANITIZED_CALLS, counts
    # every status the filter returns but QL_ERR_NULL (the driver passes no NULL)
    assert all(counts[v] > 0 for k, v in STATUS.items()
               if k not in ("QL_ERR_NULL", "QL_ERR_TILT")), counts


if __name__ == "__main__":
    n = int(sys.argv[1]) if len(sys.argv) > 1 else CALLS
    seed = int(sys.argv[2]) if len(sys.argv) > 2 else SEED
    names = {v: k for k, v in STATUS.items()}
    for precision in ("double", "float"):
        counts = _campaign(precision, n, seed)
        print(f"{precision} estimator_step: {n} calls: " + ", ".join(
            f"{names[k]} {counts[k]}" for k in sorted(names) if counts[k])
            + f"; {counts['imu_invalid']} successes with a non-finite IMU sample")
