"""Compensation of a single-input single-output Hammerstein model: a stable inverse of
the dynamics, then the exact inverse of the hysteresis (docs/theory/hammerstein.md).

With y = G(q) h, G = q^-d B_s(q^-1) B_u(q^-1) / A(q^-1) (the zeros of B split into
those inside the unit circle, B_s with B's leading coefficient, and the others, B_u
monic of degree n_u), the zero-phase error tracking prefilter

    h_d[t] = A(q^-1) B_u*(q^-1) / (B_s(q^-1) B_u(1)^2) r[t + d + n_u],

with B_u*(q^-1) = q^-n_u B_u(q) (B_u's coefficients reversed), makes
G h_d = B_u(q^-1) B_u(q) / B_u(1)^2 r: zero phase, unit static gain, exact where B has
no zeros outside the unit circle. It looks d + n_u samples ahead, so it needs the
trajectory in advance (offline, or with that much preview); the trajectory is held at
its ends. The hysteresis output h_d is then inverted by :func:`pihyst.compensate`, whose
voltage and slew limits hold for every output whatever h_d is.

For a periodic trajectory (one period of N samples, repeated) the stable inverse needs no
approximation: on every harmonic k of the period (rfft line, z_k = exp(2 pi i k / N))

    H_d(k) = R(k) / G(z_k),

the non-causal inverse of the unstable zeros being as periodic as the rest (the whole
period is the preview). Lines where |G| is below ``1e-9`` of its largest value (a zero
on the unit circle) are left out.

A square MIMO :class:`StateSpaceHammerstein` (as many inputs as outputs) is compensated
the same way for a periodic trajectory of all outputs, R(k) a vector per line:

    H_d(k) = G(z_k)^-1 R(k)       (least squares where G(z_k) is singular),

then each input's hysteresis inverted on its own (its own limits and slew).
"""

import numpy as np

from pihyst.exceptions import InvalidArgumentError
from pihyst.inverse import compensate

ZERO_TOLERANCE = 1e-12   # leading coefficients of B below this (relative): pure delay


def _lfilter():
    from scipy.signal import lfilter
    return lfilter


