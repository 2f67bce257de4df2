"""Branch-free Kalman pieces: the Joseph update against its product form in NumPy."""

import casadi as ca
import numpy as np
from nav_reference import (
    N,
    random_spd,
)

from quadland_symbolic.kalman import CovariancePattern, joseph_update, scalar_update

# ---------------------------------------------------------------- Joseph form

def _joseph_function():
    P, k, h, r = (ca.SX.sym("P", N, N), ca.SX.sym("k", N), ca.SX.sym("h", N), ca.SX.sym("r"))
    pat = CovariancePattern.full(N)
    return ca.Function("j", [P, k, h, r],
                       [ca.densify(joseph_update(pat.unpack(pat.pack(P)), k, h, r, pat))])


def _scalar_function():
    x, P, h = ca.SX.sym("x", N), ca.SX.sym("P", N, N), ca.SX.sym("h", N)
    nu, r, acc = ca.SX.sym("nu"), ca.SX.sym("r"), ca.SX.sym("accept")
    pat = CovariancePattern.full(N)
    out = scalar_update(x, pat.unpack(pat.pack(P)), h, nu, r, acc, pat)
    return ca.Function("s", [x, P, h, nu, r, acc], [out[0], ca.densify(out[1])])


def _ill_conditioned(rng, decades):
    Qm, _ = np.linalg.qr(rng.normal(size=(N, N)))
    P = (Qm * np.logspace(0, -decades, N)) @ Qm.T
    return np.triu(P) + np.triu(P, 1).T


def test_joseph_form_is_positive_for_any_gain_where_the_short_form_is_not(rng):
    """(E9) equals (I - k h^T) P (I - k h^T)^T + r k k^T for a gain that is not
    optimal, and stays positive semi-definite; P - s k k^T with that gain does not."""
    f = _joseph_function()
    naive_negative = 0
    for _ in range(50):
        P = random_spd(rng, N)
        h, r = rng.normal(size=N), rng.uniform(0.01, 1)
        k_opt = P @ h / (h @ P @ h + r)
        k = k_opt * (1 + 0.3 * rng.normal(size=N))        # a gain with errors
        A = np.eye(N) - np.outer(k, h)
        expected = A @ P @ A.T + r * np.outer(k, k)
        got = np.array(f(P, k, h, r))
        np.testing.assert_allclose(got, expected, rtol=1e-10, atol=1e-12)
        assert np.linalg.eigvalsh(got).min() > -1e-12
        naive = P - (h @ P @ h + r) * np.outer(k, k)
        naive_negative += np.linalg.eigvalsh(naive).min() < 0
    assert naive_negative >= 45


def test_joseph_updates_keep_an_ill_conditioned_covariance_positive(rng):
    """2000 optimal scalar updates with tiny r on P spanning 10 decades: P stays exactly
    symmetric with positive eigenvalues; the short form P - u u^T / s agrees to rounding."""
    f = _scalar_function()
    P = _ill_conditioned(rng, 10)
    x = np.zeros(N)
    worst = np.inf
    for it in range(2000):
        h = rng.normal(size=N)
        r = 1e-12 * (h @ P @ h)
        x, P_next = (np.array(v) for v in f(x, P, h, 1.0, r, 1.0))
        u = P @ h
        short = P - np.outer(u, u) / (h @ u + r)
        np.testing.assert_allclose(P_next, short, atol=1e-9 * np.abs(P).max())
        np.testing.assert_array_equal(P_next, P_next.T)
        P = P_next
        if it % 10 == 9:                                  # process noise, as a prediction adds
            P = P + np.diag(rng.uniform(0, 1e-6, N))
        ev = np.linalg.eigvalsh(P)
        worst = min(worst, ev.min() / ev.max())
    assert worst > 0


def test_a_record_not_pushed_never_reaches_a_fifo_slot():
    """A pop shifts the FIFO; the slot it empties is zero, not the record that was not
    pushed (a NaN in a packet that is not fresh stays out of the memory)."""
    from quadland_symbolic.kalman import fifo_push_pop

    slots, count = ca.SX.sym("slots", 2, 3), ca.SX.sym("count")
    record, push, due = ca.SX.sym("record", 2), ca.SX.sym("push"), ca.SX.sym("due")
    f = fifo_push_pop(slots, count, record, push, lambda head, nonempty: ca.logic_and(
        nonempty, due > 0.5))
    fn = ca.Function("fifo", [slots, count, record, push, due], [f["slots"], f["count"]])
    full = np.array([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]])
    for n in (1, 3):                       # part full, full: the head pops
        out, c = fn(full, n, [np.nan, np.inf], 0, 1)
        np.testing.assert_array_equal(np.asarray(out), [[2.0, 3.0, 0.0], [5.0, 6.0, 0.0]])
        assert float(c) == n - 1
    out, c = fn(full, 3, [7.0, 8.0], 1, 1)  # full, pushed and popped: the record lands last
    np.testing.assert_array_equal(np.asarray(out), [[2.0, 3.0, 7.0], [5.0, 6.0, 8.0]])
    assert float(c) == 3
