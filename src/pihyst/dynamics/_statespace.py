"""Discrete MIMO state-space models identified by frequency-domain subspace
identification (McKelvey, Akcay and Ljung 1996, "Subspace-based multivariable system
identification from frequency response data", IEEE TAC 41(7)).

The model, from rest (x[0] = 0), sample time 1:

    x[t+1] = A x[t] + B u[t],      y[t] = C x[t] + D u[t],
    G(z) = C (z I - A)^-1 B + D,   z_k = exp(i w_k).

**FSID** (:func:`fsid`) from a frequency response G_k (p x m) on lines w_k, k = 1..L.
With q > n block rows, the data satisfy G_q = O_q X + Gamma_q W_q, where

    G_q = [G_k; z_k G_k; ...; z_k^(q-1) G_k]_k         (q p x m L),
    W_q = [I_m; z_k I_m; ...; z_k^(q-1) I_m]_k         (q m x m L),
    O_q = [C; C A; ...; C A^(q-1)]                     (the extended observability matrix),
    X   = [(z_k I - A)^-1 B]_k,

Gamma_q the lower block-triangular Toeplitz matrix of D, CB, CAB, ... Stacking real and
imaginary parts (so the realisation is real), the LQ factorisation

    [Re W_q  Im W_q]   [L11  0 ] [Q1]
    [Re G_q  Im G_q] = [L21 L22] [Q2]

removes the input term: the n dominant left singular vectors U_n of L22 span O_q's
range, so O_q = U_n (up to a state basis). Then C is its first block row and A solves
the shift equation O_q[p:] = O_q[:-p] A by least squares. With A and C fixed, G is
linear in B and D; they solve

    min_{B, D} sum_k || W_k o (C (z_k I - A)^-1 B + D - G_k) ||_F^2

(W_k elementwise weights, e.g. 1 / standard deviation of the estimate G_k), linear least
squares on the real and imaginary parts, one input column at a time.

**Stability** (:func:`stabilized`). A's eigenvalues outside the unit circle are
reflected inside (lambda -> 1 / conj(lambda), which keeps each mode's amplitude response
up to a gain, then B and D are refitted); the realisation is then in real modal form.
Eigenvalues on or within 1e-6 of the unit circle are pulled to radius 1 - 1e-6. Every
returned model has spectral radius < 1.

**Order** (:func:`pihyst.dynamics.fit_state_space`): chosen by validation: the models of
each candidate order fitted on the BLA of some records are simulated from rest on the
others, and the order with the smallest steady-state simulation error wins.
"""

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pihyst.exceptions import InvalidArgumentError

MAX_RADIUS = 1.0 - 1e-6


