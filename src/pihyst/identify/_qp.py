"""Constrained least squares on a Gram matrix, solved by quadprog (Goldfarb-Idnani).

Identification (docs/theory/identification.md, paper eqs. 8-11) minimizes ||A x - d||^2 over the
weights x, i.e. the quadratic programme

    minimize  1/2 x^T H x - g^T x,    H = A^T A,  g = A^T d,
    subject to  lower <= x <= upper,  A_eq x = b_eq,

on the small K x K matrix H, never on A itself. Before solving, the variables are scaled
so that H has a unit diagonal (x_i = x'_i / sqrt(H_ii)); a scaled H whose condition
number (LAPACK's 1-norm estimate) exceeds 1/``rcond`` is ill-conditioned: a ridge of
``rcond * ||H'||_1`` (>= rcond * lambda_max) is added (which picks the smallest weights
among the almost equally good ones) and an
:class:`~pihyst.exceptions.IllConditionedWarning` says so.
"""

import warnings
from dataclasses import dataclass

import numpy as np
import quadprog

from pihyst.exceptions import IllConditionedWarning, InfeasibleConstraintsError

DEFAULT_RCOND = 1e-11


@dataclass(frozen=True)
class QPSolution:
    """Result of :func:`solve_qp`.

    ``x``: the solution; ``objective``: 1/2 x^T H x - g^T x (without the ridge);
    ``condition``: condition number (1-norm estimate) of the diagonally scaled H;
    ``regularized``: whether
    a ridge was needed."""

    x: np.ndarray
    objective: float
    condition: float
    regularized: bool


def _bound_vector(value, n, default, name):
    if value is None:
        return np.full(n, default)
    v = np.asarray(value, dtype=float)
    if v.shape != (n,):
        v = np.broadcast_to(v, (n,))
    if np.isnan(v).any():
        raise ValueError(f"{name} contains NaN")
    return v


def _independent_equalities(A_eq, b_eq, n):
    """Equality rows reduced to an independent set; InfeasibleConstraintsError if they
    contradict each other."""
    A = np.atleast_2d(np.asarray(A_eq, dtype=float))
    b = np.atleast_1d(np.asarray(b_eq, dtype=float))
    if A.shape[1] != n or A.shape[0] != b.size:
        raise ValueError(f"A_eq must be (m, {n}) and b_eq (m,), got {A.shape} and {b.shape}")
    if not (np.all(np.isfinite(A)) and np.all(np.isfinite(b))):
        raise ValueError("equality constraints must be finite")
    # A = U S V^T: the constraints are S_r V_r^T x = U_r^T b on the rank-r part, and
    # they are consistent iff b has no component outside range(A).
    U, s, Vt = np.linalg.svd(A, full_matrices=False)
    tol = max(A.shape) * np.finfo(float).eps * (s[0] if s.size else 0.0)
    r = int(np.sum(s > tol))
    c = U.T @ b
    scale = max(1.0, float(np.abs(b).max(initial=0.0)))
    if np.linalg.norm(b - U[:, :r] @ c[:r]) > 1e-9 * scale * np.sqrt(b.size):
        raise InfeasibleConstraintsError("the equality constraints contradict each other")
    return Vt[:r], c[:r] / s[:r]


