"""Pure-NumPy twin of :mod:`pihyst._core`: same class, same methods, no C.

A test oracle, written for clarity rather than speed: the tests run both on the
same signals and compare. Formulas are docs/theory/operators.md. Also the per-sample
reference of a vectorized NumPy path (:func:`turning_points_loop`).
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
        """R_k(u), F_k(u) for every operator (docs/theory/operators.md)."""
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


# ---------------------------------------------------------------- compensator (inverse)

FLAG_SATURATED_LOW, FLAG_SATURATED_HIGH, FLAG_NAN, FLAG_SLEW = 1, 2, 4, 8


def _polyline_many(x, y, u):
    """The polyline of :func:`polyline` at every value of the array ``u``."""
    if x.size == 1:
        return np.full(u.shape, float(y[0]))
    i = np.clip(np.searchsorted(x, u, side="right") - 1, 0, x.size - 2)
    return y[i] + (y[i + 1] - y[i]) * (u - x[i]) / (x[i + 1] - x[i])


class Compensator:
    """NumPy twin of :class:`pihyst._core.Compensator`: same constructor and methods.

    Independent of the C segment walk. For each sample it lists every breakpoint of

        y(u) = offset + sum_k w_k max(R_k(u), min(F_k(u), f_k))

    in the window of allowed voltages: the envelopes' own kinks, and on every piece
    between them the voltages where R_k or F_k crosses f_k. Between consecutive
    breakpoints y is linear, so after evaluating y at all of them by the formula above,
    the voltage nearest the last one with y(u) = y_d follows from one linear
    interpolation in the first bracketing interval. Slow (O(K^2) per sample), clear.
    """

    def __init__(self, bank, u_min, u_max, max_step, initial_voltage):
        if np.any(bank.weights < 0):
            raise CoreError("compensation needs non-negative weights")
        self.bank = bank
        lo, hi = float(u_min), float(u_max)  # explicit: this Bank does not keep its range
        if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi) or not max_step > 0:
            raise CoreError("invalid voltage limits or slew limit")
        if not np.isfinite(initial_voltage):
            raise CoreError("initial voltage is not finite")
        if not lo <= initial_voltage <= hi:
            raise CoreError("initial voltage outside the limits")
        self.limits = (lo, hi)
        self.max_step = float(max_step)
        # rounding of the output: 4 (K + 2) eps (|offset| + sum_k w_k max|envelopes|)
        r_lo, f_lo = bank.envelopes(lo)
        r_hi, f_hi = bank.envelopes(hi)
        big = np.max(np.abs([r_lo, f_lo, r_hi, f_hi]), axis=0)
        scale = abs(bank.offset) + float(bank.weights @ big)
        self.tolerance = 4.0 * (bank.n_ops + 2) * np.finfo(float).eps * scale
        self.last_flags = 0
        self._apply(float(initial_voltage))

    # ------------------------------------------------------------ the model, vectorized
    def _envelopes_at(self, u):
        """R, F of shape (len(u), K)."""
        b = self.bank
        u = np.asarray(u, dtype=float)[:, None]
        if b.family == "classical":
            return u - b.thresholds, u + b.thresholds
        if b.family == "multislope":
            r, U, a, bb, h = b.thresholds, b.U, b.a, b.b, b.h
            return (np.maximum(a * (u - r), bb * u - r - (bb - 1) * U),
                    np.minimum(bb * u, a * u + (1 - a) * U - (1 - a * h) * r))
        u = u[:, 0]
        rise = np.column_stack([_polyline_many(x, y, u) for x, y in b.rising])
        fall = np.column_stack([_polyline_many(x, y, u) for x, y in b.falling])
        return rise, fall

    def _kinks(self):
        b = self.bank
        if b.family == "classical":
            return np.empty(0)
        if b.family == "multislope":
            r, U, a, bb, h = b.thresholds, b.U, b.a, b.b, b.h
            rise_kink = (r * (1 - a) + (bb - 1) * U) / (bb - a)   # a(u - r) = b u - r - (b-1)U
            fall_kink = ((1 - a) * U - (1 - a * h) * r) / (bb - a)  # b u = a u + (1-a)U - (1-ah)r
            return np.concatenate([rise_kink, fall_kink])
        return np.concatenate([x for x, _ in b.rising] + [x for x, _ in b.falling])

    def _output_at(self, u, f):
        rise, fall = self._envelopes_at(u)
        return self.bank.offset + np.maximum(rise, np.minimum(fall, f)) @ self.bank.weights

    def _breakpoints(self, lo, hi, u_p, f):
        """Every breakpoint of y(u) in [lo, hi] (with lo, hi and u_p), sorted."""
        kinks = self._kinks()
        p = np.unique(np.concatenate([[lo, hi, u_p], kinks[(kinks > lo) & (kinks < hi)]]))
        points = [p]
        env = self._envelopes_at(p)
        for e in env:  # R and F: where a linear piece crosses the level f_k
            e0, e1 = e[:-1], e[1:]
            p0, p1 = p[:-1, None], p[1:, None]
            crosses = ((e0 - f) * (e1 - f) <= 0) & (e1 != e0)
            with np.errstate(divide="ignore", invalid="ignore"):
                u = p0 + (f - e0) * (p1 - p0) / (e1 - e0)
            u = u[crosses]
            points.append(u[(u >= lo) & (u <= hi)])
        return np.unique(np.concatenate(points))

    # ------------------------------------------------------------ state
    def _apply(self, u):
        self.output = self.bank.step(u)
        self.voltage = u

    @property
    def state(self):
        return self.bank.state

    def reset(self, state, voltage):
        if not np.isfinite(voltage):
            raise CoreError("voltage is not finite")
        if not self.limits[0] <= voltage <= self.limits[1]:
            raise CoreError("voltage outside the limits")
        if state is not None and not np.all(np.isfinite(state)):
            raise CoreError("state is not finite")
        self.bank.reset(state)
        self._apply(float(voltage))
        self.last_flags = 0

    # ------------------------------------------------------------ one sample
    def _window(self, u_p):
        lo, hi = self.limits
        step = self.max_step
        top, bottom = u_p + step, u_p - step
        while top - u_p > step:  # keep (end - u_p) <= max_step in floating point
            top = np.nextafter(top, u_p)
        while u_p - bottom > step:
            bottom = np.nextafter(bottom, u_p)
        return (max(lo, bottom), bottom > lo), (min(hi, top), top < hi)

    def step(self, y_desired):
        y_d = float(y_desired)
        u_p, y_p = self.voltage, self.output
        flags = 0
        if np.isnan(y_d):
            flags = FLAG_NAN
        elif abs(y_d - y_p) > self.tolerance:
            (lo, slew_lo), (hi, slew_hi) = self._window(u_p)
            f = self.bank.state
            c = self._breakpoints(lo, hi, u_p, f)
            up = y_d > y_p
            c = c[c >= u_p] if up else c[c <= u_p][::-1]  # walk away from u_p
            y = self._output_at(c, f)
            sign = 1.0 if up else -1.0
            reached = np.flatnonzero(sign * (y - y_d) >= 0)
            if reached.size == 0:
                u = hi if up else lo
                slew = slew_hi if up else slew_lo
                flags = FLAG_SATURATED_HIGH if up else FLAG_SATURATED_LOW
                if slew:
                    # out of reach too if the voltage limit itself misses y_d
                    limit = self.limits[1] if up else self.limits[0]
                    y_limit = float(self._output_at(np.array([limit]), f)[0])
                    short_by = y_d - y_limit if up else y_limit - y_d
                    flags = FLAG_SLEW | (flags if short_by > self.tolerance else 0)
            elif reached[0] == 0:
                u = u_p
            else:
                j = reached[0]
                # the linear piece between breakpoints j - 1 and j holds y_d
                u = c[j - 1] + (y_d - y[j - 1]) * (c[j] - c[j - 1]) / (y[j] - y[j - 1])
                u = float(np.clip(u, min(c[j - 1], c[j]), max(c[j - 1], c[j])))
            self._apply(float(u))
            if flags and abs(y_d - self.output) <= self.tolerance:
                flags = 0  # the window's end meets y_d to rounding: not a miss
        self.last_flags = flags
        return self.voltage

    def run(self, y_desired):
        y_desired = np.asarray(y_desired, dtype=float)
        u = np.empty(y_desired.size)
        y = np.empty(y_desired.size)
        flags = np.zeros(y_desired.size, dtype=np.uint8)
        for t, y_d in enumerate(y_desired):
            u[t] = self.step(y_d)
            y[t] = self.output
            flags[t] = self.last_flags
        return u, y, flags


class CompensatorSoA:
    """NumPy twin of :class:`pihyst._core.CompensatorSoA` (csrc/pihyst_bank_soa.c): N
    :class:`Compensator` objects; classical channels with r_0 = 0 and w_0 >= sum w / 1024
    (> 0) step the model's exact inverse, a classical PI model in y~ = y - offset,

        z_j <- clip(z_j, y~ - r'_j, y~ + r'_j),   u = w' . z
        r'_j = sum_{i<=j} w_i (r_j - r_i),  w'_0 = 1/W_0,  w'_j = -w_j / (W_j W_{j-1})

    with W_j = sum_{i<=j} w_i, whose state is z_j = W_j f_j + sum_{i>j} w_i f_i of the
    model's state f (it needs a state 1-Lipschitz in r: |f_i - f_j| <= r_j - r_i).
    A tick whose voltage would leave the limits or the slew limit goes to the channel's
    compensator from the state f of z; a desired value within the compensator's
    tolerance of the last output, or NaN, holds. One channel at a time, for clarity."""

    def __init__(self, compensators):
        self.compensators = tuple(compensators)
        self.reload()

    @staticmethod
    def _has_fast_path(c):
        b = c.bank
        if b.family != "classical" or b.thresholds[0] != 0.0:
            return False
        w = b.weights
        return bool(w[0] > 0 and w[0] >= np.sum(w) / 1024)

    @staticmethod
    def _lipschitz(c):
        r, f = c.bank.thresholds, c.bank.state
        tol = 8 * np.finfo(float).eps * (max(abs(c.limits[0]), abs(c.limits[1])) + r[-1])
        return bool(np.all(np.abs(np.diff(f)) <= np.diff(r) + tol))

    @staticmethod
    def _to_z(c):
        w, f = c.bank.weights, c.bank.state
        above = np.cumsum((w * f)[::-1])[::-1] - w * f  # sum_{i>j} w_i f_i
        return np.cumsum(w) * f + above

    @staticmethod
    def _from_z(c, z):
        W = np.cumsum(c.bank.weights)
        f = np.empty_like(z)
        f[-1] = z[-1] / W[-1]
        for j in range(z.size - 2, -1, -1):
            f[j] = f[j + 1] + (z[j] - z[j + 1]) / W[j]
        return f

    def _load(self, i):
        c = self.compensators[i]
        r, w = c.bank.thresholds, c.bank.weights
        W = np.cumsum(w)
        r_inv = np.array([np.sum(w[:j + 1] * (r[j] - r[:j + 1])) for j in range(w.size)])
        w_inv = np.r_[1.0 / w[0], -w[1:] / (W[1:] * W[:-1])]
        self._fast[i] = [r_inv, w_inv, self._to_z(c), c.voltage, c.output]

    def reload(self):
        self._fast = {}
        self._pending = set()
        for i, c in enumerate(self.compensators):
            if self._has_fast_path(c):
                if self._lipschitz(c):
                    self._load(i)
                else:
                    self._pending.add(i)

    @property
    def n_fast(self):
        return len(self._fast)

    def sync(self):
        for i, (_, _, z, u_last, _) in self._fast.items():
            c = self.compensators[i]
            c.reset(self._from_z(c, z), u_last)

    def _exact(self, i, y_d):
        c = self.compensators[i]
        if i in self._fast:
            fast = self._fast[i]
            c.reset(self._from_z(c, fast[2]), fast[3])
            c.step(y_d)
            fast[2:] = [self._to_z(c), c.voltage, c.output]
        else:
            c.step(y_d)
            if i in self._pending and self._lipschitz(c):
                self._pending.discard(i)
                self._load(i)
        return c.voltage, c.output, c.last_flags

    def step(self, y_desired):
        """One tick: (u, y, flags) for one desired value per channel."""
        n = len(self.compensators)
        u, y, flags = np.empty(n), np.empty(n), np.zeros(n, dtype=np.uint8)
        for i, y_d in enumerate(np.asarray(y_desired, dtype=float)):
            c = self.compensators[i]
            if i not in self._fast:
                u[i], y[i], flags[i] = self._exact(i, y_d)
                continue
            fast = self._fast[i]
            r_inv, w_inv, z, u_p, y_p = fast
            if not abs(y_d - y_p) > c.tolerance:  # hold (NaN included)
                u[i], y[i], flags[i] = u_p, y_p, FLAG_NAN if np.isnan(y_d) else 0
                continue
            y_t = y_d - c.bank.offset
            with np.errstate(invalid="ignore", over="ignore"):  # y_d infinite: u NaN
                z_new = np.clip(z, y_t - r_inv, y_t + r_inv)
                u_new = float(w_inv @ z_new)
            lo, hi = c.limits
            if lo <= u_new <= hi and abs(u_new - u_p) <= c.max_step:
                fast[2:] = [z_new, u_new, y_d]
                u[i], y[i] = u_new, y_d
            else:
                u[i], y[i], flags[i] = self._exact(i, y_d)
        return u, y, flags

    def run(self, y_desired):
        """(u, y, flags), each T x N, for desired values T x N."""
        y_desired = np.asarray(y_desired, dtype=float)
        out = [self.step(row) for row in y_desired]
        shape = y_desired.shape
        return (np.array([o[0] for o in out]).reshape(shape),
                np.array([o[1] for o in out]).reshape(shape),
                np.array([o[2] for o in out], dtype=np.uint8).reshape(shape))


class Creep:
    """NumPy twin of :class:`pihyst._core.Creep` (docs/theory/creep.md), same methods.

    Written from the definitions, not from (C4)-(C5): the target is found from the
    output's value at two hysteresis levels, which is exact because the output is affine
    in h at each sample.
    """

    def __init__(self, tau, gain, dt, initial_state=None):
        self.tau = np.array(tau, dtype=float)
        self.gain = np.array(gain, dtype=float)
        self.n = self.tau.size
        if self.n == 0:
            raise CoreError("creep needs at least one lag")
        if not (np.all(np.isfinite(self.tau)) and np.all(np.isfinite(self.gain))):
            raise CoreError("creep parameter is NaN or infinite")
        if np.any(self.tau <= 0):
            raise CoreError("creep time constants must be > 0")
        if np.any(self.gain < 0) or not self.gain.sum() < 1:
            raise CoreError("creep gains must be >= 0 and sum to less than 1")
        if not (np.isfinite(dt) and dt >= 0):
            raise CoreError("creep sample interval must be finite and >= 0")
        self.dt = float(dt)
        self.state = np.zeros(self.n) if initial_state is None else \
            np.array(initial_state, dtype=float)

    @property
    def beta(self):
        return float(self.gain @ np.exp(-self.dt / self.tau))

    def _next(self, h, dt):
        # alpha_i = 1 - exp(-dt/tau_i);  z_i[t] = z_i[t-1] + alpha_i (h - z_i[t-1])
        alpha = 1.0 - np.exp(-dt / self.tau)
        z = self.state + alpha * (h - self.state)
        # y[t] = h - sum_i g_i (h - z_i[t])
        return h - self.gain @ (h - z), z

    def step(self, h, dt=None):
        y, self.state = self._next(float(h), self.dt if dt is None else float(dt))
        return float(y)

    def target(self, y_desired, dt=None):
        dt = self.dt if dt is None else float(dt)
        y0, _ = self._next(0.0, dt)
        y1, _ = self._next(1.0, dt)
        return float((y_desired - y0) / (y1 - y0))

    def run(self, h, dt=None):
        h = np.asarray(h, dtype=float)
        dts = [None] * h.size if dt is None else np.asarray(dt, dtype=float)
        return np.array([self.step(x, d) for x, d in zip(h, dts)])

    def compensate(self, comp, y_desired, dt=None):
        y_desired = np.asarray(y_desired, dtype=float)
        dts = [None] * y_desired.size if dt is None else np.asarray(dt, dtype=float)
        u = np.empty(y_desired.size)
        y = np.empty(y_desired.size)
        flags = np.zeros(y_desired.size, dtype=np.uint8)
        for t, (y_d, d) in enumerate(zip(y_desired, dts)):
            with np.errstate(invalid="ignore"):
                u[t] = comp.step(self.target(y_d, d))
            y[t] = self.step(comp.output, d)
            flags[t] = comp.last_flags
        return u, y, flags


def turning_points_loop(v, tolerance):
    """Turning points of ``v``, sample by sample: the reference of the vectorized
    :func:`pihyst.identify._cycles.turning_points` (same (index, +1 max / -1 min) list)."""
    points = []
    hi_i = lo_i = 0
    direction = 0          # +1 rising (looking for a maximum), -1 falling, 0 unknown
    for t in range(1, v.size):
        x = v[t]
        if x > v[hi_i]:
            hi_i = t
        if x < v[lo_i]:
            lo_i = t
        if direction >= 0 and v[hi_i] - x > tolerance:
            if hi_i > 0:
                points.append((hi_i, +1))
            direction, lo_i = -1, t
        elif direction <= 0 and x - v[lo_i] > tolerance:
            if lo_i > 0:
                points.append((lo_i, -1))
            direction, hi_i = +1, t
    return points
