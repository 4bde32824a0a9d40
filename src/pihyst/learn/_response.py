"""The plant's response per harmonic of the period, estimated from the trials.

Every trial j gives the spectra H_j = rfft(h_j) of the hysteresis output (the model's,
for the voltages sent) and Y_j = rfft(y_j) of the measured period. On each line k

    Y_jk = G_k H_jk + D_k + N_jk,       N_jk the sensor noise, E|N_jk|^2 = N sigma^2,

and G_k is estimated by least squares over the trials so far:

- from the changes: each trial j after the first was built from an earlier one p(j)
  (the best so far), and G_k = sum_j conj(dH_jk) dY_jk / sum_j |dH_jk|^2 with
  dH_jk = H_jk - H_p(j)k, dY_jk = Y_jk - Y_p(j)k: the local (incremental) gain the
  learning needs, blind to D_k as long as a change does not move it, variance
  2 N sigma^2 / sum_j |dH_jk|^2 (nothing is known before a trial changes the line); its
  relative deviation is judged against min(|G_k|, the static gain), so that a line the
  trials hardly changed is never trusted for a large ratio of what the model misses to
  that change;
- until that is trusted, on the lines the desired trajectory carries (|R_k| above a
  millionth of its largest line, the DC line excepted), where H is large and what the
  model misses is small beside it, through the origin:
  G_k = sum_j conj(H_jk) Y_jk / sum_j |H_jk|^2, variance N sigma^2 / sum_j |H_jk|^2 (a
  secant gain: with hysteresis the local gain differs from it, and the learning is
  slower until the local one is known).

A line's estimate is trusted when its relative standard deviation is at most
``TRUST_REL_STD`` (then the phase is known to about 17 degrees, well inside the 90 degrees
the learning law tolerates, docs/theory/learning.md). The sensor noise sigma is
estimated from the measured spectrum's upper quarter, where lightly damped dynamics
pass almost nothing: for white noise |N_k|^2 is exponential with mean N sigma^2, whose
median is N sigma^2 ln 2.
"""

import numpy as np

TRUST_REL_STD = 0.3
REFERENCE_LINE = 1e-6      # a line of the desired trajectory: |R_k| > this * max |R|


def reference_lines(desired):
    """Boolean mask of the rfft lines the desired trajectory carries (DC excepted)."""
    R = np.abs(np.fft.rfft(desired))
    lines = R > REFERENCE_LINE * max(R[1:].max() if R.size > 1 else 0.0, 1e-300)
    lines[0] = False
    return lines


def noise_sigma(y_period, floor=0.0):
    """Sensor noise standard deviation from the upper quarter of a measured period's
    spectrum (module notes), at least ``floor``."""
    Y = np.fft.rfft(y_period)
    n = np.asarray(y_period).size
    upper = np.abs(Y[3 * Y.size // 4:-1] if n % 2 == 0 else Y[3 * Y.size // 4:]) ** 2
    if upper.size == 0:
        return float(floor)
    return max(float(np.sqrt(np.median(upper) / (n * np.log(2)))), float(floor))


class ResponseEstimate:
    """G_k from the trials (module notes); :meth:`add` one trial, then read
    :attr:`gain` and :attr:`trusted`."""

    def __init__(self, desired):
        self.n = int(np.asarray(desired).size)
        self.on_reference = reference_lines(desired)
        self._H, self._Y, self._parent = [], [], []
        self.sigma = 0.0

    @property
    def trials(self):
        return len(self._H)

    def add(self, h, y, sigma, parent=None):
        """One trial: hysteresis output ``h`` and measurement ``y`` of a period, the index
        of the trial it was built from (None for the first); the noise estimate ``sigma``
        (um) to judge the estimates by."""
        self._H.append(np.fft.rfft(h))
        self._Y.append(np.fft.rfft(y))
        self._parent.append(parent)
        self.sigma = float(sigma)

    def estimate(self):
        """(G, relative standard deviation) per line; NaN where nothing is known."""
        H, Y = np.array(self._H), np.array(self._Y)
        noise_var = self.n * self.sigma ** 2
        through_origin = np.sum(np.abs(H) ** 2, axis=0)
        pairs = [(j, p) for j, p in enumerate(self._parent) if p is not None]
        dH = np.array([H[j] - H[p] for j, p in pairs]).reshape(-1, H.shape[1])
        dY = np.array([Y[j] - Y[p] for j, p in pairs]).reshape(-1, H.shape[1])
        spread = np.sum(np.abs(dH) ** 2, axis=0)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            g_origin = np.sum(np.conj(H) * Y, axis=0) / through_origin
            rel_origin = np.sqrt(noise_var / through_origin) / np.abs(g_origin)
            g_local = np.sum(np.conj(dH) * dY, axis=0) / spread
            # judged against at most the static gain: a large estimate from a tiny change
            # is what the model misses moving, not a resonance
            rel_local = np.sqrt(2 * noise_var / spread) / np.minimum(np.abs(g_local),
                                                                     self.reference_gain())
        # the local (incremental) gain once the trials tell it, else through the origin
        # on the desired trajectory's lines
        local = np.nan_to_num(rel_local, nan=np.inf) <= TRUST_REL_STD
        origin = self.on_reference & ~local
        g = np.where(local, g_local, np.where(origin, g_origin, g_local))
        rel = np.where(local, rel_local, np.where(origin, rel_origin, rel_local))
        energy = np.where(origin, through_origin, spread)
        known = np.isfinite(g) & (energy > 0)
        g = np.where(known, g, np.nan)
        rel = np.where(known, rel, np.inf)
        return g, rel

    def reference_gain(self):
        """|G| through the origin on the lowest line of the desired trajectory (1 when
        there is none): the static gain the DC line, the probe and the trust in an
        estimate are measured by."""
        lines = np.flatnonzero(self.on_reference)
        if not lines.size:
            return 1.0
        H = np.array([h[lines[0]] for h in self._H])
        Y = np.array([y[lines[0]] for y in self._Y])
        energy = float(np.sum(np.abs(H) ** 2))
        with np.errstate(over="ignore", invalid="ignore"):
            gain = float(abs(np.sum(np.conj(H) * Y)) / energy) if energy > 0 else 1.0
        return gain if np.isfinite(gain) else 1.0

    def trusted(self, rel):
        return rel <= TRUST_REL_STD
