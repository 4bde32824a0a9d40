"""Discrete linear dynamics: MISO output-error models fitted by least squares.

For one output y and input columns v_c (c = 1..C) the model is

    A(q) y[t] = sum_c B_c(q) v_c[t],
    A(q) = 1 + a_1 q^-1 + ... + a_na q^-na,  B_c(q) = b_c0 + b_c1 q^-1 + ... + b_c,nb-1 q^-(nb-1)

(q^-1 the delay). The ARX estimate minimizes the equation error A y - sum B_c v_c by
linear least squares; the Steiglitz-McBride iterations then refit the same problem on
y and v prefiltered by 1 / A of the previous estimate, which moves the estimate towards
the output-error (simulation-error) optimum. Poles outside the unit circle are reflected
inside (|p| -> 1/|p|, the same amplitude response up to a gain) so the model is stable.
Several experiments (records) are fitted together; the first max(na, nb) samples of
each only start the regressors.
"""

import numpy as np


def _signal():
    # lazy: importing scipy.signal takes about 0.4 s
    import scipy.signal
    return scipy.signal


def lagged(x, n, start=0):
    """[x[t - start], x[t - start - 1], ..., x[t - start - n + 1]] for every t (zeros
    before the record)."""
    out = np.zeros((x.size, n))
    for k in range(n):
        s = start + k
        out[s:, k] = x[:x.size - s] if s else x
    return out


def stabilized(a):
    """A(q) with its roots outside the unit circle reflected inside."""
    roots = np.roots(a)
    big = np.abs(roots) >= 1.0
    if not np.any(big):
        return np.asarray(a, dtype=float)
    roots[big] = 1.0 / np.conj(roots[big])
    return np.real(np.poly(roots))


def _design(records, na, nb, a_filter):
    sig = _signal()
    rows, target = [], []
    skip = max(na, nb)
    for v, y in records:
        if a_filter is not None:
            y = sig.lfilter([1.0], a_filter, y)
            v = sig.lfilter([1.0], a_filter, v, axis=0)
        cols = [-lagged(y, na, 1)] + [lagged(v[:, c], nb) for c in range(v.shape[1])]
        rows.append(np.hstack(cols)[skip:])
        target.append(y[skip:])
    return np.vstack(rows), np.concatenate(target)


def fit_oe(records, na, nb, iterations=5, ridge=1e-9):
    """(A, B) of the model of the module notes; B has one row per input column.

    ``records``: list of (v, y) with v of shape (N, C) and y of length N.
    """
    a_prev = None
    C = records[0][0].shape[1]
    for _ in range(iterations + 1):
        X, t = _design(records, na, nb, a_prev)
        scale = np.sqrt(np.mean(X * X, axis=0)) + 1e-300
        G = (X / scale).T @ (X / scale)
        G[np.diag_indices_from(G)] += ridge * np.trace(G) / G.shape[0]
        theta = np.linalg.solve(G, (X / scale).T @ t) / scale
        a = stabilized(np.r_[1.0, theta[:na]])
        b = theta[na:].reshape(C, nb)
        a_prev = a
    return a, b


def simulate(a, b, v):
    """y = sum_c B_c / A v_c from rest."""
    sig = _signal()
    return sum(sig.lfilter(b[c], a, v[:, c]) for c in range(v.shape[1]))


# ----------------------------------------------------------------------------- periodic
# For a record in periodic steady state (the last period of a periodic input, after the
# transient has died out) the model holds line by line of the period's DFT:
#
#     Y(w_k) = sum_c B_c(z_k) / A(z_k) V_c(w_k),     z_k = exp(-i w_k)  (q^-1 on line k),
#
# so the output-error criterion sum_k |Y - sum_c (B_c / A) V_c|^2 needs no transient and
# no time-domain simulation. It is minimized by Sanathanan-Koerner iterations (the
# equation error A Y - sum_c B_c V_c weighted by 1 / |A_prev|, linear least squares on
# real and imaginary parts), the frequency-domain twin of Steiglitz-McBride.

