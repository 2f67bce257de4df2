"""Branch-free Kalman filter pieces on CasADi SX expressions.

The navigation filter of :mod:`quadland_symbolic.landing.estimator` is assembled from
these; docs/estimator.md gives the equations, cited here as (E1)...

* :func:`nilpotent_discretization`: exact ``Phi``, ``Gamma`` and discrete
  ``Q`` of ``x' = A x + B u + w`` (``u`` held, ``E[w w^T] = W delta``) when
  ``A`` is nilpotent, as finite power series (E3)-(E5);
* :class:`CovariancePattern`: which upper-triangle entries of a covariance
  are stored (all of them, or blocks), packed to and from a vector;
* :func:`scalar_update`: one scalar measurement in Joseph form on the stored
  entries only (E9), gated so that a rejected one changes nothing;
* :func:`block_nis`: ``nu^T S^-1 nu`` by a small Cholesky factorization (E8);
* :func:`select`, :func:`is_finite`, :func:`fifo_push_pop`: branch-free
  selections, so that generated C runs the same instructions every period;
* :func:`operation_counts`: what an SX Function costs.

Every selection is CasADi's ``if_else`` written without short-circuit, which
the C code computes as ``(c ? a : 0) + (!c ? b : 0)``: both sides are computed,
a NaN on the unused side does not leak, and a zero may change its sign.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections import Counter

import casadi as ca
import numpy as np

__all__ = [
    "CovariancePattern",
    "nilpotent_discretization",
    "block_nis",
    "joseph_update",
    "scalar_update",
    "select",
    "is_finite",
    "fifo_push_pop",
    "operation_counts",
]


def select(c, a, b):
    """``a`` where ``c`` else ``b``, both computed (no branch)."""
    return ca.if_else(c, a, b)


def is_finite(e):
    """1 where ``e`` is finite (``|e| < inf`` is false for NaN)."""
    return ca.fabs(e) < ca.inf


# ---------------------------------------------------------------- discretization

def _nilpotency_index(A: np.ndarray) -> int:
    """Smallest ``k`` with ``A^k = 0`` (``ValueError`` if none)."""
    n = A.shape[0]
    M = np.eye(n)
    for k in range(1, n + 1):
        M = M @ A
        if not np.any(M):
            return k
    raise ValueError("A is not nilpotent")


def nilpotent_discretization(A, B, W, dt):
    """Exact discretization of ``x' = A x + B u + w``, nilpotent ``A``.

    With ``A^K = 0`` the matrix exponential and the integrals are finite sums
    (docs/estimator.md, (E3)-(E5)):

    ``Phi = sum_{i<K} A^i dt^i / i!``,
    ``Gamma = sum_{i<K} A^i B dt^(i+1) / (i+1)!``,
    ``Q = sum_{i,j<K} A^i W (A^T)^j dt^(i+j+1) / (i! j! (i+j+1))``,
    the last being ``int_0^dt e^(A s) W e^(A^T s) ds`` term by term.

    Parameters
    ----------
    A : numpy.ndarray
        ``n x n`` numeric nilpotent matrix.
    B : numpy.ndarray
        ``n x m`` numeric input matrix.
    W : casadi.SX
        ``n x n`` power spectral density of ``w`` (may be symbolic).
    dt : casadi.SX
        Interval (s).

    Returns
    -------
    Phi, Gamma, Q : casadi.SX
    """
    A, B = np.asarray(A, dtype=float), np.asarray(B, dtype=float)
    K = _nilpotency_index(A)
    Ak = [ca.sparsify(ca.DM(np.linalg.matrix_power(A, i))) for i in range(K)]
    dt_pow = [1, dt]
    for _ in range(2 * K):
        dt_pow.append(dt_pow[-1] * dt)
    Phi = ca.SX(*A.shape)
    Gamma = ca.SX(*B.shape)
    Q = ca.SX(*A.shape)
    for i in range(K):
        Phi += Ak[i] * (dt_pow[i] / math.factorial(i))
        Gamma += (Ak[i] @ ca.sparsify(ca.DM(B))) * (dt_pow[i + 1] / math.factorial(i + 1))
        for j in range(K):
            coef = dt_pow[i + j + 1] / (math.factorial(i) * math.factorial(j) * (i + j + 1))
            Q += (Ak[i] @ W @ Ak[j].T) * coef
    return Phi, Gamma, ca.triu(Q) + ca.triu(Q, False).T     # exactly symmetric


# ---------------------------------------------------------------- covariance storage

@dataclasses.dataclass(frozen=True)
class CovariancePattern:
    """The stored entries of an ``n x n`` covariance.

    The upper triangles of diagonal blocks: ``groups`` partitions
    ``range(n)``; entries whose row and column lie in different groups are
    structurally zero and never stored or computed. One group holding
    everything is the full covariance.

    Examples
    --------
    >>> pat = CovariancePattern(3, ((0, 2), (1,)))
    >>> pat.entries
    ((0, 0), (0, 2), (1, 1), (2, 2))
    >>> pat.size
    4
    """

    n: int
    groups: tuple[tuple[int, ...], ...]

    def __post_init__(self):
        flat = sorted(i for g in self.groups for i in g)
        if flat != list(range(self.n)):
            raise ValueError(f"groups must partition range({self.n}), got {self.groups}")

    @classmethod
    def full(cls, n: int) -> CovariancePattern:
        """Every upper-triangle entry of an ``n x n`` covariance."""
        return cls(n, (tuple(range(n)),))

    @functools.cached_property
    def group_of(self) -> tuple[int, ...]:
        """Index of each state's group."""
        out = [0] * self.n
        for k, g in enumerate(self.groups):
            for i in g:
                out[i] = k
        return tuple(out)

    @functools.cached_property
    def entries(self) -> tuple[tuple[int, int], ...]:
        """Stored ``(i, j)``, ``i <= j``, row by row."""
        return tuple((i, j) for i in range(self.n) for j in range(i, self.n)
                     if self.group_of[i] == self.group_of[j])

    @property
    def size(self) -> int:
        """Number of stored entries."""
        return len(self.entries)

    def element_names(self, prefix: str = "P") -> tuple[str, ...]:
        """``P_i_j`` (1-based) of each stored entry."""
        return tuple(f"{prefix}_{i + 1}_{j + 1}" for i, j in self.entries)

    def unpack(self, v) -> ca.SX:
        """Symmetric SX matrix from the packed vector.

        Entries outside the pattern are structural zeros.
        """
        P = ca.SX(self.n, self.n)
        for k, (i, j) in enumerate(self.entries):
            P[i, j] = v[k]
            if i != j:
                P[j, i] = v[k]
        return P

    def pack(self, P) -> ca.SX:
        """The stored entries of ``P`` (its upper triangle) as a column."""
        return ca.vertcat(*[P[i, j] for i, j in self.entries])

    def pack_numeric(self, P) -> np.ndarray:
        """The stored entries of a NumPy matrix, in order."""
        P = np.asarray(P, dtype=float)
        return np.array([P[i, j] for i, j in self.entries])

    def unpack_numeric(self, v) -> np.ndarray:
        """A symmetric NumPy matrix from the packed vector."""
        P = np.zeros((self.n, self.n))
        for k, (i, j) in enumerate(self.entries):
            P[i, j] = P[j, i] = v[k]
        return P


