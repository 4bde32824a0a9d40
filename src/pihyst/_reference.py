"""Pure-NumPy twin of :mod:`pihyst._core`: same class, same methods, no C.

A test oracle, written for clarity rather than speed: the tests run both on the
same signals and compare. Formulas are DESIGN.md section 2.
"""

import numpy as np

FAMILIES = ("classical", "multislope", "pwl")


class CoreError(ValueError):
    """Raised for parameters the C core would reject."""


def polyline(x, y, u):
    """Polyline through (x, y), continued beyond its ends with the end slopes."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if x.size == 1:
        return float(y[0])
    i = int(np.clip(np.searchsorted(x, u, side="right") - 1, 0, x.size - 2))
    return float(y[i] + (y[i + 1] - y[i]) * (u - x[i]) / (x[i + 1] - x[i]))


class Bank:
    """Operator bank with weights and offset; see :class:`pihyst._core.Bank`."""

    def __init__(self, family, thresholds, weights, offset, u_min, u_max, shape=None,
                 rising=None, falling=None, initial_state=None):
        if family not in FAMILIES:
            raise ValueError(f"unknown family {family!r}")
        self.family = family
        self.weights = np.array(weights, dtype=float)
        self.n_ops = self.weights.size
        self.offset = float(offset)
        if family != "pwl":
            self.thresholds = np.array(thresholds, dtype=float)
            r = self.thresholds
            if np.any(r < 0) or np.any(np.diff(r) <= 0):
                raise CoreError("thresholds must be >= 0 and strictly increasing")
        if family == "multislope":
            self.U, self.a, self.b, self.h = (float(v) for v in shape)
        if family == "pwl":
            self.rising = [(np.asarray(x, float), np.asarray(y, float)) for x, y in rising]
            self.falling = [(np.asarray(x, float), np.asarray(y, float)) for x, y in falling]
        self._state = np.zeros(self.n_ops)
        self.reset(initial_state)

    @property
    def state(self):
        return self._state.copy()

    @state.setter
    def state(self, value):
        self._state = np.array(value, dtype=float)

    def reset(self, initial_state=None):
        self._state = (np.zeros(self.n_ops) if initial_state is None
                       else np.array(initial_state, dtype=float))

    def envelopes(self, u):
        """R_k(u), F_k(u) for every operator (DESIGN.md section 2)."""
        if self.family == "classical":
            # R(u) = u - r,  F(u) = u + r
            return u - self.thresholds, u + self.thresholds
        if self.family == "multislope":
            # R(u) = max(a(u - r), b u - r - (b - 1)U)
            # F(u) = min(b u, a u + (1 - a)U - (1 - a h) r)
            r, U, a, b, h = self.thresholds, self.U, self.a, self.b, self.h
            rise = np.maximum(a * (u - r), b * u - r - (b - 1) * U)
            fall = np.minimum(b * u, a * u + (1 - a) * U - (1 - a * h) * r)
            return rise, fall
        rise = np.array([polyline(x, y, u) for x, y in self.rising])
        fall = np.array([polyline(x, y, u) for x, y in self.falling])
        return rise, fall

    def _update(self, u):
        # f[t] = max(R(u[t]), min(F(u[t]), f[t-1]))
        rise, fall = self.envelopes(u)
        self._state = np.maximum(rise, np.minimum(fall, self._state))
        return self._state

    def step(self, u):
        return float(self.offset + self.weights @ self._update(u))

    def run(self, u):
        return np.array([self.step(v) for v in np.asarray(u, dtype=float)])

    def operators(self, u):
        u = np.asarray(u, dtype=float)
        phi = np.empty((u.size, self.n_ops))
        for t, v in enumerate(u):
            phi[t] = self._update(v)
        return phi

    def gram(self, u, d):
        phi = self.operators(u)
        d = np.asarray(d, dtype=float)
        return phi.T @ phi, phi.T @ d, phi.sum(axis=0)
