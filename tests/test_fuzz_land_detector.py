"""Seeded, bounded fuzzing of the land detector's generated C against its contract.

The contract is ``quadland_land_detector.h``'s (docs/codegen.md, "The land detector's
API"): every call of ``ql_land_detector_step`` returns a documented status; NULL
pointers, a non-finite memory, parameter or ``dt``, ``dt <= 0`` or a memory whose stage
flags are not 0 or 1 or whose times are negative, and a parameter outside its
documented range are errors, in that order; on an error the memory is left bit for bit
untouched and the flags are zero; on ``QL_OK`` the new memory is finite and one a step
can leave (flags 0 or 1, times not negative) and every flag is 0 or 1. The cues are
never errors, whatever they hold. In double every call is also compared with the CasADi
function: ``QL_OK`` exactly when its outputs are finite, and then the same bits.
``ql_check_land_detector_params`` rejects exactly the parameters outside their
documented ranges (tests/test_land_detector_flight_code.py's table) and names the
first.

Each call starts from a random memory (stages set or not, times, the last range, the
running mean), random cues and parameters (a valid retune, sometimes), then
overwrites a few entries with extreme (huge, tiny, subnormal, negative zero),
non-finite or raw-bit values. Two campaigns per precision, as
tests/test_fuzz_estimator_step.py: through ``ctypes`` (:data:`CALLS` calls, the oracle
above) and, where the compiler has AddressSanitizer and UndefinedBehaviorSanitizer, a C
driver built with them (:data:`SANITIZED_CALLS` calls), which also calls
``ql_land_detector_form_cues``.
"""

from __future__ import annotations

import collections
import math

import numpy as np
import pytest
from land_detector_c import Call, files, load, sources
from reference import C_RANDOM, extreme, have_compiler
from reference import run as _run
from reference import sanitized_drivers as build_sanitized
from test_land_detector_flight_code import first_bad

from quadland_symbolic.codegen import STATUS_CODES
from quadland_symbolic.landing.land_detector import (
    LAND_DETECTOR_CUES,
    LAND_DETECTOR_PARAMS,
    LAND_DETECTOR_STATE,
    land_detector_function,
)

pytestmark = pytest.mark.skipif(not have_compiler(), reason="no C compiler")

SEED = 1729
#: ctypes calls per precision.
CALLS = 3000
#: Calls of the sanitized C driver per precision.
SANITIZED_CALLS = 20000
STATUS = {name: value for name, value, _ in STATUS_CODES}
DT = 0.004
STAGES = [LAND_DETECTOR_STATE.index(n) for n in ("ground_contact", "maybe_landed", "landed")]
TIMES = [LAND_DETECTOR_STATE.index(n) for n in ("t_contact", "t_maybe", "t_landed",
                                                "range_hold", "spike_hold", "age")]
FACTORS = [LAND_DETECTOR_PARAMS.index(n) for n in ("hold_factor", "no_range_factor")]
FLAG_CUES = [LAND_DETECTOR_CUES.index(n) for n in ("range_valid", "in_descend")]


def _state_valid(s) -> bool:
    s = np.asarray(s, dtype=float)
    return bool(np.all((s[STAGES] == 0) | (s[STAGES] == 1)) and np.all(s[TIMES] >= 0))


