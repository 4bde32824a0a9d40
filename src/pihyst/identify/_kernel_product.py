"""Kernel weights of product form, for records that leave the minor loops open
(docs/theory/identification.md, "What a major loop leaves open").

A record of major loops fixes the loop width at each input, not how the Preisach density
is spread over the plane. The kp family's penalty picks the density nearest an
additively separable one; this module finds the one of product form

    w_ij = f_i g_j        (i < j: kernels falling at c_i and rising at c_j),

the form a maximum-entropy density with given row and column sums takes, with the
diagonal (reversible) kernels w_ii free but smooth:

    minimize  1/2 x^T G x - b^T x + 1/2 rho sigma |D2 w_diag|^2
    over f, g >= 0, the diagonal weights and the other columns (offset, ...),

in three stages. Alternating bounded least squares first: with g fixed the weights are
linear in f, x = T_g z, so each half-step is the QP of T_g^T G T_g; then the same with f
fixed; 10 sweeps from f = g = 1 (a density constant over the plane). Alternating sweeps
alone converge slowly (after 40, predictions were still 0.2 % of range from their
limit), so a trust-region least-squares solve in all the variables at once follows
(scipy.optimize.least_squares, G = L^T L on its range), and 3 more sweeps, which keep
any equality constraints exact. sigma = tr(G_kernels) / tr(D2^T D2) makes rho
dimensionless. The problem is not convex in (f, g) together; measured on random Preisach
actuators' triangle records, the three stages predict within 1.5e-6 of the range of
3000 alternating sweeps (with 1 sweep before the joint solve instead of 10, one of three
ended 1 % away, in another minimum).
"""

import numpy as np

from pihyst.exceptions import InfeasibleConstraintsError
from pihyst.identify._qp import solve_qp

# alternating sweeps (each: one QP for f, one for g) before the joint least-squares
# solve, and after it (they keep the equality constraints exact)
PRODUCT_SWEEPS = 10
POLISH_SWEEPS = 3
LSQ_MAX_EVALUATIONS = 500
# factor entries below this fraction of the largest are 0
NEGLIGIBLE = 1e-9
# eigenvalues of G below this fraction of the largest are its null space
EIGEN_FLOOR = 1e-13
# rho: smoothness of the reversible part (second differences of the diagonal weights)
PRODUCT_REVERSIBLE_SMOOTHING = 100.0


def product_density_fit(gram, pairs, grid, lower, upper, *, A_eq=None, b_eq=None,
                        sweeps=PRODUCT_SWEEPS, smoothing=PRODUCT_REVERSIBLE_SMOOTHING):
    """Weights x over [kernels ``pairs``..., other columns...] minimizing the module's
    objective on ``gram`` (a :class:`~pihyst.identify._gram.Gram` over those columns),
    within the bounds ``lower``/``upper`` of the other columns and the equality
    constraints ``A_eq x = b_eq``; None when no weights of product form meet them."""
    try:
        return _fit(gram, pairs, grid, lower, upper, A_eq, b_eq, sweeps, smoothing)
    except InfeasibleConstraintsError:
        return None


def _fit(gram, pairs, grid, lower, upper, A_eq, b_eq, sweeps, smoothing):
    prob = _Problem(gram, pairs, grid, lower, upper, smoothing)
    f, g = np.ones(grid), np.ones(grid)
    z = None
    for sweep in range(sweeps + POLISH_SWEEPS):
        if sweep == sweeps:
            f, g = prob.least_squares(f, g, z)
        for left in (True, False):
            T = prob.map(g if left else f, left)
            # a factor entry that meets only zeros of the other weights no kernel: it
            # stays 0 (left free, the QP could only put noise there)
            on = np.flatnonzero(np.any(T != 0.0, axis=0))
            Ta = T[:, on]
            z = np.zeros(T.shape[1])
            z[on] = solve_qp(Ta.T @ prob.G @ Ta + prob.R[np.ix_(on, on)], Ta.T @ prob.b,
                             lower=prob.lo[on], upper=prob.hi[on],
                             A_eq=None if A_eq is None else A_eq @ Ta, b_eq=b_eq,
                             warn=False).x
            if left:
                f = z[:grid]
            else:
                g = z[:grid]
            x = T @ z
        # f_n-1 and g_0 weight no kernel (i < j); the scale between f and g is free:
        # keep them comparable
        f[-1] = g[0] = 0.0
        s = np.sqrt(max(f.max(), 1e-300) / max(g.max(), 1e-300))
        f, g = f / s, g * s
    return x


