"""Bouc-Wen hysteresis of a piezo actuator (Low and Guo's form), with a remanent
displacement.

    y = d u + c_2 (u / u_max)^2 - h,
    dh/dt = alpha d du/dt - beta |du/dt| h - gamma du/dt |h|          (n = 1)

The model is rate-independent: along a monotone run with direction s = sign(du) and
sigma = sign(h), dh/du = alpha d - k h with k = beta s + gamma sigma, whose exact solution
from (u_0, h_0) is

    h(u) = alpha d / k + (h_0 - alpha d / k) exp(-k (u - u_0)).

h crosses zero at most once per run (rising: from below, falling: from above), where k
changes; both pieces are evaluated in closed form, so no ODE solver is involved and the
result does not depend on the sampling. With beta > |gamma| the state stays within
|h| <= alpha d / (beta + gamma), and 2 alpha beta / (beta + gamma) <= 1 keeps y
non-decreasing in u along every branch.

Unlike a Preisach or PI model, its minor loops do not close and a unipolar cycle leaves a
remanent displacement y = -h > 0 at u = 0.

With an exponent n != 1 (the general Bouc-Wen form),

    dh/dt = alpha d du/dt - beta |du/dt| |h|^(n-1) h - gamma du/dt |h|^n,
    i.e.  dh/du = alpha d - (beta s sigma + gamma) |h|^n   along a run of direction s,

which has no closed form: it is integrated in u along each monotone run by classical
Runge-Kutta (4th order) in steps of at most ``u_max / 2000`` (the result depends on the
sampling only through that integration error, ~1e-9 of the range). The bounds hold with
|h| <= (alpha d / (beta + gamma))^(1/n), and 2 alpha beta / (beta + gamma) <= 1 still keeps
y non-decreasing in u: the largest dh/du is alpha d + (beta - gamma) |h|^n on a falling
run, at most 2 alpha beta d / (beta + gamma).
"""

import numpy as np

from pihyst.exceptions import InvalidArgumentError
from pihyst.sim._runs import checked_input, monotone_runs