class _Harness:
    """One build's detector API and a random operating point per call."""

    def __init__(self, precision: str):
        self.c = Call(load(precision))
        self.dtype = self.c.api.dtype
        self.p0 = self.c.v["params"].copy()

    def draw(self, rng):
        """Fill the arguments; return dt and the pointer arguments to pass as NULL."""
        v = self.c.v
        s = v["state"]
        s[:] = rng.uniform(0, 2, s.size) * rng.choice((0.1, 1.0, 10.0))
        s[STAGES] = rng.integers(0, 2, 3)
        s[LAND_DETECTOR_STATE.index("range_gap")] = rng.normal() * 0.5
        s[LAND_DETECTOR_STATE.index("f_z_mean")] = 9.8 + rng.normal() * 5
        if rng.uniform() < 0.2:
            s[:] = 0.0                                     # the start
        v["params"][:] = self.p0
        if rng.uniform() < 0.3:                            # a valid retune
            v["params"][:] *= 10 ** rng.uniform(-1, 1, size=v["params"].size)
            v["params"][FACTORS] = np.maximum(v["params"][FACTORS], 1.0)   # they widen
        c = v["cues"]
        c[:] = rng.normal(size=c.size) * [0.2, 1, 0.2, 0.5, 0.5, 5, 1]
        c[FLAG_CUES] = rng.integers(0, 2, 2)
        c[5] += 9.8
        dt = DT if rng.uniform() < 0.9 else 10 ** rng.uniform(-6, 1)
        if rng.uniform() < 0.05:                           # a corrupted memory
            s[rng.choice(STAGES + TIMES)] = rng.choice((0.5, -1e-9, 2.0))
        if rng.uniform() < 0.3:
            return float(self.dtype(dt)), ()
        targets = (s, v["params"], c, "dt")
        for _ in range(rng.integers(1, 4)):
            target = targets[rng.integers(len(targets))]
            value = extreme(rng, self.dtype)
            if isinstance(target, str):
                dt = value
            else:
                target[rng.integers(target.size)] = value
        null = () if rng.uniform() > 0.02 else (Call.ARGS[rng.integers(len(Call.ARGS))],)
        return float(self.dtype(dt)), null


def _check(h, rng, counts, oracle):
    dt, null = h.draw(rng)
    c, v = h.c, h.c.v
    bad = first_bad(v["params"])
    assert c.check() == ((STATUS["QL_ERR_PARAM"], bad) if bad else (STATUS["QL_OK"], None))
    state, cues, params = (v[n].astype(float) for n in ("state", "cues", "params"))
    before = bytes(c.s["state"])
    v["flags"][:] = 7.0
    status = c.step(dt, null)
    counts[status] += 1
    assert status in STATUS.values()
    if null:
        assert status == STATUS["QL_ERR_NULL"]
    elif not (np.all(np.isfinite(state)) and np.all(np.isfinite(params)) and math.isfinite(dt)):
        assert status == STATUS["QL_ERR_NONFINITE_INPUT"]
    elif not (dt > 0 and _state_valid(state)):
        assert status == STATUS["QL_ERR_INVALID"]
    elif bad:
        assert status == STATUS["QL_ERR_PARAM"]
    else:
        assert status in (STATUS["QL_OK"], STATUS["QL_ERR_NONFINITE_OUTPUT"])
        if oracle is not None:
            want = [np.asarray(o, dtype=float).ravel() for o in oracle(state, cues, params, dt)]
            finite = all(np.all(np.isfinite(w)) for w in want)
            assert status == (STATUS["QL_OK"] if finite else STATUS["QL_ERR_NONFINITE_OUTPUT"])
            if finite:
                for got, w in zip((v["state"], v["flags"]), want, strict=True):
                    np.testing.assert_array_equal(got.view(np.uint64), w.view(np.uint64))
    if status != STATUS["QL_OK"]:
        assert bytes(c.s["state"]) == before, "the memory is untouched on error"
        if "flags" not in null:
            assert not np.any(v["flags"]), "the flags are zero on error"
        return
    assert np.all(np.isfinite(v["state"])) and _state_valid(v["state"])
    assert np.all((v["flags"] == 0) | (v["flags"] == 1))
    counts["nonfinite_cue"] += not np.all(np.isfinite(cues))


def _campaign(precision, calls, seed=SEED):
    h = _Harness(precision)
    rng = np.random.default_rng([seed, precision == "float"])
    oracle = land_detector_function() if precision == "double" else None
    counts = collections.Counter()
    for _ in range(calls):
        _check(h, rng, counts, oracle)
    return counts