@dataclass(frozen=True, eq=False)
class StateSpace:
    """x[t+1] = A x[t] + B u[t], y[t] = C x[t] + D u[t] (module notes).

    Parameters
    ----------
    A : array_like
        (n, n) state matrix.
    B : array_like
        (n, m) input matrix.
    C : array_like
        (p, n) output matrix.
    D : array_like
        (p, m) feedthrough.

    Raises
    ------
    InvalidArgumentError
        Shapes that do not match, or NaN or infinite entries.

    Examples
    --------
    >>> from pihyst.dynamics import StateSpace
    >>> ss = StateSpace([[0.5]], [[1.0]], [[1.0]], [[0.0]])
    >>> ss.order, ss.n_inputs, ss.n_outputs, ss.spectral_radius
    (1, 1, 1, 0.5)
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray

    def __post_init__(self):
        A, B, C, D = (np.atleast_2d(np.asarray(x, dtype=float))
                      for x in (self.A, self.B, self.C, self.D))
        n = A.shape[0]
        if A.shape != (n, n) or B.shape[0] != n or C.shape[1] != n or \
                D.shape != (C.shape[0], B.shape[1]):
            raise InvalidArgumentError(f"state-space shapes do not match: A {A.shape}, "
                                       f"B {B.shape}, C {C.shape}, D {D.shape}")
        for name, x in zip("ABCD", (A, B, C, D)):
            if not np.all(np.isfinite(x)):
                raise InvalidArgumentError(f"state-space matrix {name} holds NaN or inf")
            object.__setattr__(self, name, x)

    @property
    def order(self):
        return self.A.shape[0]

    @property
    def n_inputs(self):
        return self.B.shape[1]

    @property
    def n_outputs(self):
        return self.C.shape[0]

    @property
    def spectral_radius(self):
        return float(np.max(np.abs(np.linalg.eigvals(self.A)), initial=0.0))

    def response(self, omega: ArrayLike) -> NDArray[np.complex128]:
        """G(exp(i w)) for normalised angular frequencies w (rad/sample).

        Parameters
        ----------
        omega : array_like
            (L,) angular frequencies, rad/sample.

        Returns
        -------
        ndarray of complex
            (L, p, m) the frequency response on each.

        Examples
        --------
        >>> from pihyst.dynamics import StateSpace
        >>> ss = StateSpace([[0.5]], [[1.0]], [[1.0]], [[0.0]])
        >>> G = ss.response([0.0, 3.141592653589793])
        >>> G.shape, G.real.round(6).ravel().tolist()
        ((2, 1, 1), [2.0, -0.666667])
        """
        return _response(self.A, self.B, self.C, self.D, np.asarray(omega, dtype=float))

    def dc_gain(self) -> NDArray[np.float64]:
        """G(1), the static gain.

        Returns
        -------
        ndarray
            (p, m) the steady output per unit of each input.

        Examples
        --------
        >>> from pihyst.dynamics import StateSpace
        >>> ss = StateSpace([[0.5]], [[1.0]], [[1.0]], [[0.0]])
        >>> ss.dc_gain()
        array([[2.]])
        """
        return self.response([0.0])[0].real

    def predict(self, u: ArrayLike) -> NDArray[np.float64]:
        """The output for the input ``u``, from rest (x[0] = 0).

        Parameters
        ----------
        u : array_like
            (N, m) inputs, or (N,) for one input.

        Returns
        -------
        ndarray
            (N, p) outputs.

        Raises
        ------
        InvalidArgumentError
            ``u`` has not as many columns as the model has inputs.

        Examples
        --------
        >>> from pihyst.dynamics import StateSpace
        >>> ss = StateSpace([[0.5]], [[1.0]], [[1.0]], [[0.0]])
        >>> ss.predict([1.0, 1.0, 1.0]).ravel().tolist()
        [0.0, 1.0, 1.5]
        """
        inputs = np.atleast_2d(np.asarray(u, dtype=float).T).T
        if inputs.shape[1] != self.n_inputs:
            raise InvalidArgumentError(f"the model has {self.n_inputs} inputs; u has "
                                       f"{inputs.shape[1]} columns")
        return simulate(self.A, self.B, self.C, self.D, inputs)

    def scaled_inputs(self, gains: ArrayLike) -> "StateSpace":
        """The model of u -> y with input i scaled by gains[i] (B and D columns).

        Parameters
        ----------
        gains : array_like
            (m,) one gain per input.

        Returns
        -------
        StateSpace
            The model of u -> y where this one sees gains * u.

        Examples
        --------
        >>> from pihyst.dynamics import StateSpace
        >>> ss = StateSpace([[0.5]], [[1.0]], [[1.0]], [[0.0]])
        >>> ss.scaled_inputs([3.0]).dc_gain()
        array([[6.]])
        """
        g = np.asarray(gains, dtype=float)
        return StateSpace(self.A, self.B * g, self.C, self.D * g)

    def to_dict(self) -> dict[str, Any]:
        """The model as JSON values (:meth:`from_dict` reads them back).

        Returns
        -------
        dict
            ``family`` ("state-space") and the matrices ``A``, ``B``, ``C``, ``D`` as
            nested lists.

        Examples
        --------
        >>> from pihyst.dynamics import StateSpace
        >>> ss = StateSpace([[0.5]], [[1.0]], [[1.0]], [[0.0]])
        >>> ss.to_dict()
        {'family': 'state-space', 'A': [[0.5]], 'B': [[1.0]], 'C': [[1.0]], 'D': [[0.0]]}
        """
        return {"family": "state-space", "A": self.A.tolist(), "B": self.B.tolist(),
                "C": self.C.tolist(), "D": self.D.tolist()}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> "StateSpace":
        """The model a dict of :meth:`to_dict` describes.

        Parameters
        ----------
        d : dict
            With the matrices ``A``, ``B``, ``C``, ``D``.

        Returns
        -------
        StateSpace
            The model.

        Examples
        --------
        >>> from pihyst.dynamics import StateSpace
        >>> ss = StateSpace.from_dict({"A": [[0.5]], "B": [[1.0]], "C": [[1.0]], "D": [[0.0]]})
        >>> ss.dc_gain()
        array([[2.]])
        """
        return cls(*(np.asarray(d[k], dtype=float) for k in "ABCD"))


MODAL_CONDITION = 1e8    # eigenvector conditioning up to which the modal resolvent is used


def _left_resolvent(C, A, z):
    """C (z_k I - A)^-1 for every z_k: (L, p, n). With A = V diag(lambda) V^-1 (V well
    conditioned) this is (C V) diag(1 / (z_k - lambda)) V^-1, O(p n^2) per line instead
    of a solve."""
    n = A.shape[0]
    lam, V = np.linalg.eig(A)
    if np.linalg.cond(V) < MODAL_CONDITION:
        CV, Vi = C @ V, np.linalg.inv(V)
        return (CV[None] / (z[:, None] - lam[None])[:, None, :]) @ Vi[None]
    lhs = np.swapaxes(z[:, None, None] * np.eye(n)[None] - A[None], 1, 2)
    rhs = np.broadcast_to(C.T.astype(complex), (z.size,) + C.T.shape)
    return np.swapaxes(np.linalg.solve(lhs, rhs), 1, 2)


def _response(A, B, C, D, omega):
    z = np.exp(1j * omega)
    return _left_resolvent(C, A, z) @ B[None] + D[None]


def simulate(A, B, C, D, u):
    """The state recursion of the module notes from x[0] = 0: y (N, p)."""
    N, n = u.shape[0], A.shape[0]
    Bu = u @ B.T
    X = np.empty((N, n))
    x = np.zeros(n)
    At = A.T.copy()
    for t in range(N):                     # n <= ~100: the loop is cheap next to the fit
        X[t] = x
        x = x @ At + Bu[t]
    return X @ C.T + u @ D.T


def observability_bases(omega, G, qs):
    """{q: (U, s)} for each number of block rows q in ``qs``: the left singular vectors
    and values of L22 (module notes), (q p, q p) and (q p,).

    One QR serves every q: with the block rows interleaved, [W_0; G_0; W_1; G_1; ...],
    the LQ factor of the first q blocks is the leading part L_q of the whole one (rows
    of a lower-triangular factorisation); permuting L_q's rows to the [W; G] order and
    factorising that small square matrix again, P L_q = L' Q', gives the LQ factor L'
    of [W_q; G_q] (Q' times the big orthonormal factor is still orthonormal)."""
    L, p, m = G.shape
    z = np.exp(1j * omega)
    qmax = max(qs)
    eye = np.eye(m)
    rows = []
    for i in range(qmax):
        zi = z ** i
        Wi = np.swapaxes(eye[None] * zi[:, None, None], 0, 1).reshape(m, L * m)
        Gi = np.swapaxes(G * zi[:, None, None], 0, 1).reshape(p, L * m)
        rows += [Wi, Gi]
    stacked = np.vstack(rows)
    stacked = np.hstack([stacked.real, stacked.imag])
    Lbig = np.linalg.qr(stacked.T, mode="r").T
    out = {}
    for q in qs:
        k = q * (m + p)
        blocks = np.arange(k).reshape(q, m + p)
        order = np.r_[blocks[:, :m].ravel(), blocks[:, m:].ravel()]
        Lq = np.linalg.qr(Lbig[:k, :k][order].T, mode="r").T
        U, sv, _ = np.linalg.svd(Lq[q * m:, q * m:], full_matrices=False)
        out[q] = (U, sv)
    return out


def observability_basis(omega, G, q):
    """(U, s) of :func:`observability_bases` for one q."""
    return observability_bases(omega, G, [q])[q]


def fit_ac(U, n, p):
    """A and C of order n from the observability basis U (module notes)."""
    obs = U[:, :n]
    C = obs[:p]
    A = np.linalg.lstsq(obs[:-p], obs[p:], rcond=None)[0]
    return A, C


def fit_bd(omega, G, A, C, weight=None):
    """B and D minimising the weighted error of the module notes, A and C fixed."""
    L, p, m = G.shape
    n = A.shape[0]
    CK = _left_resolvent(C, A, np.exp(1j * omega))                        # (L, p, n)
    M = np.concatenate([CK, np.broadcast_to(np.eye(p), (L, p, p))], axis=2)
    B, D = np.empty((n, m)), np.empty((p, m))
    for i in range(m):
        w = np.ones((L, p)) if weight is None else weight[:, :, i]
        Mi = (M * w[:, :, None]).reshape(L * p, n + p)
        ti = (G[:, :, i] * w).ravel()
        X = np.vstack([Mi.real, Mi.imag])
        scale = np.sqrt(np.sum(X * X, axis=0)) + 1e-300
        theta = np.linalg.lstsq(X / scale, np.r_[ti.real, ti.imag], rcond=None)[0] / scale
        B[:, i], D[:, i] = theta[:n], theta[n:]
    return B, D


def stabilized(A, C):
    """(A, C) with A's eigenvalues reflected into the unit circle (module notes); A and
    C unchanged when A is already stable within MAX_RADIUS."""
    lam, V = np.linalg.eig(A)
    r = np.abs(lam)
    if np.all(r < MAX_RADIUS):
        return A, C
    from scipy.linalg import cdf2rdf
    big = r > 1.0
    lam = lam.copy()
    lam[big] = 1.0 / np.conj(lam[big])
    r = np.abs(lam)
    near = r >= MAX_RADIUS
    lam[near] *= MAX_RADIUS / r[near] * (1 - 1e-9)
    # real modal form: x = Vr x', so A' = blockdiag(lam) and C' = C Vr
    wr, vr = cdf2rdf(lam, V)
    return wr, C @ vr


def fsid(omega: ArrayLike, G: ArrayLike, order: int, *, q: int | None = None,
         weight: ArrayLike | None = None, basis: tuple[Any, Any] | None = None) -> StateSpace:
    """A stable :class:`StateSpace` of ``order`` fitted to a frequency response (module
    notes: frequency-domain subspace identification).

    Parameters
    ----------
    omega : array_like
        (L,) angular frequencies of the lines, rad/sample.
    G : array_like
        (L, p, m) the frequency response on them.
    order : int
        The model's order (number of states), >= 1.
    q : int, optional
        Block rows (default order + 1).
    weight : array_like, optional
        (L, p, m) elementwise weights of the B, D fit (e.g. 1 / standard deviation).
    basis : tuple, optional
        A precomputed ``observability_basis`` of the same data (with q > order).

    Returns
    -------
    StateSpace
        The fitted model, its spectral radius below 1.

    Raises
    ------
    InvalidArgumentError
        An order that is not a positive integer, too few block rows or frequency lines.

    Examples
    --------
    >>> import numpy as np
    >>> from pihyst.dynamics import StateSpace, fsid
    >>> true = StateSpace([[0.5]], [[1.0]], [[1.0]], [[0.0]])
    >>> omega = np.linspace(0.1, 3.0, 20)
    >>> model = fsid(omega, true.response(omega), 1)
    >>> np.round(model.dc_gain(), 6)
    array([[2.]])
    """
    G = np.asarray(G)
    L, p, m = G.shape
    if not isinstance(order, (int, np.integer)) or order < 1:
        raise InvalidArgumentError(f"order must be a positive integer, not {order!r}")
    q = order + 1 if q is None else int(q)
    if basis is None:
        if q <= order:
            raise InvalidArgumentError(f"q = {q} block rows must exceed the order {order}")
        if 2 * L * m < q * (m + p):
            raise InvalidArgumentError(f"{L} frequency lines are too few for order {order} "
                                       f"(q = {q} block rows need {q * (m + p) // (2 * m) + 1})")
        basis = observability_basis(omega, G, q)
    U = basis[0]
    if U.shape[1] < order + p:
        raise InvalidArgumentError(f"order {order} needs more block rows than the basis has")
    A, C = fit_ac(U, order, p)
    A, C = stabilized(A, C)
    B, D = fit_bd(omega, G, A, C, weight)
    return StateSpace(A, B, C, D)
