"""Fitting families: candidate operators, how each family is fitted, models in two frames.

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

import copy
from abc import ABC, abstractmethod

import numpy as np

from pihyst.exceptions import FitError
from pihyst.identify._shape import identify_shape, refine_shape
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
    """A fitting family: the recipe that turns a record into one model.

    A family says which operators are candidates (``candidates``, or a kernel grid), how
    they are built in the fitting frame (``template``) and mapped back to the raw input
    (``final_model``), and how its structure is chosen (``fit``: threshold subset search
    by default; the multislope shape search and the KP regularization override it). Its
    own options (shape, input segments, kernel grid) are constructor arguments; options
    common to all families are :func:`pihyst.identify.fit`'s.

    A family is not the model's operator kind: ``model.family`` (``"classical"``,
    ``"multislope"``, ``"pwl"``) names the operators a model is made of, while several
    fitting families (``modified-pi``, ``kp``, and multislope on a range not starting at
    0) produce ``pwl`` models. The fitting family is recorded in
    ``model.metadata["fit"]["family"]``.
    """

    name = None
    title = None
    # the report's key for the operators: thresholds (floats) or kernels (index pairs)
    operators_key = "thresholds"
    n_fixed = 0            # operator columns always present after the thresholds'
    has_thresholds = True  # thresholds to choose (or give): False for kp and bouc-wen
    # PI-type structure: the minor loops follow from the major loop (the operators'
    # geometry fixes them), so a record of major loops alone is enough to fit it
    minor_loops_fixed = True
    # the compensator solves one piecewise-linear equation per sample (a segment walk):
    # tens of nanoseconds whatever the trajectory; False for an iterative inverse
    piecewise_linear_inverse = True

    def max_threshold(self, S):
        return np.inf

    def check_thresholds(self, thresholds, S):
        """FitError if explicit thresholds are not valid for this family (beyond
        sorted, distinct, >= 0, which every family needs); the limit of
        :meth:`max_threshold` is checked by the data instead (an operator the input
        never moves)."""
        return None

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

    def fit(self, fitter, rival_rms=None):
        """Fit this family to ``fitter``'s record: a :class:`FamilyFit`. Default: the
        thresholds chosen by subset search over ``candidates(S, n_candidates)``."""
        return fitter.fit_subsets(self)

    def prepare(self, fitter):
        """The family to run the threshold search with (e.g. with an identified shape)."""
        return self

    def refine(self, fitter, fitted):
        """A better fit of the chosen structure, or ``fitted`` itself."""
        return fitted

    def options(self, S):
        """This family's own options as the report shows them (resolved on span S)."""
        return {}

    def __eq__(self, other):
        return type(self) is type(other) and self.__dict__ == other.__dict__

    def __hash__(self):
        return hash((type(self), tuple(sorted(self.__dict__.items()))))

    def __repr__(self):
        args = ", ".join(f"{k}={v!r}" for k, v in self._args().items())
        return f"{type(self).__name__}({args})"

    def _args(self):
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


SHAPE_KEYS = ("U", "a", "b", "h")


class Multislope(Family):
    """Multislope PI of Xu et al. (2020), eq. 6, with a fixed shape {"U", "a", "b", "h"}
    (default the paper's a = 0.8, b = 1.2, h = 0.5; U defaults to the data's span S,
    the top of the range in the fitting frame)."""

    name = "multislope"
    title = "multislope PI (paper's shape)"
    # its geometry is anchored at the top of the range U, not at the last turning
    # point: after a reversal at M inside the range an operator holds flat for
    # 75 + r/2 - M/2 V (the paper's shape, docs/theory/operators.md), so its minor loops
    # are not those of a Preisach-type material (Masing's rule), and a record of major
    # loops alone says nothing about them
    minor_loops_fixed = False

    def __init__(self, shape=None):
        shape = {} if shape is None else dict(shape)
        unknown = sorted(set(shape) - set(SHAPE_KEYS))
        if unknown:
            raise FitError(f"{self.name}: unknown shape parameter(s) {', '.join(unknown)}; "
                           f"expected U, a, b, h")
        try:
            self.U = None if shape.get("U") is None else float(shape["U"])
            self.a = float(shape.get("a", PAPER_A))
            self.b = float(shape.get("b", PAPER_B))
            self.h = float(shape.get("h", PAPER_H))
        except (TypeError, ValueError):
            raise FitError(f"{self.name}: shape values must be numbers, got {shape}") from None

    def with_shape(self, **shape):
        out = copy.copy(self)
        Multislope.__init__(out, {**self._shape_dict(), **shape})
        return out

    def _shape_dict(self):
        return {"U": self.U, "a": self.a, "b": self.b, "h": self.h}

    def shape(self, S):
        return {"U": S if self.U is None else float(self.U), "a": self.a, "b": self.b,
                "h": self.h}

    def max_threshold(self, S):
        s = self.shape(S)
        return multislope_max_threshold(s["U"], s["a"], s["h"])

    def check_thresholds(self, thresholds, S):
        limit = self.max_threshold(S)
        if np.max(thresholds) > limit * (1 + 1e-12):
            s = self.shape(S)
            raise FitError(f"{self.name}: threshold {np.max(thresholds):g} is above "
                           f"(1 - a)U/(1 - a h) = {limit:g} for U={s['U']:g}, a={s['a']:g}, "
                           f"h={s['h']:g}", column="input")

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

    def options(self, S):
        return {"shape": {k: float(v) for k, v in self.shape(S).items()}}

    def _args(self):
        return {"shape": self._shape_dict()}


