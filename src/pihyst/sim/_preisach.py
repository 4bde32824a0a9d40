"""Preisach hysteresis with an asymmetric exponential density and a reversible part.

Normalised input x = u / u_max in [0, 1], warped by a monotone map (to shape the loop)

    v = x - kappa sin(2 pi x) / (2 pi),          0 <= kappa < 1,

drives a Preisach model of relays gamma_{alpha,beta} in {0, 1} (on when v >= alpha, off when
v <= beta, 0 <= beta <= alpha <= 1) with density

    mu(alpha, beta) = sum_j A_j exp(p_j alpha + q_j beta)        (A_j >= 0, um),

which is asymmetric unless p_j = -q_j. The output adds a reversible (anhysteretic) part:

    H(u) = c_1 x + c_2 x^2 + c_3 x^3 + integral of mu * gamma over the Preisach triangle.

The Preisach integral is evaluated exactly through the memory (reversal) stack: rising
from the last minimum m the output is P(m) + T(v, m), falling from the last maximum M it
is P(M) - T(M, v), where T(a, b) is the density's mass on the triangle
b <= beta <= alpha <= a; a reversal pushes the turning point, passing an older extremum
pops it (wiping-out). Each sample costs O(1) and monotone runs are vectorised.

Rest state: u = 0 after a full 0 -> u_max -> 0 cycle, which switches every relay off
(P = 0, and the major loop closes at the origin).
"""

import numpy as np

from pihyst.exceptions import InvalidArgumentError
from pihyst.sim._runs import checked_input, monotone_runs


def _ramp_integral(c, d):
    """E(c, d) = integral_0^d exp(c s) ds = d exprel(c d) (exact also for c = 0)."""
    from scipy.special import exprel  # lazy, like every SciPy import of pihyst.sim

    return d * exprel(c * d)