@pytest.mark.slow
@pytest.mark.parametrize("precision", ["double", "float"])
def test_random_calls_keep_the_contract(precision):
    counts = _campaign(precision, CALLS)
    for name in ("QL_OK", "QL_ERR_NULL", "QL_ERR_NONFINITE_INPUT", "QL_ERR_INVALID",
                 "QL_ERR_PARAM"):
        assert counts[STATUS[name]] >= 5, (name, counts)
    assert counts[STATUS["QL_OK"]] >= CALLS // 4
    # finite inputs never overflow: every value the step stores is a clamp, a choice or a
    # bounded mix of finite ones (docs/codegen.md)
    assert counts[STATUS["QL_ERR_NONFINITE_OUTPUT"]] == counts[STATUS["QL_ERR_TILT"]] == 0
    assert counts["nonfinite_cue"] >= 5


# --- the sanitized build -----------------------------------------------------

#: A C driver of seeded random calls that checks the contract's C-visible part and
#: counts the outcomes; each call also forms cues from random signals first.
DRIVER = r"""
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "quadland_land_detector.h"

#define N_REALS(s) ((int)(sizeof(s) / sizeof(ql_real)))

/* RANDOM */

static int fail(long k, const char *what, int status)
{
    printf("call %ld: %s (status %d)\n", k, what, status);
    return 1;
}

static void fill(ql_real *v, int n, double scale)
{
    int i;
    for (i = 0; i < n; ++i) v[i] = (ql_real)(scale * (2 * uniform() - 1));
}

static int state_valid(const ql_land_detector_state *s)
{
    const ql_real flags[3] = {s->ground_contact, s->maybe_landed, s->landed};
    const ql_real times[6] = {s->t_contact, s->t_maybe, s->t_landed, s->range_hold,
                              s->spike_hold, s->age};
    int i;
    for (i = 0; i < 3; ++i) {
        if (!(flags[i] == 0 || flags[i] == 1)) return 0;
    }
    for (i = 0; i < 6; ++i) {
        if (!(times[i] >= 0)) return 0;
    }
    return 1;
}

int main(int argc, char **argv)
{
    ql_land_detector_params defaults, params;
    ql_land_detector_state state, before;
    ql_land_detector_cues cues;
    ql_land_detector_flags flags;
    ql_landing_measurement y;
    ql_range_packet range;
    ql_imu imu;
    ql_guidance_params guidance;
    ql_guidance_state gs;
    ql_quadrotor_params quad;
    ql_real F_cmd[4], dt, *targets[9];
    int sizes[9], i, j;
    long k, n = argc > 1 ? atol(argv[1]) : 1000, counts[8] = {0};
    const char *bad;

    seed = argc > 2 ? strtoull(argv[2], NULL, 10) : 1;
    if (seed == 0) {
        seed = 1;   /* xorshift stays at 0 */
    }
    ql_land_detector_params_init(&defaults);
    for (k = 0; k < n; ++k) {
        int status, check;
        /* the cues, from random signals: any status but NULL is a pass here */
        fill((ql_real *)&y, N_REALS(y), 3);
        fill((ql_real *)&range, N_REALS(range), 3);
        range.fresh = (ql_real)(next() % 2);
        fill((ql_real *)&imu, N_REALS(imu), 3);
        fill(F_cmd, 4, 10);
        fill((ql_real *)&guidance, N_REALS(guidance), 2);
        gs.phase = (int)(next() % 5);
        gs.aborts = (int)(next() % 3);
        gs.timer = gs.z_ref = 1;
        fill((ql_real *)&quad, N_REALS(quad), 2);
        targets[0] = (ql_real *)&y; sizes[0] = N_REALS(y);
        targets[1] = (ql_real *)&range; sizes[1] = N_REALS(range);
        targets[2] = (ql_real *)&imu; sizes[2] = N_REALS(imu);
        targets[3] = F_cmd; sizes[3] = 4;
        targets[4] = (ql_real *)&guidance; sizes[4] = N_REALS(guidance);
        targets[5] = (ql_real *)&quad; sizes[5] = N_REALS(quad);
        for (j = (int)(next() % 3); j > 0; --j) {
            i = (int)(next() % 6);
            targets[i][next() % (unsigned long long)sizes[i]] = extreme();
        }
        status = ql_land_detector_form_cues(&y, &range, &imu, F_cmd, &gs, &guidance, &quad,
                                            &cues);
        if (status != QL_OK && status != QL_ERR_NONFINITE_INPUT) {
            return fail(k, "ql_land_detector_form_cues: undocumented status", status);
        }
        /* the step, from a random memory */
        fill((ql_real *)&state, N_REALS(state), 2);
        state.t_contact = (ql_real)uniform();
        state.t_maybe = (ql_real)uniform();
        state.t_landed = (ql_real)uniform();
        state.range_hold = (ql_real)uniform();
        state.spike_hold = (ql_real)uniform();
        state.age = (ql_real)(10 * uniform());
        state.ground_contact = (ql_real)(next() % 2);
        state.maybe_landed = (ql_real)(next() % 2);
        state.landed = (ql_real)(next() % 2);
        if (next() % 20 == 0) state.maybe_landed = (ql_real)0.5;
        params = defaults;
        dt = (ql_real)0.004;
        targets[6] = (ql_real *)&state; sizes[6] = N_REALS(state);
        targets[7] = (ql_real *)&params; sizes[7] = N_REALS(params);
        targets[8] = &dt; sizes[8] = 1;
        for (j = (int)(next() % 4); j > 0; --j) {
            i = 6 + (int)(next() % 3);
            targets[i][next() % (unsigned long long)sizes[i]] = extreme();
        }
        if (next() % 4 == 0) fill((ql_real *)&cues, N_REALS(cues), 1e3);
        check = ql_check_land_detector_params(&params, &bad);
        if (!(check == QL_OK ? bad == NULL : check == QL_ERR_PARAM && bad != NULL)) {
            return fail(k, "ql_check_land_detector_params: status and bad_field disagree", check);
        }
        memcpy(&before, &state, sizeof state);
        status = ql_land_detector_step(&cues, &params, dt, &state, &flags);
        if (status < QL_OK || status > QL_ERR_PARAM || status == QL_ERR_TILT) {
            return fail(k, "undocumented status", status);
        }
        ++counts[status];
        if (status != QL_OK) {
            if (memcmp(&before, &state, sizeof state) != 0) {
                return fail(k, "memory changed on error", status);
            }
            for (i = 0; i < N_REALS(flags); ++i) {
                if (((ql_real *)&flags)[i] != 0) return fail(k, "flags not zero on error", status);
            }
            continue;
        }
        if (check != QL_OK || !(dt > 0)) {
            return fail(k, "QL_OK for refused parameters or dt", status);
        }
        for (i = 0; i < N_REALS(state); ++i) {
            if (!isfinite(((ql_real *)&state)[i])) return fail(k, "memory not finite", status);
        }
        if (!state_valid(&state)) {
            return fail(k, "a memory no step can leave", status);
        }
        for (i = 0; i < N_REALS(flags); ++i) {
            ql_real f = ((ql_real *)&flags)[i];
            if (!(f == 0 || f == 1)) return fail(k, "a flag neither 0 nor 1", status);
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
    """The driver with the detector's C, both precisions, compiled in parallel."""
    return build_sanitized(tmp_path_factory, "detector", files, sources(), DRIVER)


@pytest.mark.slow
@pytest.mark.parametrize("precision", ["double", "float"])
def test_sanitized_random_calls(sanitized_drivers, precision):
    res = _run([str(sanitized_drivers[precision]), str(SANITIZED_CALLS), str(SEED)])
    assert res.returncode == 0, res.stdout + res.stderr
    counts = [int(v) for v in res.stdout.split()]
    assert sum(counts) == SANITIZED_CALLS, counts
    # every status the step returns on the driver's input (it passes no NULL, and finite
    # inputs never overflow)
    assert all(counts[STATUS[k]] > 0 for k in ("QL_OK", "QL_ERR_NONFINITE_INPUT",
                                               "QL_ERR_INVALID", "QL_ERR_PARAM")), counts