class MultislopeIdentified(Multislope):
    """Multislope PI whose shape (a, b, h; with ``identify="with-U"`` U too) is
    identified from the data, starting from ``shape`` (default the paper's); see
    docs/theory/identification.md. ``identify=False`` keeps the starting shape."""

    name = "multislope-identified"
    title = "multislope PI (identified shape)"

    def __init__(self, shape=None, identify=True):
        super().__init__(shape)
        if identify not in (True, False, "with-U"):
            raise FitError(f"{self.name}: identify must be True, False or 'with-U', got "
                           f"{identify!r}")
        self.identify = identify

    def prepare(self, fitter):
        return identify_shape(fitter, self) if self.identify else self

    def refine(self, fitter, fitted):
        if not self.identify or fitted.threshold_choice is None:
            return fitted            # explicit thresholds: nothing was chosen
        return refine_shape(fitter, fitted)

    def _args(self):
        return {"shape": self._shape_dict(), "identify": self.identify}


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
    g_j(v) = clamp(v, s_j, s_{j+1}) - s_j on ``segments`` equal segments of [0, S]
    (operators with R = F = g_j, i.e. without memory). With c_j >= 0, p is non-decreasing,
    so the model stays monotone and invertible; p bends the loop's centre line, which the
    point-symmetric classical loop cannot (the modified PI of Gu, Zhu and Su, with a
    piecewise-linear rather than polynomial input function)."""

    name = "modified-pi"
    title = "classical PI + monotone input function"

    def __init__(self, segments=4):
        if int(segments) != segments or segments < 1:
            raise FitError(f"{self.name}: segments must be a positive integer, got {segments}")
        self.segments = int(segments)

    @property
    def n_fixed(self):
        return self.segments

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
        edges = np.linspace(0.0, S, self.segments + 1)
        for s0, s1 in zip(edges[:-1], edges[1:]):
            g = _ramp(s0, s1 - s0, s1 - s0)      # R(v) = F(v) = clamp(v, s0, s1) - s0
            rising.append(g)
            falling.append(g)
        return rising, falling

    def options(self, S):
        return {"input_function_segments": self.segments}

    def _args(self):
        return {"segments": self.segments}


# weight of the reversible part's smoothness against the density's in the KP penalty
REVERSIBLE_SMOOTHING = 10.0


class KrasnoselskiiPokrovskii(PolylineFamily):
    """Krasnosel'skii-Pokrovskii kernels (docs/theory/identification.md): ramp-smoothed relays
    R(v) = sat((v - c_j)/w + 1/2), F(v) = sat((v - c_i)/w + 1/2), c_i <= c_j on a grid of
    ``grid`` centres over [0, S], width w = S/(grid - 1); sat clamps to [0, 1]. A
    Preisach-type basis: captures asymmetric loops; where the data cannot decide, its
    weights are regularized towards an additively separable density and a smooth
    reversible part (see :meth:`penalty`)."""

    name = "kp"
    title = "Krasnosel'skii-Pokrovskii kernels (regularized)"
    operators_key = "kernels"
    has_thresholds = False
    # a kernel basis has a weight for every minor loop: a record of major loops alone
    # leaves the interior of the Preisach plane to the regularization, which fixes it:
    # of the densities that fit the record, the one closest to separable with a smooth
    # reversible part (see penalty), averaged with the product-form one
    # (_kernel_product). Measured on the 30 random actuators
    # (benchmarks/bench_population.py), the eight Preisach ones recorded on a two-cycle
    # triangle: 0.08-0.42 % of range on ramps and staircases (validation, with creep);
    # on the P-885 pair 0.30 um on the test record
    minor_loops_fixed = True

    def __init__(self, grid=16):
        if int(grid) != grid or grid < 2:
            raise FitError(f"{self.name}: grid must be an integer >= 2, got {grid}")
        self.grid = int(grid)

    def fit(self, fitter, rival_rms=None):
        return fitter.fit_kernels(self)

    def pairs(self):
        return [(i, j) for i in range(self.grid) for j in range(i, self.grid)]

    def _polylines(self, pairs, S):
        w = S / (self.grid - 1)
        centres = np.arange(self.grid) * w
        rising = [_ramp(centres[j] - w / 2, w, 1.0) for _, j in pairs]
        falling = [_ramp(centres[i] - w / 2, w, 1.0) for i, _ in pairs]
        return rising, falling

    # the penalty's shapes (see penalty); the first is the prior where the record has no
    # minor loops, and with minor loops the held-back cycles choose between them
    PENALTIES = {
        "separable": "mixed differences of the kernel weights (a separable density) and "
                     "second differences of the diagonal ones (a smooth reversible part)",
        "width": "differences of neighbouring kernels along the diagonal (a density of "
                 "the loop width)",
    }

    def penalty(self, pairs, shape="separable"):
        """D^T D of the differences that the kernel weights w_ij are pulled towards zero
        where the data cannot decide (docs/theory/identification.md, "What a major loop
        leaves open"). ``shape`` "separable":

            mixed:      w_ij - w_i+1,j - w_i,j+1 + w_i+1,j+1      (off the diagonal)
            reversible: sqrt(REVERSIBLE_SMOOTHING) (w_ii - 2 w_i+1,i+1 + w_i+2,i+2)

        A major loop fixes the loop width at each input, not how the density is spread
        along the diagonal, nor how much of the mean branch is reversible. The first
        rows make the density additively separable, w_ij = a_i + b_j (a PI density
        of linear width profile is one such); the second make the reversible part (the
        diagonal kernels) a smooth curve, so the mean branch's curvature is left to the
        hysteretic kernels. Measured on 49 random Preisach actuators recorded on a
        two-cycle triangle (no creep): ramps and staircases 0.18 / 0.49 / 0.67 % of
        range (median / p90 / max), against 0.24 / 0.57 / 1.37 % with ``shape``
        "width": w_ij - w_i+1,j+1, a density of the loop width alone (a PI density)."""
        if shape not in self.PENALTIES:
            raise FitError(f"{self.name}: unknown penalty {shape!r}; expected one of "
                           f"{', '.join(self.PENALTIES)}")
        index = {p: k for k, p in enumerate(pairs)}
        rows = []

        def row(entries):
            r = np.zeros(len(pairs))
            for k, v in entries:
                r[k] = v
            rows.append(r)

        for (i, j), k in index.items():
            if shape == "width":
                nb = index.get((i + 1, j + 1))
                if nb is not None:
                    row([(k, 1.0), (nb, -1.0)])
                continue
            square = [index.get(p) for p in ((i + 1, j), (i, j + 1), (i + 1, j + 1))]
            if j >= i + 2 and None not in square:
                row([(k, 1.0), (square[0], -1.0), (square[1], -1.0), (square[2], 1.0)])
            line = [index.get((i + d, i + d)) for d in (1, 2)]
            if i == j and None not in line:
                c = np.sqrt(REVERSIBLE_SMOOTHING)
                row([(k, c), (line[0], -2.0 * c), (line[1], c)])
        if not rows:
            return np.zeros((len(pairs), len(pairs)))
        D = np.array(rows)
        return D.T @ D

    def options(self, S):
        return {"grid": self.grid}

    def _args(self):
        return {"grid": self.grid}


class BoucWen(Family):
    """Not a PI family: a :class:`pihyst.model.BoucWenModel` (remanence, minor loops that
    drift), its linear part by bounded least squares and its shape (beta, gamma, n) by an
    outer search (:mod:`pihyst.identify._boucwen`, docs/theory/bouc-wen.md). ``n``: a
    fixed exponent, or None to search it."""

    name = "bouc-wen"
    title = "Bouc-Wen"
    has_thresholds = False
    # its minor loops follow from the shape (beta, gamma, n) the major loop identifies:
    # three parameters of a differential equation, none of them seen only inside the range
    minor_loops_fixed = True
    # its compensator iterates (Newton on the Runge-Kutta step): 0.2-6 us per tracking
    # sample, up to hundreds of us on jumps (benchmarks/bench_boucwen.py)
    piecewise_linear_inverse = False

    def __init__(self, n=None):
        self.n = None if n is None else float(n)

    def fit(self, fitter, rival_rms=None):
        from pihyst.identify._boucwen import family_fit
        return family_fit(self, fitter, rival_rms)

    def template(self, thresholds, S):
        raise FitError("bouc-wen has no PI operators (it is fitted by its own search)")

    def final_model(self, thresholds, weights, offset, state_v, lo, S):
        raise FitError("bouc-wen has no PI operators (it is fitted by its own search)")

    def options(self, S):
        return {"n": self.n}

    def _args(self):
        return {} if self.n is None else {"n": self.n}


FAMILIES = {cls.name: cls for cls in (Classical, Multislope, MultislopeIdentified,
                                        ModifiedPI, KrasnoselskiiPokrovskii, BoucWen)}
# the default comparison: every family
FAMILY_NAMES = tuple(FAMILIES)
# the PI families (models of play-type operators: thresholds, weights, the C export)
PI_FAMILY_NAMES = tuple(name for name in FAMILIES if name != BoucWen.name)
# the families whose models can carry creep (docs/theory/creep.md): every one
CREEP_FAMILIES = FAMILY_NAMES


def as_family(spec):
    """A family object from a name (its default options) or a family object."""
    if isinstance(spec, Family):
        return spec
    if isinstance(spec, str) and spec in FAMILIES:
        return FAMILIES[spec]()
    raise FitError(f"unknown model family {spec!r}; expected one of {', '.join(FAMILIES)} "
                   f"or a family object such as pihyst.identify.Classical()")
