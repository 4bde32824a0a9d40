"""Nonlinear least-squares refinement of a state-space model on its frequency response.

The model is put in modal form, one term per conjugate pole pair (lambda, Im > 0) and per
real pole:

    G(z) = sum_pairs [c b^T / (z - lambda) + conj(c) conj(b)^T / (z - conj(lambda))]
           + sum_real c b^T / (z - lambda) + D,

and all of it (poles, c, b, D) is fitted to the estimate G_k by Levenberg-Marquardt
(scipy.optimize.least_squares) on

    min sum_k || W_k o (G(z_k) - G_k) ||_F^2,

starting from the subspace estimate. Stability is built into the parametrisation: a
pair's pole is lambda = r exp(i phi) with r = MAX_RADIUS / (1 + exp(-rho)), a real pole
lambda = MAX_RADIUS tanh(sigma), so every iterate is stable. The Jacobian is analytic:
d/dlambda of c b^T / (z - lambda) is c b^T / (z - lambda)^2, and G is linear in c, b
(each separately) and D. The result is returned in real modal form, a pair's block being

    A = [[Re l, -Im l], [Im l, Re l]],  B = [Re b^T; Im b^T],  C = [2 Re c, -2 Im c].
"""

import numpy as np

from pihyst.dynamics._statespace import MAX_RADIUS, StateSpace

REAL_TOLERANCE = 1e-9   # |Im lambda| below this (relative to |lambda|): a real pole


def _modes(model):
    lam, V = np.linalg.eig(model.A)
    c, b = model.C @ V, np.linalg.solve(V, model.B)
    real = np.abs(lam.imag) <= REAL_TOLERANCE * np.maximum(np.abs(lam), 1e-300)
    pair = ~real & (lam.imag > 0)
    return (lam[pair], c[:, pair].T, b[pair]), (lam[real].real, c[:, real].real.T,
                                                 b[real].real)


def _pack(pairs, reals, D):
    lam, c, b = pairs
    r = np.clip(np.abs(lam) / MAX_RADIUS, 1e-12, 1 - 1e-12)
    rho = np.log(r / (1 - r))
    lr, cr, br = reals
    sigma = np.arctanh(np.clip(lr / MAX_RADIUS, -1 + 1e-12, 1 - 1e-12))
    return np.concatenate([rho, np.angle(lam), c.real.ravel(), c.imag.ravel(),
                           b.real.ravel(), b.imag.ravel(), sigma, cr.ravel(), br.ravel(),
                           D.ravel()])


class _Layout:
    def __init__(self, n_pairs, n_reals, p, m):
        self.shape = (n_pairs, n_reals, p, m)
        sizes = [n_pairs, n_pairs, n_pairs * p, n_pairs * p, n_pairs * m, n_pairs * m,
                 n_reals, n_reals * p, n_reals * m, p * m]
        self.edges = np.cumsum([0] + sizes)

    def split(self, theta):
        P, Rn, p, m = self.shape
        e = self.edges
        rho, phi = theta[e[0]:e[1]], theta[e[1]:e[2]]
        c = (theta[e[2]:e[3]] + 1j * theta[e[3]:e[4]]).reshape(P, p)
        b = (theta[e[4]:e[5]] + 1j * theta[e[5]:e[6]]).reshape(P, m)
        sigma = theta[e[6]:e[7]]
        cr, br = theta[e[7]:e[8]].reshape(Rn, p), theta[e[8]:e[9]].reshape(Rn, m)
        D = theta[e[9]:e[10]].reshape(p, m)
        return rho, phi, c, b, sigma, cr, br, D


def _poles(rho, phi, sigma):
    s = 1.0 / (1.0 + np.exp(-rho))
    r = MAX_RADIUS * s
    lam = r * np.exp(1j * phi)
    dlam_drho = MAX_RADIUS * s * (1 - s) * np.exp(1j * phi)
    t = np.tanh(sigma)
    return lam, dlam_drho, MAX_RADIUS * t, MAX_RADIUS * (1 - t * t)


