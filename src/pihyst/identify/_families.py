"""Model families for identification: candidate operators, and models in two frames.

Fitting works in a shifted input v = u - lo on [0, S], S = hi - lo, whatever range the
data span (0-150 V, 0-3.6 V, +-150 V): the multislope operator's geometry is anchored at
v = 0 (F(0) = 0, its kinks, the hold after a maximum at U), so it must see the data's
range as [0, U]. Each family builds its operators there (``template``: unit weights) and
maps the fitted weights back to a model of the raw input u (``final_model``) by that
affine change of variable:

- classical: R(u) = u - r = (v - r) + lo, so f_u = f_v + lo for every operator, and
  y = c_v + sum w f_v = (c_v - lo sum w) + sum w f_u: a ClassicalPI with the same
  thresholds and weights, offset c_v - lo sum w, state f_v + lo;
- multislope and the other polyline families: R_u(u) = R_v(u - lo), i.e. the same
  polylines moved by lo along the input axis, outputs unchanged. For lo = 0 the multislope
  model stays a MultislopePI with U = S; otherwise it is stored as a PiecewiseLinearPI
  whose polylines are exactly the multislope envelopes (and the shape is in the metadata).
"""

from abc import ABC, abstractmethod

import numpy as np

from pihyst.model import ClassicalPI, MultislopePI, PiecewiseLinearPI

PAPER_A, PAPER_B, PAPER_H = 0.8, 1.2, 0.5


def multislope_max_threshold(U, a, h):
    """Largest valid multislope threshold, (1 - a)U / (1 - a h) (docs/theory/operators.md)."""
    return (1 - a) * U / (1 - a * h)


def _line(S, slope, intercept):
    """A straight polyline y = slope v + intercept (two points, extended by the core)."""
    x = np.array([0.0, S])
    return (x, slope * x + intercept)


def _ramp(start, length, height):
    """0 below ``start``, rising linearly to ``height`` over ``length``, flat above."""
    x = np.array([start - length, start, start + length, start + 2 * length])
    return (x, np.array([0.0, 0.0, height, height]))


def multislope_polylines(r, S, U, a, b, h):
    """Rising and falling envelopes of a multislope operator as polylines on [0, S].

    R(v) = max(a(v - r), b v - r - (b - 1)U)         kink at ((b - 1)U + (1 - a)r)/(b - a)
    F(v) = min(b v, a v + (1 - a)U - (1 - a h) r)    kink at ((1 - a)U - (1 - a h)r)/(b - a)
    """
    def rise(v):
        return np.maximum(a * (v - r), b * v - r - (b - 1) * U)

    def fall(v):
        return np.minimum(b * v, a * v + (1 - a) * U - (1 - a * h) * r)

    out = []
    for env, kink in ((rise, ((b - 1) * U + (1 - a) * r) / (b - a)),
                      (fall, ((1 - a) * U - (1 - a * h) * r) / (b - a))):
        x = [0.0, S]
        if 1e-9 * S < kink < S * (1 - 1e-9):
            x = [0.0, kink, S]
        x = np.array(x)
        out.append((x, env(x)))
    return out


def _shift(polylines, lo):
    return [(x + lo, y.copy()) for x, y in polylines]


class Family(ABC):
    """One model family: how to build its operators and map them to the raw input."""

    name = None
    title = None
    # thresholds chosen by subset search over ``candidates(S, n_candidates)``, which
    # such families define
    subset_search = True
    n_fixed = 0            # operator columns always present after the thresholds'

    def max_threshold(self, S):
        return np.inf

    @abstractmethod
    def template(self, thresholds, S):
        """Model of v on [0, S] with unit weights; columns = thresholds' operators, then
        the fixed ones."""

    @abstractmethod
    def final_model(self, thresholds, weights, offset, state_v, lo, S):
        """The fitted model of the raw input u (see the module docstring)."""

    def raw_state(self, state_v, lo):
        """Operator state in the raw frame (u) from the v frame."""
        return np.asarray(state_v, dtype=float)

    def v_state(self, state_u, lo):
        return np.asarray(state_u, dtype=float)

    def describe(self):
        return {}


