"""Seeded, bounded fuzzing of the generated C control step against its contract.

The contract is docs/codegen.md's (status codes, ``ql_check_params``) and
docs/reliability.md's "The generated C step": every call returns a
documented status; on ``QL_OK`` every output and the new state are finite,
the rotor forces lie in ``[rotor_force_min, rotor_force_max]``, ``n_clipped``
counts the forces of ``u`` beyond them and the command is the law
extrapolated by the hold compensation; on an error the adaptive state is
left bit for bit untouched and the outputs are zero; ``ql_check_params``
rejects exactly the parameters outside their documented ranges and names
the first. Each call starts from a random operating point near the paper's
and overwrites a few inputs, parameters or state entries with random,
extreme (huge, tiny, subnormal, negative zero), non-finite or raw-bit values.

Two campaigns per precision: through ``ctypes`` (:data:`CALLS` calls, the
Python oracle below) and, where the compiler has AddressSanitizer and
UndefinedBehaviorSanitizer, a C driver built with them around the step
(:data:`SANITIZED_CALLS` calls). ``python tests/test_fuzz_c_step.py N [SEED]``
runs a longer ctypes campaign and prints the outcomes.
"""

from __future__ import annotations

import collections
import ctypes
import functools
import math
import subprocess
import sys
from fractions import Fraction as Q

import numpy as np
import pytest
from reference import C_RANDOM, SANITIZE, extreme, have_compiler, sanitizer_missing
from reference import run as _run

import quadland
from quadland.engine import build
from quadland.kinds.paper.flight import flight_files, load_api
from quadland.kinds.paper.values import model_values
from quadland_symbolic.codegen import STATUS_CODES, c_sources
from quadland_symbolic.codegen.structs import adaptive_state_layout, output_layout, param_ranges

pytestmark = pytest.mark.skipif(not have_compiler(), reason="no C compiler")

L = 100
SEED = 173
#: ctypes calls per precision (about 2 s each).
CALLS = 4000
#: Calls of the sanitized C driver per precision.
SANITIZED_CALLS = 20000
STATUS = {name: value for name, value, _ in STATUS_CODES}


def _positive(v, p):
    return v > 0


def _nonnegative(v, p):
    return v >= 0


#: The documented range of every member of ql_params (docs/codegen.md),
#: written out here, not read from quadland_symbolic.codegen.structs: a predicate of the
#: member's values ``v`` and the parameter vector's members ``p``. NaN
#: and infinities are outside every range.
DOCUMENTED = {
    "quad.m1": _positive,
    "quad.I": _positive,
    "quad.Kt": _nonnegative,
    "quad.Kr": _nonnegative,
    "quad.g": _positive,
    "quad.arm": _positive,
    "quad.c": _positive,
    "ctrl.k1": _positive,
    "ctrl.k2": _positive,
    "ctrl.gamma1": _positive,
    "ctrl.gamma2": _positive,
    "ctrl.k_w": _positive,
    "ctrl.k_zeta": _positive,
    "ctrl.rho": _positive,
    "ctrl.nominal_model": lambda v, p: (v == 0) | (v == 1),
    "ctrl.centers": lambda v, p: np.ones_like(v, dtype=bool),
    "ctrl.widths": _positive,
    "rotor_force_min": lambda v, p: np.ones_like(v, dtype=bool),
    "rotor_force_max": lambda v, p: v >= p["rotor_force_min"],
    "tilt_min": lambda v, p: (v >= 0) & (v < 1),
    "hold_compensation": lambda v, p: (v >= 0) & (v <= 1),
}
#: Members that only ql_check_params tests (the step would test l values a call).
CHECK_PARAMS_ONLY = {"ctrl.widths"}


@functools.cache
def _members() -> tuple:
    """(path, start, stop) of every real member of ql_params, in layout order."""
    return tuple((r.name, r.offset, r.offset + r.size) for r in param_ranges(L))


def test_every_member_has_a_documented_range():
    assert [name for name, _, _ in _members()] == list(DOCUMENTED)
    assert output_layout(L).size == 17 and adaptive_state_layout(L).size == 4 * L + 8


