"""Linear time-invariant parts of the beam as sums of first-order modes.

A transfer function with simple poles p_j and residues r_j plus a direct term D,

    G(s) = D + sum_j r_j / (s - p_j),

is run as modal states x_j' = p_j x_j + h with output y = D h + Re(sum_j r_j x_j) (a
complex-conjugate pair is one complex mode with its residue doubled). Sample n holds the
input h[n] over (t[n-1], t[n]], which gives the exact update

    x_j[n] = lambda_j x_j[n-1] + (lambda_j - 1) / p_j h[n],   lambda_j = exp(p_j dt_n),

for any spacing dt_n (runs of equal spacing go through scipy.signal.lfilter).
"""

import numpy as np

from pihyst.exceptions import InvalidArgumentError


def _lfilter():
    # lazy: importing scipy.signal takes about 0.4 s, too long for `pihyst --help`
    from scipy.signal import lfilter
    return lfilter


class ModalFilter:
    """G(s) = direct + sum_j residues[j] / (s - poles[j]); see the module docstring.

    Parameters
    ----------
    poles, residues : sequences of complex
        Stable poles (negative real part, 1/s) and their residues.
    direct : float
        Direct feed-through D.

    Examples
    --------
    >>> import numpy as np
    >>> lag = ModalFilter([-1.0], [1.0])        # 1 / (s + 1), time constant 1 s
    >>> lag.rest(0.0)
    >>> t = np.arange(0.0, 5.01, 0.01)
    >>> y = lag.run(np.ones(t.size), t)
    >>> round(float(y[100]), 4)                 # 1 - exp(-1) at t = 1 s
    0.6321
    """

    def __init__(self, poles, residues, direct=0.0):
        self.poles = np.array(poles, dtype=complex)
        self.residues = np.array(residues, dtype=complex)
        if self.poles.shape != self.residues.shape or self.poles.ndim != 1:
            raise InvalidArgumentError("one residue per pole")
        if np.any(self.poles.real >= 0):
            raise InvalidArgumentError("poles must have negative real parts (a stable filter)")
        self.direct = float(direct)
        self._x = np.zeros(self.poles.size, dtype=complex)
        self._t = None

    @property
    def dc_gain(self):
        """G(0) = D - sum_j r_j / p_j (real part)."""
        return float((self.direct - np.sum(self.residues / self.poles)).real)

    def rest(self, h):
        """Equilibrium for the constant input h (x_j = -h / p_j); time restarts."""
        self._x = -float(h) / self.poles
        self._t = None

    @property
    def state(self):
        """(modal states, time of the last sample or None)."""
        return (self._x.copy(), self._t)

    @state.setter
    def state(self, value):
        self._x = np.array(value[0], dtype=complex)
        self._t = value[1]

    def run(self, h, t):
        """Output for the input samples ``h`` at times ``t`` (s, non-decreasing and after
        the previous call's last time; the first sample after :meth:`rest` has dt = 0)."""
        h = np.asarray(h, dtype=float)
        t = np.asarray(t, dtype=float)
        n = h.size
        if n == 0:
            return np.empty(0)
        t_prev = t[0] if self._t is None else self._t
        dt = np.diff(np.concatenate(([t_prev], t)))
        # group runs of equal spacing (to 1 ns) so that each goes through one lfilter
        key = np.round(dt, 9)
        cuts = np.concatenate(([0], np.flatnonzero(np.diff(key)) + 1, [n]))
        y = self.direct * h
        modes = np.empty((self.poles.size, n), dtype=complex)
        x = self._x.copy()
        for i0, i1 in zip(cuts[:-1], cuts[1:]):
            step = float(np.mean(dt[i0:i1]))
            for j, p in enumerate(self.poles):
                lam = np.exp(p * step)
                gain = (lam - 1) / p if step > 0 else 0.0
                # x[n] = lam x[n-1] + gain h[n]  (lfilter: b = [gain], a = [1, -lam])
                seg, _ = _lfilter()([gain], [1.0, -lam], h[i0:i1], zi=[lam * x[j]])
                modes[j, i0:i1] = seg
                x[j] = seg[-1]
        self._x = x
        self._t = float(t[-1])
        return y + (self.residues @ modes).real


def creep_filter(per_decade, tau_min=0.1, tau_max=3000.0):
    """Logarithmic creep: y = h + sum_i c_i z_i with first-order lags z_i of h.

    Time constants at half-decade spacing from ``tau_min`` to ``tau_max`` with
    c_i = per_decade / 2, so that after a step Delta h the output grows by about
    ``per_decade`` * Delta h per decade of time in between (1 - exp(-t/tau) summed over
    log-spaced tau approximates log10 t).
    """
    taus = np.logspace(np.log10(tau_min), np.log10(tau_max),
                       int(round(2 * np.log10(tau_max / tau_min))) + 1)
    c = per_decade / 2.0
    # z_i' = (h - z_i) / tau_i: pole -1/tau_i, residue c_i / tau_i
    return ModalFilter(-1.0 / taus, c / taus, direct=1.0)


def beam_filter(resonance_hz, damping):
    """Second-order beam: G(s) = w^2 / (s^2 + 2 zeta w s + w^2), unit static gain."""
    w = 2 * np.pi * float(resonance_hz)
    z = float(damping)
    if not (w > 0 and 0 < z < 1):
        raise InvalidArgumentError("beam dynamics need resonance_hz > 0 and 0 < damping < 1")
    p = complex(-z * w, w * np.sqrt(1 - z * z))
    # G = r / (s - p) + conj(r) / (s - conj(p)), r = w^2 / (p - conj(p)); one complex mode
    # with residue 2 r gives the same real output.
    r = w * w / (p - p.conjugate())
    return ModalFilter([p], [2 * r])


def modes_filter(modes):
    """Several lightly damped modes in parallel, unit static gain overall:

        G(s) = sum_i g_i w_i^2 / (s^2 + 2 zeta_i w_i s + w_i^2),   sum_i g_i = 1,

    ``modes``: (resonance_hz, damping, share g_i) per mode (the shares are normalised to
    sum 1). One complex modal state per mode, as :func:`beam_filter`."""
    modes = [tuple(float(v) for v in m) for m in modes]
    if not modes or any(len(m) != 3 for m in modes):
        raise InvalidArgumentError("modes: one or more (resonance_hz, damping, share)")
    total = sum(m[2] for m in modes)
    if not all(m[2] > 0 for m in modes):
        raise InvalidArgumentError("modes: every share must be > 0")
    poles, residues = [], []
    for hz, zeta, share in modes:
        one = beam_filter(hz, zeta)
        poles.append(one.poles[0])
        residues.append(one.residues[0] * share / total)
    return ModalFilter(poles, residues)