class Preisach:
    """Preisach model plus reversible part; see the module docstring.

    Parameters
    ----------
    u_max : float
        Input range is [0, u_max] (V); the Preisach plane covers it exactly.
    terms : sequence of (A, p, q)
        Density terms A exp(p alpha + q beta) in normalised coordinates; A >= 0 (um).
    reversible : sequence of float
        (c_1, c_2, ...): reversible part sum_k c_k x^k (um); must be non-decreasing.
    warp : float
        kappa of the input warp, in [0, 1).

    Examples
    --------
    >>> import numpy as np
    >>> h = Preisach(150.0, [(20.0, 1.0, -1.0)], reversible=(10.0,))
    >>> u = np.r_[np.linspace(0, 150, 151), np.linspace(149, 0, 150)]
    >>> y = h.run(u)
    >>> bool(y[75] < y[-76]), bool(abs(y[-1]) < 1e-12)  # falling branch above; closes at 0
    (True, True)
    """

    def __init__(self, u_max, terms, reversible=(), warp=0.0):
        self.u_max = float(u_max)
        if not (np.isfinite(self.u_max) and self.u_max > 0):
            raise InvalidArgumentError(f"u_max must be a positive number, got {u_max}")
        terms = np.array(terms, dtype=float).reshape(-1, 3)
        if not np.all(np.isfinite(terms)) or np.any(terms[:, 0] < 0):
            raise InvalidArgumentError("density terms (A, p, q) must be finite with A >= 0")
        self.terms = terms
        self.reversible = np.array(reversible, dtype=float)
        x = np.linspace(0.0, 1.0, 1001)
        if self.reversible.size and np.any(np.diff(self._reversible(x)) < 0):
            raise InvalidArgumentError("the reversible part must be non-decreasing on [0, u_max]")
        self.warp = float(warp)
        if not 0.0 <= self.warp < 1.0:
            raise InvalidArgumentError(f"warp must be in [0, 1), got {warp}")
        self.reset()

    # ------------------------------------------------------------- formulas
    def triangle_mass(self, a, b):
        """T(a, b): density mass on b <= beta <= alpha <= a (0 where a <= b).

        With d = a - b, for one term: T = A exp((p + q) b) tau(d) where
        tau(d) = integral_0^d exp(q s) integral_s^d exp(p s') ds' ds
               = [exp(p d) E(q, d) - E(p + q, d)] / p = [E(p + q, d) - E(p, d)] / q;
        the form with the larger divisor is used (both are exact)."""
        a = np.asarray(a, dtype=float)
        b = np.asarray(b, dtype=float)
        d = np.maximum(a - b, 0.0)
        total = np.zeros(np.broadcast(a, b).shape)
        for amp, p, q in self.terms:
            if max(abs(p), abs(q)) < 1e-6:           # uniform density: tau = d^2 / 2
                tau = 0.5 * d * d
            elif abs(p) >= abs(q):
                tau = (np.exp(p * d) * _ramp_integral(q, d) - _ramp_integral(p + q, d)) / p
            else:
                tau = (_ramp_integral(p + q, d) - _ramp_integral(p, d)) / q
            total = total + amp * np.exp((p + q) * b) * tau
        return total

    def _reversible(self, x):
        # r(x) = sum_k c_k x^k, k = 1, 2, ...
        out = np.zeros_like(x)
        for c in self.reversible[::-1]:
            out = (out + c) * x
        return out

    def _warped(self, x):
        # v = x - kappa sin(2 pi x) / (2 pi)
        return x - self.warp * np.sin(2 * np.pi * x) / (2 * np.pi)

    # ------------------------------------------------------------- state
    def reset(self):
        """Rest at u = 0 after a full 0 -> u_max -> 0 cycle: every relay off."""
        # Stack of turning points (alternating max, min, max, ...), bottom = v = 1
        # (the full cycle's maximum), with the Preisach output at each.
        self._ext = [1.0]
        self._out = [float(self.triangle_mass(1.0, 0.0))]
        self._v = 0.0          # current warped input
        self._p = 0.0          # current Preisach output
        self._dir = -1         # last direction of motion (came down)

    @property
    def state(self):
        """A copy of the memory (turning points and outputs, current point, direction)."""
        return (list(self._ext), list(self._out), self._v, self._p, self._dir)

    @state.setter
    def state(self, value):
        ext, out, v, p, direction = value
        self._ext, self._out = list(ext), list(out)
        self._v, self._p, self._dir = float(v), float(p), int(direction)

    @property
    def memory_size(self):
        """Number of turning points held (wiping-out keeps it small)."""
        return len(self._ext)

    # ------------------------------------------------------------- simulation
    def run(self, u):
        """Hysteretic output H (um) for the inputs ``u`` (V, within [0, u_max]),
        continuing from the current state."""
        u = checked_input(u, self.u_max)
        x = u / self.u_max
        v = self._warped(x)
        return self._reversible(x) + self._preisach(v)

    def _preisach(self, v):
        n = v.size
        y = np.empty(n)
        if n == 0:
            return y
        for i0, i1, s in monotone_runs(v, self._v, self._dir):
            if s != self._dir:                        # reversal: push the turning point
                self._ext.append(self._v)
                self._out.append(self._p)
                self._dir = s
            self._monotone_run(v[i0:i1], y[i0:i1], s)
            self._v, self._p = float(v[i1 - 1]), float(y[i1 - 1])
        return y

    def _monotone_run(self, vs, out, s):
        ext, outs = self._ext, self._out
        pos = 0
        n = vs.size
        while pos < n:
            # rising: top is a minimum, the maximum below it bounds the run (popped when
            # reached, if a minimum remains under it); falling: mirror image.
            deep_enough = len(ext) >= (4 if s > 0 else 3)
            if deep_enough:
                bound = ext[-2]
                if s > 0:
                    k = pos + int(np.searchsorted(vs[pos:], bound, side="left"))
                else:
                    k = pos + int(np.searchsorted(-vs[pos:], -bound, side="left"))
            else:
                k = n
            seg = vs[pos:k]
            if seg.size:
                if s > 0:
                    out[pos:k] = outs[-1] + self.triangle_mass(seg, ext[-1])
                else:
                    out[pos:k] = outs[-1] - self.triangle_mass(ext[-1], seg)
            if k < n:                                 # wiping-out: forget the inner loop
                del ext[-2:]
                del outs[-2:]
            pos = k