def _bad_members(p):
    """Names of the members of the parameter vector ``p`` outside their range, in order."""
    values = {name: p[a:b].astype(float) for name, a, b in _members()}
    bad = []
    with np.errstate(invalid="ignore"):
        for name, v in values.items():
            if not (np.all(np.isfinite(v)) and np.all(DOCUMENTED[name](v, values))):
                bad.append(name)
    return bad


def _view(struct, dtype, count):
    """The first ``count`` values of a ctypes struct, as a writable NumPy array."""
    return np.frombuffer((ctypes.c_char * ctypes.sizeof(struct)).from_buffer(struct),
                         dtype=dtype, count=count)


class _Harness:
    """One build's API, its structs and NumPy views on them."""

    def __init__(self, precision: str):
        self.api = api = load_api(L, precision, "-O2", model=False)
        self.dtype = np.float64 if precision == "double" else np.float32
        self.fi = np.finfo(self.dtype)
        self.xq, self.yv, self.ref = api.QuadrotorState(), api.VehicleState(), api.Reference()
        self.params, self.state, self.out = api.Params(), api.AdaptiveState(), api.Output()
        self.v_xq = _view(self.xq, self.dtype, 10)
        self.v_yv = _view(self.yv, self.dtype, 3)
        self.v_ref = _view(self.ref, self.dtype, 12)
        self.v_p = _view(self.params, self.dtype, ctypes.sizeof(self.params)
                         // np.dtype(self.dtype).itemsize)
        n_state = adaptive_state_layout(L).size
        self.v_state = _view(self.state, self.dtype, n_state)
        self.v_out = _view(self.out, self.dtype, output_layout(L).size)
        o = output_layout(L).offsets()
        self.o_u, self.o_law, self.o_wrench, self.o_rotor, self.o_tilt = (
            slice(*o[n]) for n in ("u", "u_law", "wrench", "rotor", "tilt"))
        s = adaptive_state_layout(L).offsets()
        self.s_W, self.s_zeta, self.s_prev = (slice(*s[n]) for n in ("W_hat", "zeta_hat",
                                                                     "u_prev"))
        api.lib.ql_params_init(ctypes.byref(self.params))
        api.lib.ql_reference_init(ctypes.byref(self.ref))
        self.p0 = self.v_p.copy()
        self.ref0 = self.v_ref.copy()
        mv = model_values(quadland.load_scenario("paper"))
        self.xq0 = mv.x0[0:10].copy()
        self.yv0 = np.array([mv.p_veh[-1], mv.x0[12], mv.x0[15]])

    def extreme(self, rng) -> float:
        """A value of this precision from one of the hard classes."""
        return extreme(rng, self.dtype)

    def draw(self, rng):
        """A random call: operating point, tuning and state, then a few hard values.

        Returns dt and the pointer arguments to pass as NULL (usually none).
        """
        p = self.v_p
        p[:] = self.p0
        if rng.uniform() < 0.3:     # a valid retune
            for name, a, b in _members():
                if DOCUMENTED[name] is _positive:
                    p[a:b] *= 10 ** rng.uniform(-1, 1, size=b - a)
            p[_offset("ctrl.nominal_model")] = rng.integers(2)
        if rng.uniform() < 0.5:     # limits that clip
            lo = -rng.uniform(0, 60)
            p[_offset("rotor_force_min")] = lo
            p[_offset("rotor_force_max")] = lo + rng.uniform(0, 120)
        p[_offset("hold_compensation")] = rng.choice((0.0, 0.5, 1.0, rng.uniform()))
        p[_offset("tilt_min")] = rng.choice((0.0, 1e-3, rng.uniform(0, 0.9)))
        scale = rng.choice((0.05, 0.5, 2.0))
        self.v_xq[:] = self.xq0 + scale * rng.normal(size=10)
        self.v_yv[:] = self.yv0 + scale * rng.normal(size=3)
        self.v_ref[:] = self.ref0 + 0.1 * scale * rng.normal(size=12)
        st = self.v_state
        st[self.s_W] = rng.choice((0.0, 0.1, 1.0, 30.0)) * rng.normal(size=4 * L)
        st[self.s_zeta] = rng.normal(size=4)
        st[self.s_prev] = 20 * rng.normal(size=4)
        self.state.has_prev = int(rng.integers(2))
        dt = rng.choice((0.002, 10 ** rng.uniform(-6, 1)))
        if rng.uniform() < 0.3:
            return float(self.dtype(dt)), ()
        targets = (self.v_xq, self.v_yv, self.v_ref, "dt", p, p, st)
        scalars = np.r_[0:_offset("ctrl.centers"), _offset("rotor_force_min"):p.size]
        for _ in range(rng.integers(1, 4)):
            t = targets[rng.integers(len(targets))]
            value = self.extreme(rng)
            if isinstance(t, str):
                dt = value
            elif t is p and rng.uniform() < 0.6:    # mostly the scalar members
                p[scalars[rng.integers(scalars.size)]] = value
            else:
                t[rng.integers(t.size)] = value
        null = () if rng.uniform() > 0.02 else (int(rng.choice((0, 1, 2, 3, 5, 6))),)
        return float(self.dtype(dt)), null

    def call(self, dt, null=()):
        args = [ctypes.byref(self.xq), ctypes.byref(self.yv), ctypes.byref(self.ref),
                ctypes.byref(self.params), dt, ctypes.byref(self.state),
                ctypes.byref(self.out)]
        for i in null:
            args[i] = None
        return self.api.lib.ql_control_step(*args)

    def check_params(self):
        bad = ctypes.c_char_p()
        status = self.api.lib.ql_check_params(ctypes.byref(self.params), ctypes.byref(bad))
        return status, None if bad.value is None else bad.value.decode()


@functools.cache
def _offset(name):
    return next(a for n, a, _ in _members() if n == name)


def _mixed(u, tilt, p):
    """The forces F1..F4 of the virtual input u before clipping, exactly.

    docs/codegen.md: ``F_total = m1 u1 / tilt``, ``M = I u2..4`` and the
    closed-form inverse of the mixer, in rational arithmetic from the
    step's own ``u`` and ``tilt``. Returns the forces, each one's sum of
    the magnitudes of its terms (the scale of the step's rounding), and
    the largest magnitude of any intermediate value.
    """
    m1, d, c = (Q(float(p[_offset(n)])) for n in ("quad.m1", "quad.arm", "quad.c"))
    I = [Q(float(v)) for v in p[_offset("quad.I"):_offset("quad.I") + 3]]
    u = [Q(float(v)) for v in u]
    T = m1 * u[0] / Q(float(tilt))
    Mx, My, Mz = (I[k] * u[k + 1] for k in range(3))
    terms = [[T / 4, -My / (2 * d), Mz / (4 * c)],
             [T / 4, Mx / (2 * d), -Mz / (4 * c)],
             [T / 4, My / (2 * d), Mz / (4 * c)],
             [T / 4, -Mx / (2 * d), -Mz / (4 * c)]]
    forces = [sum(row) for row in terms]
    sizes = [sum(abs(t) for t in row) for row in terms]
    largest = max([abs(m1 * u[0]), abs(T), abs(Mx), abs(My), abs(Mz), *sizes])
    return forces, sizes, largest


def _check_call(h, rng, counts):
    """One random call against the contract; counts its outcome."""
    dt, null = h.draw(rng)
    p = h.v_p.astype(float)
    bad = _bad_members(h.v_p)
    assert h.check_params() == ((STATUS["QL_ERR_PARAM"], bad[0]) if bad else (STATUS["QL_OK"],
                                                                             None))
    st = h.v_state.astype(float)
    has_prev = h.state.has_prev
    before = bytes(h.state)
    inputs = np.r_[h.v_xq, h.v_yv, h.v_ref, dt].astype(float)
    status = h.call(dt, null)
    counts[status] += 1
    assert status in STATUS.values()
    out = h.v_out.astype(float)
    if null:
        assert status == STATUS["QL_ERR_NULL"]
    elif not (np.all(np.isfinite(inputs)) and np.all(np.isfinite(p))):
        assert status == STATUS["QL_ERR_NONFINITE_INPUT"]
    elif not dt > 0:
        assert status == STATUS["QL_ERR_INVALID"]
    elif set(bad) - CHECK_PARAMS_ONLY:
        assert status == STATUS["QL_ERR_PARAM"]
    else:
        read = np.r_[st[h.s_W], st[h.s_zeta], st[h.s_prev] if has_prev else []]
        tilt = math.cos(float(h.v_xq[2])) * math.cos(float(h.v_xq[1]))
        eps = 8 * float(h.fi.eps)
        assert out[h.o_tilt][0] == pytest.approx(tilt, rel=eps, abs=eps)
        if abs(out[h.o_tilt][0]) < p[_offset("tilt_min")]:
            assert status == STATUS["QL_ERR_TILT"]
        elif not np.all(np.isfinite(read)):
            assert status == STATUS["QL_ERR_NONFINITE_INPUT"]
        else:
            assert status in (STATUS["QL_OK"], STATUS["QL_ERR_NONFINITE_OUTPUT"])
    if status != STATUS["QL_OK"]:
        if 6 not in null:
            assert not np.any(out[:h.o_tilt.start]), "outputs are zero on error"
            assert h.out.n_clipped == 0 and np.isfinite(out[h.o_tilt][0])
        assert bytes(h.state) == before, "the state is untouched on error"
        return
    _check_success(h, p, st, has_prev, out, counts)


def _check_success(h, p, st, has_prev, out, counts):
    new = h.v_state.astype(float)
    assert np.all(np.isfinite(out)) and np.all(np.isfinite(new))
    assert h.state.has_prev == 1
    assert np.array_equal(new[h.s_prev], out[h.o_law])
    u, law, rotor = out[h.o_u], out[h.o_law], out[h.o_rotor]
    eps = float(h.fi.eps)
    # u_prev is read only when has_prev is set (it may be anything otherwise).
    hold, prev = (p[_offset("hold_compensation")], st[h.s_prev]) if has_prev else (0.0, law)
    want = law + hold * (law - prev)
    assert np.all(np.abs(u - want) <= 32 * eps * ((1 + hold) * np.abs(law) + hold * np.abs(prev)))
    lo, hi = p[_offset("rotor_force_min")], p[_offset("rotor_force_max")]
    assert np.all((lo <= rotor) & (rotor <= hi))
    n = h.out.n_clipped
    assert 0 <= n <= 4
    tilt = out[h.o_tilt][0]
    assert tilt != 0, "QL_OK although the thrust map divided by zero"
    forces, sizes, largest = _mixed(u, tilt, p)
    # Each value the step computed is representable (a few roundings aside):
    # a NaN or an infinite force must not be clipped into a finite command.
    representable = largest <= Q(float(h.fi.max)) * (1 + Q(1, 10 ** 6))
    assert representable, "QL_OK although a rotor force overflowed"
    if max(p[_offset("quad.arm")], p[_offset("quad.c")]) > float(h.fi.max) / 8:
        return      # 2 d or 4 c overflowed into the exact limit 0 of a term: not checked
    lo, hi = Q(float(lo)), Q(float(hi))
    sure = unsure = 0
    for F, size, r in zip(forces, sizes, rotor, strict=True):
        tol = 64 * Q(eps) * size + 16 * Q(float(h.fi.smallest_subnormal))
        if F < lo - tol or F > hi + tol:
            sure += 1
            assert Q(float(r)) == (lo if F < lo else hi)
        elif lo + tol <= F <= hi - tol:
            assert abs(Q(float(r)) - F) <= tol
        else:
            unsure += 1
    assert sure <= n <= sure + unsure
    counts["clipped"] += n > 0


def _campaign(precision, calls, seed=SEED):
    h = _Harness(precision)
    rng = np.random.default_rng([seed, precision == "float"])
    counts = collections.Counter()
    for _ in range(calls):
        _check_call(h, rng, counts)
    return counts


@pytest.mark.slow
@pytest.mark.parametrize("precision", ["double", "float"])
def test_random_calls_keep_the_contract(precision):
    counts = _campaign(precision, CALLS)
    # Every outcome is reached, successes with and without clipping among them.
    for name in STATUS:
        assert counts[STATUS[name]] >= 10, (name, counts)
    assert counts[STATUS["QL_OK"]] >= CALLS // 10
    assert 0 < counts["clipped"] < counts[STATUS["QL_OK"]]


# --- the sanitized build -----------------------------------------------------

#: A C driver of seeded random calls that checks the contract's C-visible
#: part (statuses, untouched state and zero outputs on error, finite
#: outputs within the limits on success) and counts the outcomes.
DRIVER = r"""
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "quadland.h"

#define N_REALS(s) ((int)(sizeof(s) / sizeof(ql_real)))
#define N_STATE (4 * QL_RBF_NODES + 8)

/* RANDOM */
static int fail(long k, const char *what, int status)
{
    printf("call %ld: %s (status %d)\n", k, what, status);
    return 1;
}

int main(int argc, char **argv)
{
    static ql_params defaults, params;
    static ql_adaptive_state state, before;
    ql_quadrotor_state xq;
    ql_vehicle_state yv;
    ql_reference ref;
    ql_output out;
    ql_real dt, *targets[6];
    int sizes[6], i, j;
    long k, n = argc > 1 ? atol(argv[1]) : 1000, counts[8] = {0};
    const char *bad;

    seed = argc > 2 ? strtoull(argv[2], NULL, 10) : 1;
    if (seed == 0) {
        seed = 1;   /* xorshift stays at 0 */
    }
    ql_params_init(&defaults);
    /* Each struct is its reals (quadland.c checks the layouts). */
    targets[0] = (ql_real *)&xq; sizes[0] = N_REALS(xq);
    targets[1] = (ql_real *)&yv; sizes[1] = N_REALS(yv);
    targets[2] = (ql_real *)&ref; sizes[2] = N_REALS(ref);
    targets[3] = (ql_real *)&params; sizes[3] = QL_PARAMS_SIZE;
    targets[4] = (ql_real *)&state; sizes[4] = N_STATE;
    targets[5] = &dt; sizes[5] = 1;
    for (k = 0; k < n; ++k) {
        int status, check;
        params = defaults;
        if (uniform() < 0.5) {
            params.rotor_force_min = (ql_real)(-60 * uniform());
            params.rotor_force_max = params.rotor_force_min + (ql_real)(120 * uniform());
        }
        params.hold_compensation = (ql_real)uniform();
        params.tilt_min = (ql_real)(0.5 * uniform());
        ql_reference_init(&ref);
        xq.z1 = (ql_real)(1 + uniform());
        for (i = 0; i < 3; ++i) {
            xq.eta1[i] = (ql_real)(uniform() - 0.5);
            xq.V1[i] = (ql_real)(4 * uniform() - 2);
            xq.Omega1[i] = (ql_real)(4 * uniform() - 2);
        }
        yv.z2 = 0;
        yv.psi2 = (ql_real)uniform();
        yv.r2 = (ql_real)(uniform() - 0.5);
        for (i = 0; i < N_STATE; ++i) {
            targets[4][i] = (ql_real)(10 * (uniform() - 0.5));
        }
        state.has_prev = (int)(next() & 1);
        dt = (ql_real)0.002;
        for (j = (int)(next() % 4); j > 0; --j) {
            i = (int)(next() % 6);
            targets[i][next() % (unsigned long long)sizes[i]] = extreme();
        }
        check = ql_check_params(&params, &bad);
        if (!(check == QL_OK ? bad == NULL : check == QL_ERR_PARAM && bad != NULL)) {
            return fail(k, "ql_check_params: status and bad_field disagree", check);
        }
        memcpy(&before, &state, sizeof state);
        status = ql_control_step(&xq, &yv, &ref, &params, dt, &state, &out);
        if (status < QL_OK || status > QL_ERR_PARAM) {
            return fail(k, "undocumented status", status);
        }
        ++counts[status];
        if (status != QL_OK) {
            if (memcmp(&before, &state, sizeof state) != 0) {
                return fail(k, "state changed on error", status);
            }
            for (i = 0; i < 4; ++i) {
                if (out.u[i] != 0 || out.u_law[i] != 0 || out.wrench[i] != 0
                    || out.rotor[i] != 0) {
                    return fail(k, "output not zero on error", status);
                }
            }
            if (out.n_clipped != 0 || !isfinite(out.tilt)) {
                return fail(k, "n_clipped or tilt on error", status);
            }
            continue;
        }
        if (check != QL_OK && strcmp(bad, "ctrl.widths") != 0) {
            return fail(k, "QL_OK for parameters ql_check_params rejects", status);
        }
        for (i = 0; i < 4; ++i) {
            if (!(isfinite(out.u[i]) && isfinite(out.u_law[i]) && isfinite(out.wrench[i])
                  && out.rotor[i] >= params.rotor_force_min
                  && out.rotor[i] <= params.rotor_force_max)) {
                return fail(k, "non-finite output or rotor force beyond the limits", status);
            }
        }
        for (i = 0; i < N_STATE; ++i) {
            if (!isfinite(targets[4][i])) {
                return fail(k, "non-finite state", status);
            }
        }
        if (out.n_clipped < 0 || out.n_clipped > 4 || state.has_prev != 1) {
            return fail(k, "n_clipped or has_prev", status);
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
def sanitizer(tmp_path_factory):
    """The compiler, if it builds and runs an address- and UB-sanitized program."""
    cc = build.find_compiler()
    why = sanitizer_missing(cc, tmp_path_factory.mktemp("sanitizer_probe"))
    if why:
        pytest.skip(why)
    return cc


@pytest.fixture(scope="module")
def sanitized_drivers(sanitizer, tmp_path_factory):
    """The driver with the step, both precisions, compiled in parallel."""
    procs, exes = [], {}
    for precision in ("double", "float"):
        root = tmp_path_factory.mktemp(f"sanitized_{precision}")
        for name, text in flight_files(L, precision).items():
            (root / name).write_text(text)
        (root / "driver.c").write_text(DRIVER)
        for src in (*c_sources(), "driver.c"):
            procs.append(subprocess.Popen(
                [sanitizer, *build.STRICT_CFLAGS, "-O1", *SANITIZE, "-c", src],
                cwd=root, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True))
        exes[precision] = root
    for p in procs:
        out, _ = p.communicate(timeout=300)
        assert p.returncode == 0, out
    for precision, root in exes.items():
        objs = [f"{src[:-2]}.o" for src in (*c_sources(), "driver.c")]
        res = _run([sanitizer, *SANITIZE, *objs, "-lm", "-o", "driver"], cwd=root)
        assert res.returncode == 0, res.stderr
        exes[precision] = root / "driver"
    return exes


@pytest.mark.slow
@pytest.mark.parametrize("precision", ["double", "float"])
def test_sanitized_random_calls(sanitized_drivers, precision):
    res = _run([str(sanitized_drivers[precision]), str(SANITIZED_CALLS), str(SEED)])
    assert res.returncode == 0, res.stdout + res.stderr
    counts = [int(v) for v in res.stdout.split()]
    assert sum(counts) == SANITIZED_CALLS, counts
    # Every status but QL_ERR_NULL (the driver passes no NULL) is reached.
    assert all(counts[v] > 0 for k, v in STATUS.items() if k != "QL_ERR_NULL"), counts


if __name__ == "__main__":
    n = int(sys.argv[1]) if len(sys.argv) > 1 else CALLS
    seed = int(sys.argv[2]) if len(sys.argv) > 2 else SEED
    names = {v: k for k, v in STATUS.items()}
    for precision in ("double", "float"):
        counts = _campaign(precision, n, seed)
        print(f"{precision}: {n} calls: " + ", ".join(
            f"{names[k]} {counts[k]}" for k in sorted(names) if counts[k])
            + f"; {counts['clipped']} successes clipped")