# ---------------------------------------------------------------- measurement update

def block_nis(S, nu):
    """``nu^T S^-1 nu`` of a small SPD ``S`` by Cholesky (E8).

    ``S = L L^T``; ``y = L^-1 nu`` by forward substitution; NIS ``= y^T y``.
    A ``S`` that is not positive definite gives NaN (the square root of a
    negative number), which no gate accepts.
    """
    m = nu.shape[0]
    L = [[None] * m for _ in range(m)]
    for j in range(m):
        d = S[j, j] - sum((L[j][k] ** 2 for k in range(j)), 0)
        L[j][j] = ca.sqrt(d)
        for i in range(j + 1, m):
            L[i][j] = (S[i, j] - sum((L[i][k] * L[j][k] for k in range(j)), 0)) / L[j][j]
    y = []
    for i in range(m):
        y.append((nu[i] - sum((L[i][k] * y[k] for k in range(i)), 0)) / L[i][i])
    return sum((yi**2 for yi in y), 0)


def joseph_update(P, k, h, r, pattern: CovariancePattern):
    """Joseph's covariance update for any gain ``k`` (E9).

    ``(I - k h^T) P (I - k h^T)^T + r k k^T``, expanded with ``u = P h``,
    ``s = h^T u + r``: ``P - k u^T - u k^T + s k k^T``, on the upper triangle
    of ``pattern``'s entries only (``O(n^2)``), mirrored. Positive
    semi-definite for every ``k``, the optimal ``u / s`` or not.
    """
    u = P @ h
    s = h.T @ u + r
    sk = s * k
    # the same scalar expressions as P[i, j] - k[i] u[j] - u[i] k[j] + sk[i] k[j] entry by
    # entry, formed as outer products at once (Python's element access was most of the
    # cost of building a filter), then kept on the pattern's entries only
    E = P - k @ u.T - u @ k.T + sk @ k.T
    P_next = ca.SX(pattern.n, pattern.n)
    for i, j in pattern.entries:
        e = E[i, j]
        P_next[i, j] = e
        if i != j:
            P_next[j, i] = e
    return P_next