class _Problem:
    """The objective in the variables z = [f or g, diagonal weights, other columns]."""

    def __init__(self, gram, pairs, grid, lower, upper, smoothing):
        self.G, self.b = gram.G, gram.b
        m, n_k = self.G.shape[0], len(pairs)
        self.grid, self.n_k = grid, n_k
        self.off = np.array([(k, i, j) for k, (i, j) in enumerate(pairs) if i < j],
                            dtype=int).reshape(-1, 3)
        diag = [k for k, (i, j) in enumerate(pairs) if i == j]
        rest = list(range(n_k, m))
        lower = np.broadcast_to(np.asarray(lower, dtype=float), (m,))
        upper = np.broadcast_to(np.asarray(upper, dtype=float), (m,))
        self.lo = np.r_[np.zeros(grid), lower[diag], lower[rest]]
        self.hi = np.r_[np.full(grid, np.inf), upper[diag], upper[rest]]
        # the fixed part of T: diagonal kernels and the other columns map to themselves
        self.fixed = np.zeros((m, grid + len(diag) + len(rest)))
        for q, k in enumerate(diag + rest):
            self.fixed[k, grid + q] = 1.0
        D2 = np.zeros((max(len(diag) - 2, 0), self.fixed.shape[1]))
        for q in range(D2.shape[0]):
            D2[q, grid + q:grid + q + 3] = (1.0, -2.0, 1.0)
        if D2.size:
            D2 *= np.sqrt(smoothing * np.trace(self.G[:n_k, :n_k]) / np.trace(D2.T @ D2))
        self.D2 = D2
        self.R = D2.T @ D2

    def map(self, other, left):
        """T with x = T z, z = [f, diagonal, others] (left) or [g, ...], the other
        factor fixed."""
        T = self.fixed.copy()
        k, i, j = self.off.T
        # entries at the solver's round-off of 0 are 0: scaled up, they would turn the
        # next QP's columns of them into huge, meaningless weights
        other = np.where(other > NEGLIGIBLE * max(other.max(), 1e-300), other, 0.0)
        if left:
            T[k, i] = other[j]
        else:
            T[k, j] = other[i]
        return T

    def least_squares(self, f, g, z):
        """(f, g) after a trust-region least-squares solve in all variables at once,
        from ``f``, ``g`` and the other variables of ``z`` (the last half-step's). The
        variables are f_0..f_n-2 and g_1..g_n-1: the others weight no kernel."""
        from scipy.optimize import least_squares  # lazy, like every SciPy import here

        n = self.grid - 1
        lam, V = np.linalg.eigh(self.G)
        keep = lam > EIGEN_FLOOR * max(lam.max(), 1e-300)
        L = np.sqrt(lam[keep])[:, None] * V[:, keep].T        # G = L^T L on its range
        c = (V[:, keep].T @ self.b) / np.sqrt(lam[keep])
        k, i, j = self.off.T
        fixed = self.fixed[:, self.grid:]
        D2 = self.D2[:, self.grid:]

        def weights(v):
            x = fixed @ v[2 * n:]
            x[k] += v[i] * v[n + j - 1]
            return x

        def residuals(v):
            return np.r_[L @ weights(v) - c, D2 @ v[2 * n:]]

        def jacobian(v):
            dx = np.zeros((self.G.shape[0], v.size))
            dx[k, i] = v[n + j - 1]
            dx[k, n + j - 1] = v[i]
            dx[:, 2 * n:] = fixed
            return np.r_[L @ dx, np.c_[np.zeros((D2.shape[0], 2 * n)), D2]]

        lo = np.r_[np.zeros(2 * n), self.lo[self.grid:]]
        hi = np.r_[np.full(2 * n, np.inf), self.hi[self.grid:]]
        rest = np.zeros(fixed.shape[1]) if z is None else z[self.grid:]
        v0 = np.clip(np.r_[f[:-1], g[1:], rest], lo, hi)
        v = least_squares(residuals, v0, jac=jacobian, bounds=(lo, hi), method="trf",
                          x_scale="jac", max_nfev=LSQ_MAX_EVALUATIONS).x
        return np.r_[v[:n], 0.0], np.r_[0.0, v[n:2 * n]]