def change_scales(layout, theta):
    """Per parameter, the size of a change that counts as one unit in the penalty of
    :func:`fit_modes`: a pole's radius in log-odds (already relative to 1 - r), its
    angle in units of 1 - r (its half-power bandwidth), a real pole in arctanh, each
    mode's c and b relative to their norm, D relative to its RMS."""
    P, Rn, p, m = layout.shape
    rho, phi, c, b, sigma, cr, br, D = layout.split(theta)
    lam, _, _, _ = _poles(rho, phi, sigma)
    tiny = 1e-12
    nc = np.maximum(np.linalg.norm(c, axis=1), tiny)
    nb = np.maximum(np.linalg.norm(b, axis=1), tiny)
    ncr = np.maximum(np.linalg.norm(cr, axis=1), tiny)
    nbr = np.maximum(np.linalg.norm(br, axis=1), tiny)
    return np.concatenate([np.ones(P), np.maximum(1 - np.abs(lam), tiny),
                           np.repeat(nc, p), np.repeat(nc, p), np.repeat(nb, m),
                           np.repeat(nb, m), np.ones(Rn), np.repeat(ncr, p),
                           np.repeat(nbr, m),
                           np.full(p * m, max(float(np.sqrt(np.mean(D ** 2))), tiny))])


def modal_response(layout, theta, z):
    """G(z_k) (L, p, m) of packed modal parameters ``theta`` at the points ``z`` (L,)."""
    rho, phi, c, b, sigma, cr, br, D = layout.split(theta)
    lam, _, lr, _ = _poles(rho, phi, sigma)
    T, Tc, Tr = 1 / (z[:, None] - lam), 1 / (z[:, None] - lam.conj()), 1 / (z[:, None] - lr)
    out = np.einsum("kq,qj,qi->kji", T, c, b) + np.einsum("kq,qj,qi->kji", Tc, c.conj(),
                                                            b.conj())
    return out + np.einsum("kq,qj,qi->kji", Tr, cr, br) + D


def modal_jacobian(layout, theta, z):
    """dG(z_k) / dtheta (L, p, m, n), complex, of :func:`modal_response`."""
    rho, phi, c, b, sigma, cr, br, D = layout.split(theta)
    lam, dl, lr, dlr = _poles(rho, phi, sigma)
    T, Tc, Tr = 1 / (z[:, None] - lam), 1 / (z[:, None] - lam.conj()), 1 / (z[:, None] - lr)
    P, Rn, p, m = layout.shape
    L = z.size
    cols = []
    # poles: d/dx [c b^T T + conj(c) conj(b)^T Tc] = c b^T T^2 s + conj(..) Tc^2 conj(s)
    for s in (dl, 1j * lam):                  # d lambda / d rho, d lambda / d phi
        cols.append(np.einsum("kq,qj,qi->kjiq", T ** 2 * s, c, b)
                    + np.einsum("kq,qj,qi->kjiq", Tc ** 2 * s.conj(), c.conj(), b.conj()))
    eye_p, eye_m = np.eye(p), np.eye(m)
    # c (real, imaginary parts): row j of the term, b^T T +- conj(b)^T Tc
    for s in (1.0, 1j):
        cols.append((s * np.einsum("kq,qi,jl->kjiql", T, b, eye_p)
                     + np.conj(s) * np.einsum("kq,qi,jl->kjiql", Tc, b.conj(), eye_p)
                     ).reshape(L, p, m, P * p))
    for s in (1.0, 1j):
        cols.append((s * np.einsum("kq,qj,il->kjiql", T, c, eye_m)
                     + np.conj(s) * np.einsum("kq,qj,il->kjiql", Tc, c.conj(), eye_m)
                     ).reshape(L, p, m, P * m))
    cols.append(np.einsum("kq,qj,qi->kjiq", Tr ** 2 * dlr, cr, br))
    cols.append(np.einsum("kq,qi,jl->kjiql", Tr, br, eye_p).reshape(L, p, m, Rn * p))
    cols.append(np.einsum("kq,qj,il->kjiql", Tr, cr, eye_m).reshape(L, p, m, Rn * m))
    cols.append(np.broadcast_to(np.einsum("jl,io->jilo", eye_p, eye_m).reshape(
        1, p, m, p * m), (L, p, m, p * m)))
    return np.concatenate(cols, axis=3)