def zpetc(a, b, r, settle=None):
    """h_d of the module notes for the reference r (SISO: b a 1-D array)."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float).ravel()
    r = np.asarray(r, dtype=float)
    big = np.flatnonzero(np.abs(b) > ZERO_TOLERANCE * np.abs(b).max())
    d, c = int(big[0]), b[big[0]:big[-1] + 1]
    zeros = np.roots(c) if c.size > 1 else np.zeros(0)
    unstable = np.abs(zeros) >= 1.0
    bs = c[0] * np.atleast_1d(np.real(np.poly(zeros[~unstable])))
    bu = np.atleast_1d(np.real(np.poly(zeros[unstable])))
    nu = bu.size - 1
    lead = d + nu
    # the trajectory held at its ends: before the start (rest) and past the end
    pre = r.size if settle is None else int(settle)
    ext = np.r_[np.full(pre, r[0]), r, np.full(lead, r[-1])]
    h = _lfilter()(np.convolve(a, bu[::-1]), bs, ext) / bu.sum() ** 2
    return h[pre + lead:pre + lead + r.size]


def periodic_inverse_dynamics(a, b, r):
    """H_d of the module notes for one period ``r`` of a periodic reference (SISO)."""
    from pihyst.dynamics._linear import response
    r = np.asarray(r, dtype=float)
    G = response(np.asarray(a, dtype=float), np.atleast_2d(np.asarray(b, dtype=float)),
                 r.size)[:, 0]
    R = np.fft.rfft(r)
    usable = np.abs(G) > 1e-9 * np.abs(G).max()
    H = np.where(usable, R / np.where(usable, G, 1.0), 0.0)
    return np.fft.irfft(H, r.size)


def periodic_inverse_mimo(model, r):
    """H_d of the module notes for one period ``r`` (N, p) of all outputs of a square
    state-space Hammerstein model: (N, m)."""
    r = np.asarray(r, dtype=float)
    R = np.fft.rfft(r, axis=0)
    w = 2 * np.pi * np.arange(R.shape[0]) / r.shape[0]
    G = model.dynamics.response(w)
    H = np.stack([np.linalg.lstsq(G[k], R[k], rcond=None)[0] for k in range(R.shape[0])])
    return np.fft.irfft(H, n=r.shape[0], axis=0)


def _per_input(value, m, name):
    """``value`` (None, one number or one per input) as a list of m."""
    if value is None:
        return [None] * m
    values = np.atleast_1d(np.asarray(value, dtype=float))
    if values.size == 1:
        values = np.repeat(values, m)
    if values.shape != (m,):
        raise InvalidArgumentError(f"{name}: one value or one per input ({m}), got "
                                   f"{values.size}")
    return [float(v) for v in values]


def compensate_mimo(model, desired, *, u_min=None, u_max=None, slew_rate=None,
                    sample_period=None):
    """Voltages (N, m) that make a square :class:`StateSpaceHammerstein` follow one period
    ``desired`` (N, p) of a repeated trajectory: the dynamics inverted per harmonic, then
    each input's hysteresis inverted over two periods (the second returned), within its
    limits and slew (``u_min``, ``u_max``, ``slew_rate`` in V/s at ``sample_period`` s:
    one value or one per input).
    Returns (voltage, h_desired, results of :func:`pihyst.compensate` per input)."""
    m, p = model.n_inputs, model.n_outputs
    if m != p:
        raise InvalidArgumentError(f"compensate_mimo needs as many inputs as outputs, got "
                                   f"{m} input(s) and {p} output(s)")
    desired = np.asarray(desired, dtype=float)
    if desired.ndim != 2 or desired.shape[1] != p or desired.shape[0] < 2:
        raise InvalidArgumentError(f"desired must be (N, {p}): one column per output, got "
                                   f"shape {desired.shape}")
    lows, highs = _per_input(u_min, m, "u_min"), _per_input(u_max, m, "u_max")
    slews = _per_input(slew_rate, m, "slew_rate")
    h_d = periodic_inverse_mimo(model, desired)
    n = desired.shape[0]
    results = [compensate(H, np.tile(h_d[:, i], 2), u_min=lows[i], u_max=highs[i],
                          slew_rate=slews[i], sample_period=sample_period)
               for i, H in enumerate(model.hysteresis)]
    voltage = np.column_stack([res.voltage[n:] for res in results])
    return voltage, h_d, results


def compensate_hammerstein(model, desired, *, u_min=None, u_max=None, slew_rate=None,
                           sample_period=None, periodic=False):
    """Voltages that make a SISO :class:`HammersteinModel` follow ``desired``: the
    ZPETC prefilter (``periodic``: ``desired`` is one period of a repeated trajectory,
    inverted exactly per harmonic), then the hysteresis inverse from the hysteresis
    model's initial state (``periodic``: run over two periods, the second returned, from
    which the hysteresis memory repeats); ``slew_rate`` in V/s at ``sample_period`` s, as
    for :func:`pihyst.compensate`. Returns (voltage, h_desired, result of
    :func:`pihyst.compensate`)."""
    if model.n_inputs != 1 or model.n_outputs != 1:
        raise InvalidArgumentError(f"compensate_hammerstein needs a single-input "
                                   f"single-output model, got {model.n_inputs} input(s) and "
                                   f"{model.n_outputs} output(s)")
    H = model.hysteresis[0]
    if not periodic:
        h_d = zpetc(model.a[0], model.b[0][0], desired)
        res = compensate(H, h_d, u_min=u_min, u_max=u_max, slew_rate=slew_rate,
                         sample_period=sample_period)
        return res.voltage, h_d, res
    desired = np.asarray(desired, dtype=float)
    h_d = periodic_inverse_dynamics(model.a[0], model.b[0][0], desired)
    res = compensate(H, np.tile(h_d, 2), u_min=u_min, u_max=u_max, slew_rate=slew_rate,
                     sample_period=sample_period)
    return res.voltage[h_d.size:], h_d, res