def solve_qp(H, g, *, lower=None, upper=None, A_eq=None, b_eq=None, rcond=DEFAULT_RCOND,
             warn=True, names=None):
    """Minimize 1/2 x^T H x - g^T x subject to bounds and equality constraints.

    Parameters
    ----------
    H : (n, n) array_like
        Symmetric positive semi-definite matrix (a Gram matrix A^T A).
    g : (n,) array_like
        Linear term (A^T d).
    lower, upper : float or (n,) array_like, optional
        Bounds on x; -inf/+inf (the defaults) for none.
    A_eq, b_eq : (m, n) and (m,) array_like, optional
        Equality constraints A_eq x = b_eq.
    rcond : float
        Smallest admissible reciprocal condition number of the scaled H.
    warn : bool
        Issue an :class:`~pihyst.exceptions.IllConditionedWarning` when a ridge was needed.
    names : list of str, optional
        Names of the variables, used in the warning message.

    Returns
    -------
    QPSolution

    Raises
    ------
    InfeasibleConstraintsError
        If no x satisfies the constraints.

    Examples
    --------
    Non-negative least squares of A x ~ d through the Gram matrix:

    >>> import numpy as np
    >>> A = np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    >>> d = np.array([1.0, -1.0, 0.5])
    >>> sol = solve_qp(A.T @ A, A.T @ d, lower=0.0)
    >>> [round(float(v), 6) for v in sol.x]
    [0.75, 0.0]
    """
    H = np.asarray(H, dtype=float)
    g = np.asarray(g, dtype=float).ravel()
    n = g.size
    if H.shape != (n, n):
        raise ValueError(f"H must be ({n}, {n}), got {H.shape}")
    if not (np.isfinite(H).all() and np.isfinite(g).all()):
        raise ValueError("H and g must be finite")
    lo = _bound_vector(lower, n, -np.inf, "lower")
    hi = _bound_vector(upper, n, np.inf, "upper")
    if (lo > hi).any():
        i = int(np.flatnonzero(lo > hi)[0])
        raise InfeasibleConstraintsError(f"lower bound {lo[i]:g} is above upper bound "
                                         f"{hi[i]:g} for {_name(names, i)}")

    # Scale: x = x' / s with s_i = sqrt(H_ii), so that H' = H / (s s^T) has a unit diagonal.
    diag = np.diag(H).copy()
    s = np.sqrt(np.where(diag > 0, diag, 1.0))
    Hs = H / np.outer(s, s)
    Hs = 0.5 * (Hs + Hs.T)
    gs = g / s
    # Condition number (1-norm estimate) from the Cholesky factor of H'; H' not positive
    # definite counts as infinitely ill-conditioned.
    norm1 = float(np.abs(Hs).sum(axis=0).max())
    from scipy.linalg.lapack import dpocon, dpotrf, dpotrs  # lazy: 0.2 s to load

    factor, info = dpotrf(Hs, lower=0, clean=1)
    condition = np.inf
    if info == 0 and norm1 > 0:
        rc, info = dpocon(factor, norm1)
        condition = 1.0 / rc if info == 0 and rc > 0 else np.inf
    regularized = not condition < 1.0 / rcond
    if regularized:
        if warn:
            _warn_ill_conditioned(np.linalg.eigh(Hs)[1][:, 0], condition, names)
        # ridge rcond * lambda_max, with lambda_max <= ||H'||_1
        Hs = Hs + rcond * max(norm1, np.finfo(float).tiny) * np.eye(n)
        factor, info = dpotrf(Hs, lower=0, clean=1)
    # Without equality constraints, the unconstrained minimizer x' = H'^-1 g' is the
    # answer whenever it is within the bounds (no constraint active).
    if (A_eq is None or not np.size(A_eq)) and info == 0:
        x = dpotrs(factor, gs, lower=0)[0] / s
        if (x >= lo).all() and (x <= hi).all():
            return QPSolution(x=x, objective=float(0.5 * x @ H @ x - g @ x),
                              condition=float(condition), regularized=bool(regularized))

    # Constraints as quadprog wants them: C^T x' >= c, the first meq being equalities.
    blocks, rhs, meq = [], [], 0
    if A_eq is not None and np.size(A_eq):
        Ar, br = _independent_equalities(A_eq, b_eq, n)
        Ar = Ar / s
        norm = np.linalg.norm(Ar, axis=1)
        blocks.append((Ar / norm[:, None]).T)
        rhs.append(br / norm)
        meq = Ar.shape[0]
    eye = np.eye(n)
    has_lo, has_hi = np.isfinite(lo), np.isfinite(hi)
    blocks += [eye[:, has_lo], -eye[:, has_hi]]
    rhs += [lo[has_lo] * s[has_lo], -hi[has_hi] * s[has_hi]]
    C = np.hstack(blocks)
    c = np.concatenate(rhs)
    try:
        xs = quadprog.solve_qp(Hs, gs, C, c, meq)[0]
    except ValueError as err:
        if "inconsistent" in str(err):
            raise InfeasibleConstraintsError("no weights satisfy the constraints (bounds and "
                                             "equality constraints together)") from None
        raise
    x = np.clip(xs / s, lo, hi)
    objective = float(0.5 * x @ H @ x - g @ x)
    return QPSolution(x=x, objective=objective, condition=float(condition),
                      regularized=bool(regularized))


def _name(names, i):
    return names[i] if names is not None else f"x[{i}]"


def _warn_ill_conditioned(vec, condition, names):
    # The eigenvector of the smallest eigenvalue shows which variables are (almost)
    # interchangeable: the data cannot tell their weights apart.
    involved = np.flatnonzero(np.abs(vec) > 0.2 * np.abs(vec).max())
    who = ", ".join(_name(names, i) for i in involved)
    cond = "infinite" if not np.isfinite(condition) else f"{condition:.3g}"
    warnings.warn(f"ill-conditioned least-squares problem (condition number {cond}): the "
                  f"data hardly distinguish {who}; returned the best admissible weights, "
                  f"with a tiny ridge choosing the smallest of them", IllConditionedWarning,
                  stacklevel=3)