class Classical(Family):
    name = "classical"
    title = "classical PI"

    def candidates(self, S, n_candidates):
        # After a full sweep, an operator with r >= S/2 never moves again (R <= S - r <= r
        # <= F on [0, S]): its output is a constant. So the useful thresholds are [0, S/2).
        return np.arange(n_candidates) * (0.5 * S / n_candidates)

    def max_threshold(self, S):
        return 0.5 * S

    def template(self, thresholds, S):
        return ClassicalPI(thresholds, np.ones(len(thresholds)), input_range=(0.0, S))

    def final_model(self, thresholds, weights, offset, state_v, lo, S):
        w = np.asarray(weights, dtype=float)
        return ClassicalPI(thresholds, w, offset=offset - lo * w.sum(),
                           input_range=(lo, lo + S), initial_state=self.raw_state(state_v, lo))

    def raw_state(self, state_v, lo):
        return np.asarray(state_v, dtype=float) + lo

    def v_state(self, state_u, lo):
        return np.asarray(state_u, dtype=float) - lo


class Multislope(Family):
    """Multislope PI of Xu et al. (2020), eq. 6, with shape (U, a, b, h); U defaults to
    the data's span S (the top of the range in the v frame)."""

    name = "multislope"
    title = "multislope PI (paper's shape)"

    def __init__(self, U=None, a=PAPER_A, b=PAPER_B, h=PAPER_H):
        self.U, self.a, self.b, self.h = U, float(a), float(b), float(h)

    def with_shape(self, **shape):
        return type(self)(**{"U": self.U, "a": self.a, "b": self.b, "h": self.h, **shape})

    def shape(self, S):
        return {"U": S if self.U is None else float(self.U), "a": self.a, "b": self.b,
                "h": self.h}

    def max_threshold(self, S):
        s = self.shape(S)
        return multislope_max_threshold(s["U"], s["a"], s["h"])

    def candidates(self, S, n_candidates):
        # n equally spaced over the valid range [0, (1 - a)U / (1 - a h)], both ends included
        return np.linspace(0.0, self.max_threshold(S), n_candidates)

    def template(self, thresholds, S):
        return MultislopePI(thresholds, np.ones(len(thresholds)), input_range=(0.0, S),
                            **self.shape(S))

    def final_model(self, thresholds, weights, offset, state_v, lo, S):
        s = self.shape(S)
        if lo == 0.0:
            return MultislopePI(thresholds, weights, offset=offset, input_range=(0.0, S),
                                initial_state=state_v, **s)
        polys = [multislope_polylines(r, S, s["U"], s["a"], s["b"], s["h"])
                 for r in thresholds]
        return PiecewiseLinearPI(_shift([p[0] for p in polys], lo),
                                 _shift([p[1] for p in polys], lo), weights, offset=offset,
                                 input_range=(lo, lo + S), initial_state=state_v)

    def describe(self):
        return {"shape": {"U": self.U, "a": self.a, "b": self.b, "h": self.h}}


class MultislopeIdentified(Multislope):
    """Multislope PI whose shape (a, b, h, optionally U) is identified from the data,
    starting from the paper's values (see :func:`pihyst.identify.fit`)."""

    name = "multislope-identified"
    title = "multislope PI (identified shape)"


class PolylineFamily(Family):
    """A family whose operators are polylines (``_polylines``): its models are
    PiecewiseLinearPI, moved by lo along the input axis in the raw frame."""

    @abstractmethod
    def _polylines(self, thresholds, S):
        """(rising, falling) polylines of the operators on [0, S]."""

    def template(self, thresholds, S):
        rising, falling = self._polylines(thresholds, S)
        return PiecewiseLinearPI(rising, falling, np.ones(len(rising)), input_range=(0.0, S))

    def final_model(self, thresholds, weights, offset, state_v, lo, S):
        rising, falling = self._polylines(thresholds, S)
        return PiecewiseLinearPI(_shift(rising, lo), _shift(falling, lo), weights,
                                 offset=offset, input_range=(lo, lo + S),
                                 initial_state=state_v)