class BoucWen:
    """Bouc-Wen hysteresis; see the module docstring.

    Parameters
    ----------
    u_max : float
        Input range is [0, u_max] (V).
    d : float
        Piezo coefficient (um/V).
    alpha, beta, gamma : float
        Bouc-Wen shape (alpha dimensionless, beta and gamma in 1/V).
    c2 : float
        Quadratic reversible term (um at u_max).
    n : float
        Bouc-Wen exponent, >= 1 (1: the closed form above; beta, gamma are then in
        1/V, otherwise in 1/(V um^(n-1))).

    Examples
    --------
    >>> import numpy as np
    >>> bw = BoucWen(150.0, d=0.3, alpha=0.4, beta=0.03, gamma=0.005)
    >>> y = bw.run(np.r_[np.linspace(0, 150, 151), np.linspace(149, 0, 150)])
    >>> bool(y[-1] > 0.5)         # remanent displacement at 0 V
    True
    """

    def __init__(self, u_max, d, alpha, beta, gamma, c2=0.0, n=1.0):
        self.n = float(n)
        if not (np.isfinite(self.n) and self.n >= 1):
            raise InvalidArgumentError(f"Bouc-Wen exponent n must be >= 1, got {n}")
        self.u_max = float(u_max)
        self.d, self.alpha, self.beta, self.gamma, self.c2 = (
            float(v) for v in (d, alpha, beta, gamma, c2))
        values = np.array([self.u_max, self.d, self.alpha, self.beta, self.gamma, self.c2])
        if not np.all(np.isfinite(values)):
            raise InvalidArgumentError("Bouc-Wen parameters must be finite")
        if not (self.u_max > 0 and self.d > 0 and self.alpha > 0 and self.c2 >= 0):
            raise InvalidArgumentError("Bouc-Wen needs u_max > 0, d > 0, alpha > 0, c2 >= 0")
        if not self.beta > abs(self.gamma):
            raise InvalidArgumentError("Bouc-Wen needs beta > |gamma| (bounded, stable loops)")
        if 2 * self.alpha * self.beta / (self.beta + self.gamma) > 1 + 1e-12:
            raise InvalidArgumentError("Bouc-Wen needs 2 alpha beta / (beta + gamma) <= 1 "
                             "(otherwise the displacement can run against the voltage)")
        self.reset()

    @property
    def h_saturation(self):
        """(alpha d / (beta + gamma))^(1/n): the bound of |h|."""
        return (self.alpha * self.d / (self.beta + self.gamma)) ** (1.0 / self.n)

    def virgin(self):
        """Set the state of the unpoled, never driven actuator: u = 0, h = 0."""
        self._u, self._h, self._dir = 0.0, 0.0, 1

    def reset(self):
        """Rest at u = 0 after a full 0 -> u_max -> 0 cycle from the virgin state."""
        self.virgin()
        self._h = float(self._advance(0.0, 0.0, np.array([self.u_max]), 1)[-1])
        self._h = float(self._advance(self.u_max, self._h, np.array([0.0]), -1)[-1])
        self._u, self._dir = 0.0, -1

    @property
    def state(self):
        """(u, h, direction) of the current point."""
        return (self._u, self._h, self._dir)

    @state.setter
    def state(self, value):
        self._u, self._h, self._dir = (float(value[0]), float(value[1]), int(value[2]))

    def _output(self, u, h):
        # y = d u + c_2 (u / u_max)^2 - h
        x = u / self.u_max
        return self.d * u + self.c2 * x * x - h

    def run(self, u):
        """Displacement (um) for inputs ``u`` (V, within [0, u_max]), continuing from the
        current state."""
        u = checked_input(u, self.u_max)
        n = u.size
        h = np.empty(n)
        if n == 0:
            return h
        for i0, i1, s in monotone_runs(u, self._u, self._dir):
            h[i0:i1] = self._advance(self._u, self._h, u[i0:i1], s)
            self._u, self._h, self._dir = float(u[i1 - 1]), float(h[i1 - 1]), s
        return self._output(u, h)

    def _slope(self, h, s):
        # dh/du = alpha d - beta s |h|^(n-1) h - gamma |h|^n
        a = abs(h) ** self.n
        return self.alpha * self.d - self.beta * s * np.copysign(a, h) - self.gamma * a

    def _advance_numeric(self, u0, h0, us, s):
        """h along a monotone run (any n) by RK4 in steps of at most u_max / 2000."""
        out = np.empty(us.size)
        max_step = self.u_max / 2000.0
        u, h = u0, h0
        last = None
        for i, target in enumerate(us):
            if target != last:
                du = target - u
                m = max(1, int(np.ceil(abs(du) / max_step)))
                step = du / m
                for _ in range(m):
                    k1 = self._slope(h, s)
                    k2 = self._slope(h + 0.5 * step * k1, s)
                    k3 = self._slope(h + 0.5 * step * k2, s)
                    k4 = self._slope(h + step * k3, s)
                    h += step * (k1 + 2 * k2 + 2 * k3 + k4) / 6.0
                u, last = target, target
            out[i] = h
        return out

    def _advance(self, u0, h0, us, s):
        """h along a monotone run of direction s starting from (u0, h0)."""
        if self.n != 1.0:
            return self._advance_numeric(u0, h0, us, s)
        ad = self.alpha * self.d
        # sign h takes during this run: it moves up when rising, down when falling
        sigma = 1.0 if (h0 > 0 or (h0 == 0 and s > 0)) else -1.0
        k = self.beta * s + self.gamma * sigma
        out = ad / k + (h0 - ad / k) * np.exp(-k * (us - u0))
        crosses = (s > 0 and sigma < 0) or (s < 0 and sigma > 0)
        if crosses:
            # h(u_c) = 0: exp(-k (u_c - u0)) = (ad/k) / (ad/k - h0)
            uc = u0 + np.log((ad / k - h0) / (ad / k)) / k
            past = (us >= uc) if s > 0 else (us <= uc)
            if np.any(past):
                k2 = self.beta * s - self.gamma * sigma
                out[past] = ad / k2 * (1 - np.exp(-k2 * (us[past] - uc)))
        return out