def fit_modes(model, omega, G, weight=None, max_nfev=50, penalty=0.0):
    """Levenberg-Marquardt on the modal parameters of ``model`` (module notes).

    With ``penalty`` mu > 0 the criterion gains mu sum_j ((theta_j - theta0_j) / s_j)^2
    (s_j from :func:`change_scales` at the start, scaled by the start's error per
    parameter): the smallest change of the modes that explains ``G``.

    Returns ``(layout, theta0, theta, cost0, cost)``: the packing, the start and the
    fitted parameters, and the weighted squared error of ``model`` itself and of the
    fit (penalty left out); None when ``model`` has no modal form (defective or
    ill-sorted modes).
    """
    from scipy.optimize import least_squares

    G = np.asarray(G)
    L, p, m = G.shape
    W = np.ones(G.shape) if weight is None else np.asarray(weight, dtype=float)
    z = np.exp(1j * np.asarray(omega, dtype=float))
    pairs, reals = _modes(model)
    if 2 * pairs[0].size + reals[0].size != model.order:
        return None
    layout = _Layout(pairs[0].size, reals[0].size, p, m)
    theta0 = _pack(pairs, reals, model.D)
    cost0 = float(np.sum(np.abs(W * (model.response(omega) - G)) ** 2))
    # mu (cost0 / n) per unit change: a change of one unit in every parameter costs
    # mu times the start's own error
    prior = (np.sqrt(penalty * cost0 / theta0.size) / change_scales(layout, theta0)
             if penalty > 0 else None)

    def residual(theta):
        e = (W * (modal_response(layout, theta, z) - G)).ravel()
        r = np.r_[e.real, e.imag]
        return r if prior is None else np.r_[r, prior * (theta - theta0)]

    def jacobian(theta):
        J = (modal_jacobian(layout, theta, z) * W[..., None]).reshape(L * p * m, -1)
        J = np.vstack([J.real, J.imag])
        return J if prior is None else np.vstack([J, np.diag(prior)])

    # cost0, above, is judged against the model itself (its modal form may round
    # differently)
    res = least_squares(residual, theta0, jac=jacobian, method="lm", max_nfev=max_nfev)
    e = (W * (modal_response(layout, res.x, z) - G)).ravel()
    return layout, theta0, res.x, cost0, float(np.sum(np.abs(e) ** 2))


def modal_parameters(layout, theta):
    """(pair poles, pair c, pair b, real poles, real c, real b, D) of packed ``theta``."""
    rho, phi, c, b, sigma, cr, br, D = layout.split(theta)
    lam, _, lr, _ = _poles(rho, phi, sigma)
    return lam, c, b, lr, cr, br, D


def real_modal_state_space(lam, c, b, lr, cr, br, D):
    """The real modal-form :class:`StateSpace` of modal parameters (module notes)."""
    p, m = D.shape
    n = 2 * lam.size + lr.size
    A, B, C = np.zeros((n, n)), np.zeros((n, m)), np.zeros((p, n))
    for q in range(lam.size):
        k = 2 * q
        A[k:k + 2, k:k + 2] = [[lam[q].real, -lam[q].imag], [lam[q].imag, lam[q].real]]
        B[k], B[k + 1] = b[q].real, b[q].imag
        C[:, k], C[:, k + 1] = 2 * c[q].real, -2 * c[q].imag
    k0 = 2 * lam.size
    for q in range(lr.size):
        A[k0 + q, k0 + q] = lr[q]
        B[k0 + q], C[:, k0 + q] = br[q], cr[q]
    return StateSpace(A, B, C, D)


def refine(model, omega, G, weight=None, max_nfev=50):
    """The refined :class:`StateSpace` (module notes), or ``model`` itself when the
    refinement does not lower the weighted error."""
    fitted = fit_modes(model, omega, G, weight, max_nfev)
    if fitted is None:
        return model
    layout, _, theta, cost0, cost = fitted
    if not cost < cost0:
        return model
    return real_modal_state_space(*modal_parameters(layout, theta))