class ModifiedPI(PolylineFamily):
    """Classical play operators plus a monotone input function p(v) = sum_j c_j g_j(v),
    g_j(v) = clamp(v, s_j, s_{j+1}) - s_j on ``n_segments`` equal segments of [0, S]
    (operators with R = F = g_j, i.e. without memory). With c_j >= 0, p is non-decreasing,
    so the model stays monotone and invertible; p bends the loop's centre line, which the
    point-symmetric classical loop cannot (the modified PI of Gu, Zhu and Su, with a
    piecewise-linear rather than polynomial input function)."""

    name = "modified-pi"
    title = "classical PI + monotone input function"

    def __init__(self, n_segments=4):
        self.n_segments = int(n_segments)
        self.n_fixed = self.n_segments

    def candidates(self, S, n_candidates):
        # r = 0 is left out: that play is R = F = v, the sum of the input segments
        return np.arange(1, n_candidates + 1) * (0.5 * S / (n_candidates + 1))

    def max_threshold(self, S):
        return 0.5 * S

    def _polylines(self, thresholds, S):
        rising, falling = [], []
        for r in thresholds:
            rising.append(_line(S, 1.0, -r))     # R(v) = v - r
            falling.append(_line(S, 1.0, r))     # F(v) = v + r
        edges = np.linspace(0.0, S, self.n_segments + 1)
        for s0, s1 in zip(edges[:-1], edges[1:]):
            g = _ramp(s0, s1 - s0, s1 - s0)      # R(v) = F(v) = clamp(v, s0, s1) - s0
            rising.append(g)
            falling.append(g)
        return rising, falling


    def describe(self):
        return {"input_function_segments": self.n_segments}


class KrasnoselskiiPokrovskii(PolylineFamily):
    """Krasnosel'skii-Pokrovskii kernels (docs/theory/identification.md): ramp-smoothed relays
    R(v) = sat((v - c_j)/w + 1/2), F(v) = sat((v - c_i)/w + 1/2), c_i <= c_j on a grid of
    ``n_grid`` centres over [0, S], width w = S/(n_grid - 1); sat clamps to [0, 1]. A
    Preisach-type basis: captures asymmetric loops; where the data cannot decide, its
    weights are regularized towards a density that depends only on the loop width
    c_j - c_i (see :meth:`penalty`)."""

    name = "kp"
    title = "Krasnosel'skii-Pokrovskii kernels (regularized)"
    subset_search = False

    def __init__(self, n_grid=16):
        self.n_grid = int(n_grid)

    def pairs(self):
        return [(i, j) for i in range(self.n_grid) for j in range(i, self.n_grid)]

    def _polylines(self, pairs, S):
        w = S / (self.n_grid - 1)
        centres = np.arange(self.n_grid) * w
        rising = [_ramp(centres[j] - w / 2, w, 1.0) for _, j in pairs]
        falling = [_ramp(centres[i] - w / 2, w, 1.0) for i, _ in pairs]
        return rising, falling


    def penalty(self, pairs):
        """D^T D for D the differences of the weights of kernels (i, j) and (i+1, j+1):
        neighbours along the diagonal of the Preisach plane, with the same width
        c_j - c_i. Where the data cannot decide, the density then depends only on the
        loop width, as in a classical PI model, whose minor loops follow from its major
        loop (this generalizes to reversals inside the range far better than plain
        smoothing towards all neighbours)."""
        index = {p: k for k, p in enumerate(pairs)}
        rows = []
        for (i, j), k in index.items():
            nb = index.get((i + 1, j + 1))
            if nb is not None:
                row = np.zeros(len(pairs))
                row[k], row[nb] = 1.0, -1.0
                rows.append(row)
        if not rows:
            return np.zeros((len(pairs), len(pairs)))
        D = np.array(rows)
        return D.T @ D

    def describe(self):
        return {"grid": self.n_grid}


FAMILY_NAMES = ("classical", "multislope", "multislope-identified", "modified-pi", "kp")
