"""The loop's frequency response from its modal form, against direct solves."""

from __future__ import annotations

import control
import numpy as np
import pytest

from quadland.analysis import FrequencyResponse
from quadland.analysis.response import closed_loop_poles, frequency_grid, response_of


def _direct(sys, omega):
    """``C (s I - A)^-1 B + D`` by a dense LU solve at each frequency (s = j omega)."""
    A, B, C, D = (np.asarray(m, dtype=float) for m in (sys.A, sys.B, sys.C, sys.D))
    n = A.shape[0]
    z = [np.exp(1j * w * sys.dt) if sys.dt else 1j * w for w in omega]
    return np.stack([C @ np.linalg.solve(p * np.eye(n) - A, B) + D for p in z])


def _relative(G, ref):
    return float(np.max(np.linalg.norm(G - ref, axis=(1, 2)) / np.linalg.norm(ref, axis=(1, 2))))


def _adaptive_like(rng, nodes=40, m=3):
    """A stable loop shaped like the paper's: a plant of 6 states and ``nodes * m`` weight
    states that all share one eigenvalue (-0.5, identical leakage), coupled both ways."""
    k = nodes * m
    A = np.zeros((6 + k, 6 + k))
    A[:6, :6] = rng.standard_normal((6, 6)) - 6 * np.eye(6)
    A[6:, 6:] = -0.5 * np.eye(k)
    A[6:, :6] = 0.3 * rng.standard_normal((k, 6))
    A[:6, 6:] = 0.05 * rng.standard_normal((6, k))
    return control.ss(A, rng.standard_normal((6 + k, m)), rng.standard_normal((m, 6 + k)),
                      np.zeros((m, m)))


def test_a_loop_with_a_repeated_diagonalizable_eigenvalue_is_modal_and_exact(rng):
    """120 weight states on one eigenvalue: the modal form is used and agrees with the
    direct solves across the whole grid to 1e-10."""
    sys = _adaptive_like(rng)
    resp = FrequencyResponse(sys)
    assert resp.modal
    omega = frequency_grid(resp)
    assert _relative(resp(omega), _direct(sys, omega)) < 1e-10
    assert _relative(resp(omega[::50]), np.stack([resp.at(resp.point(w))
                                                  for w in omega[::50]])) < 1e-10


@pytest.mark.parametrize("dt", [0.0, 0.01])
def test_a_defective_loop_keeps_the_schur_form(dt):
    """A quadruple integrator (continuous) and a 6-period delay line (sampled, a nilpotent
    block at z = 0) have no well-conditioned eigenvectors: the triangular solves answer,
    and they agree with the direct solves."""
    if dt:
        A = np.diag(np.ones(5), -1)
        sys = control.ss(A, np.eye(6)[:, :1], 0.5 * np.eye(6)[-1:] + 0.1, [[0.0]], dt)
        omega = np.linspace(0.1, 0.99 * np.pi / dt, 40)
    else:
        sys = control.ss(control.tf([2, 6, 6, 2], [1, 0, 0, 0, 0]))
        omega = np.geomspace(1e-1, 1e2, 40)
    resp = FrequencyResponse(sys)
    assert not resp.modal
    assert _relative(resp(omega), _direct(sys, omega)) < 1e-9


def test_the_analyses_of_one_loop_share_its_response(rng):
    """Equal matrices give the same object; one changed entry another, and other poles."""
    sys = _adaptive_like(rng, nodes=5)
    same = control.ss(np.array(sys.A), np.array(sys.B), np.array(sys.C), np.array(sys.D))
    assert response_of(sys) is response_of(same)
    A = np.array(sys.A)
    A[0, 0] -= 1.0
    other = control.ss(A, sys.B, sys.C, sys.D)
    assert response_of(other) is not response_of(sys)
    closed = closed_loop_poles(other)
    closed[:] = 0.0                                         # a copy: the kept one is intact
    expected = np.linalg.eigvals(A - np.asarray(sys.B) @ np.asarray(sys.C))
    np.testing.assert_allclose(np.sort_complex(closed_loop_poles(other)),
                               np.sort_complex(expected), rtol=1e-9)


def test_a_response_keeps_its_grids_and_points(monkeypatch):
    """The defective sampled loop of the test above: a grid asked again and a point asked
    again are not solved again (one solve per frequency in all), the values equal the
    direct solves, and writing into an answer does not reach the kept one."""
    A = np.diag(np.ones(5), -1)
    sys = control.ss(A, np.eye(6)[:, :1], 0.5 * np.eye(6)[-1:] + 0.1, [[0.0]], 0.01)
    resp = FrequencyResponse(sys)
    assert not resp.modal
    solves = []
    solve = resp._solve
    monkeypatch.setattr(resp, "_solve", lambda p: solves.append(p) or solve(p))
    omega = np.linspace(0.1, 0.99 * np.pi / 0.01, 40)
    G = resp(omega)
    G[:] = 0.0
    again = resp(omega)
    assert len(solves) == omega.size
    assert _relative(again, _direct(sys, omega)) < 1e-9
    p = resp.point(1.7)
    g = resp.at(p)
    g[:] = 0.0
    assert len(solves) == omega.size + 1
    np.testing.assert_allclose(resp.at(p), _direct(sys, [1.7])[0], rtol=1e-9)
    assert len(solves) == omega.size + 1