def powers(period, n):
    """z_k^l = exp(-i w_k l) for the rfft lines k of a period and l = 0..n-1."""
    w = 2 * np.pi * np.arange(period // 2 + 1) / period
    return np.exp(-1j * np.outer(w, np.arange(n)))


def _used_lines(spectra, Z):
    """Per spectrum (Zs, V, Y) on the lines where V or Y is not zero: a line with both
    zero adds nothing to either criterion (its residual and its derivatives are 0), and
    records placed on a common period fill few of its lines."""
    out = []
    for V, Y in spectra:
        used = np.flatnonzero((Y != 0) | np.any(V != 0, axis=1))
        out.append((Z[used], V[used], Y[used]))
    return out


def fit_oe_periodic(spectra, na, nb, period, iterations=10, ridge=1e-9):
    """(A, B) from ``spectra``: list of (V, Y) rfft's of one period, V (L, C), Y (L,)."""
    Z = powers(period, max(na + 1, nb))
    C = spectra[0][0].shape[1]
    lines = _used_lines(spectra, Z)
    n_lines = sum(Y.size for _, Y in spectra)     # the scale's mean runs over every line
    a = np.r_[1.0, np.zeros(na)]
    weights = [np.ones(Y.size) for _, _, Y in lines]
    for _ in range(iterations + 1):
        rows, target = [], []
        for (Zs, V, Y), weight in zip(lines, weights):
            # A Y - sum B V = 0:  sum_l a_l z^l Y - sum_c sum_l b_cl z^l V_c = -Y
            cols = [Zs[:, 1:na + 1] * Y[:, None]] + [-Zs[:, :nb] * V[:, c:c + 1]
                                                      for c in range(C)]
            M = np.hstack(cols) * weight[:, None]
            rows += [M.real, M.imag]
            target += [(-Y * weight).real, (-Y * weight).imag]
        X, t = np.vstack(rows), np.concatenate(target)
        scale = np.sqrt(np.sum(X * X, axis=0) / (2 * n_lines)) + 1e-300
        G = (X / scale).T @ (X / scale)
        G[np.diag_indices_from(G)] += ridge * np.trace(G) / G.shape[0]
        theta = np.linalg.solve(G, (X / scale).T @ t) / scale
        a = stabilized(np.r_[1.0, theta[:na]])
        b = theta[na:].reshape(C, nb)
        weights = [1.0 / np.maximum(np.abs(Zs[:, :na + 1] @ a), 1e-12)
                   for Zs, _, _ in lines]
    return _refine_periodic(lines, a, b)


def _refine_periodic(lines, a, b):
    """Gauss-Newton (Levenberg-Marquardt) on the output-error criterion itself, from the
    Sanathanan-Koerner estimate; with e = Y - sum_c (B_c / A) V_c and Yh = sum_c B_c V_c / A,
    de/db_cl = -z^l V_c / A and de/da_l = z^l Yh / A. Kept only if it lowers the cost
    and A stays stable. ``lines``: per spectrum (Z, V, Y) on its used lines."""
    from scipy.optimize import least_squares
    na, (C, nb) = a.size - 1, b.shape
    Z = np.vstack([Zs for Zs, _, _ in lines])
    V = np.vstack([Vs for _, Vs, _ in lines])
    Y = np.concatenate([Ys for _, _, Ys in lines])
    Za, Zb = Z[:, 1:na + 1], Z[:, :nb]

    def unpack(theta):
        return np.r_[1.0, theta[:na]], theta[na:].reshape(C, nb)

    def parts(theta):
        aa, bb = unpack(theta)
        A = Z[:, :na + 1] @ aa
        Bz = Zb @ bb.T                                   # (L, C)
        return A, Bz

    def residual(theta):
        A, Bz = parts(theta)
        e = Y - np.sum(Bz * V, axis=1) / A
        return np.r_[e.real, e.imag]

    def jacobian(theta):
        A, Bz = parts(theta)
        yh = np.sum(Bz * V, axis=1) / A
        ja = Za * (yh / A)[:, None]
        jb = np.hstack([-Zb * (V[:, c] / A)[:, None] for c in range(C)])
        J = np.hstack([ja, jb])
        return np.vstack([J.real, J.imag])

    theta0 = np.r_[a[1:], b.ravel()]
    cost0 = float(np.sum(residual(theta0) ** 2))
    res = least_squares(residual, theta0, jac=jacobian, method="lm", max_nfev=200 * theta0.size)
    a1, b1 = unpack(res.x)
    if 2 * res.cost < cost0 and np.all(np.abs(np.roots(a1)) < 1.0):
        return a1, b1
    return a, b


def response(a, b, period):
    """B_c(z_k) / A(z_k) on the rfft lines of a period: (L, C)."""
    Z = powers(period, max(a.size, b.shape[1]))
    return (Z[:, :b.shape[1]] @ b.T) / (Z[:, :a.size] @ a)[:, None]