def scalar_update(x, P, h, nu, r, accept, pattern: CovariancePattern):
    """One scalar measurement, gated, in Joseph form (E9).

    ``u = P h``, ``s = h^T u + r``, ``k = u / s``; ``x+ = x + k nu`` and
    ``P+`` by :func:`joseph_update`. Where ``accept`` is 0 the gain is
    exactly 0 (and ``nu``, ``r`` are replaced by 0 and 1, so that a NaN
    measurement does not leak): ``x`` and ``P`` come back unchanged.

    Parameters
    ----------
    x : casadi.SX
        State, ``n x 1``.
    P : casadi.SX
        Symmetric covariance with ``pattern``'s sparsity.
    h : casadi.SX
        ``n x 1`` measurement row (the Jacobian's transpose); structural zeros
        where the measurement does not depend on the state. It must be finite.
    nu, r, accept : casadi.SX
        Innovation, measurement variance, and 1 to fuse.
    pattern : CovariancePattern

    Returns
    -------
    x_next, P_next : casadi.SX
    """
    nu = select(accept, nu, 0)
    r = select(accept, r, 1)
    u = P @ h
    s = h.T @ u + r
    # accept * (1/s), not a selection: CasADi would carry a selection into
    # every product of k (doubling the update's cost); s >= r > 0 is finite
    k = u * (accept * (1 / s))
    return x + k * nu, joseph_update(P, k, h, r, pattern)


# ---------------------------------------------------------------- FIFO

def fifo_push_pop(slots, count, record, push, pop_if):
    """Push ``record`` onto a FIFO, then pop its head if due.

    The FIFO is the columns of ``slots`` (``rec x depth``), oldest first, of
    which the first ``count`` are in use. The pushed record may be popped at
    once; one that finds the FIFO full after the pop is dropped. Every slot is
    written by selection, with no branch; a record that is not pushed never
    reaches a slot (a pop then empties the last one to zeros).

    Parameters
    ----------
    slots : casadi.SX
        ``rec x depth``.
    count : casadi.SX
        Records in use.
    record : casadi.SX
        ``rec x 1``, pushed where ``push`` is 1.
    push : casadi.SX
    pop_if : callable
        ``pop_if(head, nonempty) -> pop`` (0 or 1) from the head after the push.

    Returns
    -------
    dict
        ``head`` (the head after the push), ``pop``, ``dropped``, and
        ``slots`` and ``count`` after both.
    """
    depth = slots.shape[1]
    # one slot more than stored: the record lands at position ``count``. The extra
    # slot is zero unless pushed: a record that is not pushed (not fresh, not
    # finite) must not reach the memory through the shift, even beyond ``count``.
    ext = [select(ca.logic_and(push, count == i), record, slots[:, i]) for i in range(depth)]
    ext.append(select(push, record, ca.DM.zeros(record.shape)))
    count1 = count + push
    head = ext[0]
    pop = pop_if(head, count1 > 0)
    shifted = ca.horzcat(*[select(pop, ext[i + 1], ext[i]) for i in range(depth)])
    dropped = ca.logic_and(ca.logic_and(push, count >= depth), ca.logic_not(pop))
    return dict(head=head, pop=pop, dropped=dropped, slots=shifted,
                count=count1 - pop - dropped)


# ---------------------------------------------------------------- cost

#: CasADi operations that move data rather than compute.
_NOT_ARITHMETIC = frozenset({ca.OP_INPUT, ca.OP_OUTPUT, ca.OP_CONST, ca.OP_PARAMETER,
                             ca.OP_ASSIGN})


def operation_counts(f: ca.Function) -> dict:
    """Size of an SX Function's algorithm.

    Returns
    -------
    dict
        ``instructions`` (``f.n_instructions()``: every step, loads and
        stores included), ``arithmetic`` (steps that compute a value:
        arithmetic, comparisons, selections, functions), ``inputs``,
        ``outputs``, ``constants`` (their counts) and ``by_op`` (a
        ``collections.Counter`` of CasADi operation codes).
    """
    ops = Counter(f.instruction_id(k) for k in range(f.n_instructions()))
    return dict(
        instructions=f.n_instructions(),
        arithmetic=sum(n for op, n in ops.items() if op not in _NOT_ARITHMETIC),
        inputs=ops[ca.OP_INPUT], outputs=ops[ca.OP_OUTPUT], constants=ops[ca.OP_CONST],
        by_op=ops,
    )
