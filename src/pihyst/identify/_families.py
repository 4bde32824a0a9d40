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
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pihyst.exceptions import FitError
from pihyst.identify._shape import identify_shape, refine_shape
from pihyst.model import ClassicalPI, MultislopePI, PiecewiseLinearPI, PIModel

PAPER_A, PAPER_B, PAPER_H = 0.8, 1.2, 0.5


def multislope_max_threshold(U: float, a: float, h: float) -> float:
    """Largest valid multislope threshold, (1 - a)U / (1 - a h) (docs/theory/operators.md)."""
    return (1 - a) * U / (1 - a * h)


def _line(S: float, slope: float,
          intercept: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """A straight polyline y = slope v + intercept (two points, extended by the core)."""
    x = np.array([0.0, S])
    return (x, slope * x + intercept)


def _ramp(start: float, length: float,
          height: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """0 below ``start``, rising linearly to ``height`` over ``length``, flat above."""
    x = np.array([start - length, start, start + length, start + 2 * length])
    return (x, np.array([0.0, 0.0, height, height]))


def multislope_polylines(r: float, S: float, U: float, a: float, b: float,
                         h: float) -> list[tuple[NDArray[np.float64], NDArray[np.float64]]]:
    """Rising and falling envelopes of a multislope operator as polylines on [0, S].

    R(v) = max(a(v - r), b v - r - (b - 1)U)         kink at ((b - 1)U + (1 - a)r)/(b - a)
    F(v) = min(b v, a v + (1 - a)U - (1 - a h) r)    kink at ((1 - a)U - (1 - a h)r)/(b - a)
    """
    def rise(v: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.maximum(a * (v - r), b * v - r - (b - 1) * U)

    def fall(v: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.minimum(b * v, a * v + (1 - a) * U - (1 - a * h) * r)

    out = []
    for env, kink in ((rise, ((b - 1) * U + (1 - a) * r) / (b - a)),
                      (fall, ((1 - a) * U - (1 - a * h) * r) / (b - a))):
        points = [0.0, S]
        if 1e-9 * S < kink < S * (1 - 1e-9):
            points = [0.0, kink, S]
        x = np.array(points)
        out.append((x, env(x)))
    return out


def _shift(polylines: list[Any], lo: float) -> list[Any]:
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

    Examples
    --------
    >>> from pihyst.identify import Classical, Family, ModifiedPI
    >>> isinstance(ModifiedPI(segments=2), Family), Classical().name
    (True, 'classical')
    """

    name: str | None = None
    title: str | None = None
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

    def max_threshold(self, S: float) -> float:
        """The largest useful threshold on the span ``S`` (no limit by default).

        Parameters
        ----------
        S : float
            The span of the input range (the fitting frame is [0, S]).

        Returns
        -------
        float
            The limit (``inf``: none).

        Examples
        --------
        >>> from pihyst.identify import BoucWen
        >>> BoucWen().max_threshold(150.0)
        inf
        """
        return np.inf

    def check_thresholds(self, thresholds: ArrayLike, S: float) -> None:
        """Check explicit thresholds for this family (beyond sorted, distinct, >= 0,
        which every family needs).

        The limit of :meth:`max_threshold` is checked by the data instead (an operator
        the input never moves). By default every threshold is valid.

        Parameters
        ----------
        thresholds : array_like
            The thresholds, in the fitting frame.
        S : float
            The span of the input range.

        Raises
        ------
        FitError
            If a threshold is not valid for this family.

        Examples
        --------
        >>> from pihyst.identify import Classical
        >>> Classical().check_thresholds([0.0, 30.0], 150.0)
        """
        return None

    @abstractmethod
    def template(self, thresholds: ArrayLike, S: float) -> PIModel:
        """Model of v on [0, S] with unit weights.

        Parameters
        ----------
        thresholds : array_like
            The thresholds (or kernels) of the operators.
        S : float
            The span of the input range.

        Returns
        -------
        PIModel
            Columns: the thresholds' operators, then the family's fixed ones.

        Examples
        --------
        >>> from pihyst.identify import Classical
        >>> Classical().template([0.0, 30.0], 150.0).weights.tolist()
        [1.0, 1.0]
        """

    @abstractmethod
    def final_model(self, thresholds: ArrayLike, weights: ArrayLike, offset: float,
                    state_v: ArrayLike, lo: float, S: float) -> PIModel:
        """The fitted model of the raw input u (see the module docstring).

        Parameters
        ----------
        thresholds : array_like
            The thresholds (or kernels) of the operators, in the fitting frame.
        weights : array_like
            The fitted weights.
        offset : float
            The fitted offset, in the fitting frame.
        state_v : array_like
            The operator state before the first sample, in the fitting frame.
        lo : float
            The bottom of the input range (v = u - lo).
        S : float
            The span of the input range.

        Returns
        -------
        PIModel
            The model of u on [lo, lo + S].

        Examples
        --------
        >>> from pihyst.identify import Classical
        >>> model = Classical().final_model([0.0], [0.5], 1.0, [0.0], 10.0, 100.0)
        >>> model.offset
        -4.0
        """

    def raw_state(self, state_v: ArrayLike, lo: float) -> NDArray[np.float64]:
        """Operator state in the raw frame (u) from the fitting frame (v = u - lo).

        Parameters
        ----------
        state_v : array_like
            The operator outputs in the fitting frame.
        lo : float
            The bottom of the input range.

        Returns
        -------
        ndarray
            The operator outputs in the raw frame (unchanged by default).

        Examples
        --------
        >>> from pihyst.identify import Multislope
        >>> Multislope().raw_state([1.0], 10.0).tolist()
        [1.0]
        """
        return np.asarray(state_v, dtype=float)

    def v_state(self, state_u: ArrayLike, lo: float) -> NDArray[np.float64]:
        """Operator state in the fitting frame (v = u - lo) from the raw frame (u).

        Parameters
        ----------
        state_u : array_like
            The operator outputs in the raw frame.
        lo : float
            The bottom of the input range.

        Returns
        -------
        ndarray
            The operator outputs in the fitting frame (unchanged by default).

        Examples
        --------
        >>> from pihyst.identify import Multislope
        >>> Multislope().v_state([1.0], 10.0).tolist()
        [1.0]
        """
        return np.asarray(state_u, dtype=float)

    def fit(self, fitter: Any, rival_rms: float | None = None) -> Any:
        """Fit this family to ``fitter``'s record.

        Default: the thresholds chosen by subset search over
        ``candidates(S, n_candidates)`` (or the fitter's explicit thresholds).

        Parameters
        ----------
        fitter : FamilyFitter
            The record and the options common to all families
            (``pihyst.identify._family_fit``).
        rival_rms : float, optional
            The best judged RMS of the families fitted so far (used by families whose
            search can stop early).

        Returns
        -------
        FamilyFit
            The family fitted on the fitted cycles.

        Examples
        --------
        >>> import numpy as np
        >>> import pihyst
        >>> from pihyst.identify._family_fit import FamilyFitter, FramedRecord
        >>> u = np.tile(np.r_[np.linspace(0, 150, 76), np.linspace(150, 0, 76)[1:]], 3)
        >>> y = pihyst.model.ClassicalPI([0, 30], [0.3, 0.2]).predict(u)
        >>> rec = FramedRecord(u, y, input_range=None, initial_state="zero",
        ...                    holdout=None, offset=True, through=None)
        >>> fitter = FamilyFitter(rec, thresholds=[0.0, 30.0])
        >>> from pihyst.identify import Classical
        >>> [round(float(w), 6) for w in Classical().fit(fitter).weights]
        [0.3, 0.2]
        """
        return fitter.fit_subsets(self)

    def prepare(self, fitter: Any) -> "Family":
        """The family to run the threshold search with (e.g. with an identified shape).

        Parameters
        ----------
        fitter : FamilyFitter
            The record and the options common to all families.

        Returns
        -------
        Family
            This family by default.

        Examples
        --------
        >>> import numpy as np
        >>> import pihyst
        >>> from pihyst.identify._family_fit import FamilyFitter, FramedRecord
        >>> u = np.tile(np.r_[np.linspace(0, 150, 76), np.linspace(150, 0, 76)[1:]], 3)
        >>> y = pihyst.model.ClassicalPI([0, 30], [0.3, 0.2]).predict(u)
        >>> rec = FramedRecord(u, y, input_range=None, initial_state="zero",
        ...                    holdout=None, offset=True, through=None)
        >>> fitter = FamilyFitter(rec, thresholds=[0.0, 30.0])
        >>> from pihyst.identify import Classical
        >>> Classical().prepare(fitter) == Classical()
        True
        """
        return self

    def refine(self, fitter: Any, fitted: Any) -> Any:
        """A better fit of the chosen structure, or ``fitted`` itself.

        Parameters
        ----------
        fitter : FamilyFitter
            The record and the options common to all families.
        fitted : FamilyFit
            The family's fit after the threshold search.

        Returns
        -------
        FamilyFit
            The refined fit (``fitted`` itself by default).

        Examples
        --------
        >>> import numpy as np
        >>> import pihyst
        >>> from pihyst.identify._family_fit import FamilyFitter, FramedRecord
        >>> u = np.tile(np.r_[np.linspace(0, 150, 76), np.linspace(150, 0, 76)[1:]], 3)
        >>> y = pihyst.model.ClassicalPI([0, 30], [0.3, 0.2]).predict(u)
        >>> rec = FramedRecord(u, y, input_range=None, initial_state="zero",
        ...                    holdout=None, offset=True, through=None)
        >>> fitter = FamilyFitter(rec, thresholds=[0.0, 30.0])
        >>> from pihyst.identify import Classical
        >>> fitted = Classical().fit(fitter)
        >>> Classical().refine(fitter, fitted) is fitted
        True
        """
        return fitted

    def options(self, S: float) -> dict[str, Any]:
        """This family's own options as the report shows them (resolved on span S).

        Parameters
        ----------
        S : float
            The span of the input range.

        Returns
        -------
        dict
            The options by name (none by default).

        Examples
        --------
        >>> from pihyst.identify import Classical
        >>> Classical().options(150.0)
        {}
        """
        return {}

    def __eq__(self, other: object) -> bool:
        return type(self) is type(other) and self.__dict__ == other.__dict__

    def __hash__(self) -> int:
        return hash((type(self), tuple(sorted(self.__dict__.items()))))

    def __repr__(self) -> str:
        args = ", ".join(f"{k}={v!r}" for k, v in self._args().items())
        return f"{type(self).__name__}({args})"

    def _args(self) -> dict[str, Any]:
        return {}


class Classical(Family):
    """Classical PI: play operators of the chosen thresholds (a :class:`ClassicalPI`).

    Examples
    --------
    >>> import numpy as np
    >>> import pihyst
    >>> u = np.tile(np.r_[np.linspace(0, 150, 76), np.linspace(150, 0, 76)[1:]], 3)
    >>> y = pihyst.model.ClassicalPI([0, 30], [0.3, 0.2]).predict(u)
    >>> res = pihyst.fit(u, y, family=pihyst.identify.Classical(), thresholds=[0, 30])
    >>> res.model.family
    'classical'
    """

    name = "classical"
    title = "classical PI"

    def candidates(self, S: float, n_candidates: int) -> NDArray[np.float64]:
        """The default candidate thresholds: ``n_candidates`` equally spaced on [0, S/2).

        After a full sweep, an operator with r >= S/2 never moves again (R <= S - r <= r
        <= F on [0, S]): its output is a constant.

        Parameters
        ----------
        S : float
            The span of the input range.
        n_candidates : int
            How many candidates.

        Returns
        -------
        ndarray
            The candidate thresholds.

        Examples
        --------
        >>> Classical().candidates(100.0, 4).tolist()
        [0.0, 12.5, 25.0, 37.5]
        """
        return np.asarray(np.arange(n_candidates) * (0.5 * S / n_candidates), dtype=np.float64)

    def max_threshold(self, S: float) -> float:
        """The largest useful threshold, S/2 (above it an operator never moves).

        Parameters
        ----------
        S : float
            The span of the input range.

        Returns
        -------
        float
            S/2.

        Examples
        --------
        >>> Classical().max_threshold(150.0)
        75.0
        """
        return 0.5 * S

    def template(self, thresholds: ArrayLike, S: float) -> ClassicalPI:
        """A :class:`ClassicalPI` of v on [0, S] with unit weights.

        Parameters
        ----------
        thresholds : array_like
            The play operators' thresholds.
        S : float
            The span of the input range.

        Returns
        -------
        ClassicalPI
            One operator per threshold.

        Examples
        --------
        >>> Classical().template([0.0, 30.0], 150.0).input_range
        (0.0, 150.0)
        """
        return ClassicalPI(thresholds, np.ones(len(np.asarray(thresholds))),
                           input_range=(0.0, S))

    def final_model(self, thresholds: ArrayLike, weights: ArrayLike, offset: float,
                    state_v: ArrayLike, lo: float, S: float) -> ClassicalPI:
        """The fitted :class:`ClassicalPI` of the raw input u = v + lo.

        The same thresholds and weights, offset ``offset - lo * sum(weights)``, state
        ``state_v + lo``.

        Parameters
        ----------
        thresholds : array_like
            The thresholds.
        weights : array_like
            The fitted weights.
        offset : float
            The fitted offset, in the fitting frame.
        state_v : array_like
            The operator state before the first sample, in the fitting frame.
        lo : float
            The bottom of the input range.
        S : float
            The span of the input range.

        Returns
        -------
        ClassicalPI
            The model of u on [lo, lo + S].

        Examples
        --------
        >>> model = Classical().final_model([0.0], [0.5], 1.0, [0.0], 10.0, 100.0)
        >>> model.input_range, model.offset
        ((10.0, 110.0), -4.0)
        """
        w = np.asarray(weights, dtype=float)
        return ClassicalPI(thresholds, w, offset=offset - lo * w.sum(),
                           input_range=(lo, lo + S), initial_state=self.raw_state(state_v, lo))

    def raw_state(self, state_v: ArrayLike, lo: float) -> NDArray[np.float64]:
        """Play outputs in the raw frame: ``state_v + lo``.

        Parameters
        ----------
        state_v : array_like
            The operator outputs in the fitting frame.
        lo : float
            The bottom of the input range.

        Returns
        -------
        ndarray
            The operator outputs in the raw frame.

        Examples
        --------
        >>> Classical().raw_state([1.0], 10.0).tolist()
        [11.0]
        """
        return np.asarray(state_v, dtype=float) + lo

    def v_state(self, state_u: ArrayLike, lo: float) -> NDArray[np.float64]:
        """Play outputs in the fitting frame: ``state_u - lo``.

        Parameters
        ----------
        state_u : array_like
            The operator outputs in the raw frame.
        lo : float
            The bottom of the input range.

        Returns
        -------
        ndarray
            The operator outputs in the fitting frame.

        Examples
        --------
        >>> Classical().v_state([11.0], 10.0).tolist()
        [1.0]
        """
        return np.asarray(state_u, dtype=float) - lo


SHAPE_KEYS = ("U", "a", "b", "h")


class Multislope(Family):
    """Multislope PI of Xu et al. (2020), eq. 6, with a fixed shape {"U", "a", "b", "h"}
    (default the paper's a = 0.8, b = 1.2, h = 0.5; U defaults to the data's span S,
    the top of the range in the fitting frame).

    Parameters
    ----------
    shape : dict, optional
        Some or all of ``"U"``, ``"a"``, ``"b"``, ``"h"`` (numbers; U None: the span).

    Raises
    ------
    FitError
        An unknown shape parameter, or a value that is not a number.

    Examples
    --------
    >>> from pihyst.identify import Multislope
    >>> Multislope(shape={"a": 0.7}).shape(150.0)
    {'U': 150.0, 'a': 0.7, 'b': 1.2, 'h': 0.5}
    """

    name = "multislope"
    title = "multislope PI (paper's shape)"
    # its geometry is anchored at the top of the range U, not at the last turning
    # point: after a reversal at M inside the range an operator holds flat for
    # 75 + r/2 - M/2 V (the paper's shape, docs/theory/operators.md), so its minor loops
    # are not those of a Preisach-type material (Masing's rule), and a record of major
    # loops alone says nothing about them
    minor_loops_fixed = False

    def __init__(self, shape: Mapping[str, Any] | None = None) -> None:
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

    def with_shape(self, **shape: float | None) -> "Multislope":
        """This family with some shape parameters replaced.

        Parameters
        ----------
        **shape : float or None
            Any of ``U``, ``a``, ``b``, ``h``.

        Returns
        -------
        Multislope
            A copy (of the same class); this family is unchanged.

        Raises
        ------
        FitError
            An unknown shape parameter, or a value that is not a number.

        Examples
        --------
        >>> Multislope().with_shape(h=0.4).shape(150.0)["h"]
        0.4
        """
        out = copy.copy(self)
        Multislope.__init__(out, {**self._shape_dict(), **shape})
        return out

    def _shape_dict(self) -> dict[str, Any]:
        return {"U": self.U, "a": self.a, "b": self.b, "h": self.h}

    def shape(self, S: float) -> dict[str, Any]:
        """The shape resolved on the span ``S`` (U None: ``S``).

        Parameters
        ----------
        S : float
            The span of the input range.

        Returns
        -------
        dict
            ``"U"``, ``"a"``, ``"b"``, ``"h"``.

        Examples
        --------
        >>> Multislope().shape(100.0)
        {'U': 100.0, 'a': 0.8, 'b': 1.2, 'h': 0.5}
        """
        return {"U": S if self.U is None else float(self.U), "a": self.a, "b": self.b,
                "h": self.h}

    def max_threshold(self, S: float) -> float:
        """The largest valid threshold, (1 - a)U / (1 - a h).

        Parameters
        ----------
        S : float
            The span of the input range.

        Returns
        -------
        float
            The limit for this shape.

        Examples
        --------
        >>> round(Multislope().max_threshold(150.0), 6)
        50.0
        """
        s = self.shape(S)
        return float(multislope_max_threshold(s["U"], s["a"], s["h"]))

    def check_thresholds(self, thresholds: ArrayLike, S: float) -> None:
        """Check that no explicit threshold is above :meth:`max_threshold`.

        Parameters
        ----------
        thresholds : array_like
            The thresholds, in the fitting frame.
        S : float
            The span of the input range.

        Raises
        ------
        FitError
            If a threshold is above (1 - a)U / (1 - a h).

        Examples
        --------
        >>> Multislope().check_thresholds([0.0, 60.0], 150.0)  # doctest: +ELLIPSIS
        Traceback (most recent call last):
        ...
        pihyst.exceptions.FitError: multislope: threshold 60 is above (1 - a)U/(1 - a h) = 50 ...
        """
        limit = self.max_threshold(S)
        if np.max(thresholds) > limit * (1 + 1e-12):
            s = self.shape(S)
            raise FitError(f"{self.name}: threshold {np.max(thresholds):g} is above "
                           f"(1 - a)U/(1 - a h) = {limit:g} for U={s['U']:g}, a={s['a']:g}, "
                           f"h={s['h']:g}", column="input")

    def candidates(self, S: float, n_candidates: int) -> NDArray[np.float64]:
        """The default candidate thresholds: ``n_candidates`` equally spaced over the valid
        range [0, (1 - a)U / (1 - a h)], both ends included.

        Parameters
        ----------
        S : float
            The span of the input range.
        n_candidates : int
            How many candidates.

        Returns
        -------
        ndarray
            The candidate thresholds.

        Examples
        --------
        >>> Multislope().candidates(150.0, 3).round(6).tolist()
        [0.0, 25.0, 50.0]
        """
        return np.linspace(0.0, self.max_threshold(S), n_candidates)

    def template(self, thresholds: ArrayLike, S: float) -> MultislopePI:
        """A :class:`MultislopePI` of v on [0, S] with unit weights and this shape.

        Parameters
        ----------
        thresholds : array_like
            The operators' thresholds.
        S : float
            The span of the input range.

        Returns
        -------
        MultislopePI
            One operator per threshold.

        Examples
        --------
        >>> Multislope().template([0.0, 30.0], 150.0).weights.tolist()
        [1.0, 1.0]
        """
        return MultislopePI(thresholds, np.ones(len(np.asarray(thresholds))),
                            input_range=(0.0, S), **self.shape(S))

    def final_model(self, thresholds: ArrayLike, weights: ArrayLike, offset: float,
                    state_v: ArrayLike, lo: float,
                    S: float) -> MultislopePI | PiecewiseLinearPI:
        """The fitted model of the raw input u = v + lo.

        A :class:`MultislopePI` when the range starts at 0, else a
        :class:`PiecewiseLinearPI` whose polylines are the multislope envelopes moved by
        ``lo``.

        Parameters
        ----------
        thresholds : array_like
            The thresholds.
        weights : array_like
            The fitted weights.
        offset : float
            The fitted offset.
        state_v : array_like
            The operator state before the first sample, in the fitting frame.
        lo : float
            The bottom of the input range.
        S : float
            The span of the input range.

        Returns
        -------
        MultislopePI or PiecewiseLinearPI
            The model of u on [lo, lo + S].

        Examples
        --------
        >>> m = Multislope().final_model([0.0], [1.0], 0.0, [0.0], 10.0, 100.0)
        >>> m.family, m.input_range
        ('pwl', (10.0, 110.0))
        """
        s = self.shape(S)
        if lo == 0.0:
            return MultislopePI(thresholds, weights, offset=offset, input_range=(0.0, S),
                                initial_state=state_v, **s)
        polys = [multislope_polylines(r, S, s["U"], s["a"], s["b"], s["h"])
                 for r in np.asarray(thresholds, dtype=float)]
        return PiecewiseLinearPI(_shift([p[0] for p in polys], lo),
                                 _shift([p[1] for p in polys], lo), weights, offset=offset,
                                 input_range=(lo, lo + S), initial_state=state_v)

    def options(self, S: float) -> dict[str, Any]:
        """The shape, as the report shows it.

        Parameters
        ----------
        S : float
            The span of the input range.

        Returns
        -------
        dict
            ``{"shape": {"U": ..., "a": ..., "b": ..., "h": ...}}``.

        Examples
        --------
        >>> Multislope().options(150.0)["shape"]["U"]
        150.0
        """
        return {"shape": {k: float(v) for k, v in self.shape(S).items()}}

    def _args(self) -> dict[str, Any]:
        return {"shape": self._shape_dict()}


class MultislopeIdentified(Multislope):
    """Multislope PI whose shape (a, b, h; with ``identify="with-U"`` U too) is
    identified from the data, starting from ``shape`` (default the paper's); see
    docs/theory/identification.md. ``identify=False`` keeps the starting shape.

    Parameters
    ----------
    shape : dict, optional
        The starting shape: some or all of ``"U"``, ``"a"``, ``"b"``, ``"h"``.
    identify : bool or "with-U"
        True: identify a, b, h; ``"with-U"``: U too; False: keep the starting shape.

    Raises
    ------
    FitError
        An unknown shape parameter, or ``identify`` not True, False or "with-U".

    Examples
    --------
    >>> from pihyst.identify import MultislopeIdentified
    >>> MultislopeIdentified(identify="with-U")
    MultislopeIdentified(shape={'U': None, 'a': 0.8, 'b': 1.2, 'h': 0.5}, identify='with-U')
    """

    name = "multislope-identified"
    title = "multislope PI (identified shape)"

    def __init__(self, shape: Mapping[str, Any] | None = None,
                 identify: bool | str = True) -> None:
        super().__init__(shape)
        if identify not in (True, False, "with-U"):
            raise FitError(f"{self.name}: identify must be True, False or 'with-U', got "
                           f"{identify!r}")
        self.identify = identify

    def prepare(self, fitter: Any) -> Family:
        """This family with its shape identified from ``fitter``'s record (itself when
        ``identify=False``).

        Parameters
        ----------
        fitter : FamilyFitter
            The record and the options common to all families.

        Returns
        -------
        Family
            The family to run the threshold search with.

        Examples
        --------
        >>> import numpy as np
        >>> import pihyst
        >>> from pihyst.identify._family_fit import FamilyFitter, FramedRecord
        >>> u = np.tile(np.r_[np.linspace(0, 150, 76), np.linspace(150, 0, 76)[1:]], 3)
        >>> y = pihyst.model.ClassicalPI([0, 30], [0.3, 0.2]).predict(u)
        >>> rec = FramedRecord(u, y, input_range=None, initial_state="zero",
        ...                    holdout=None, offset=True, through=None)
        >>> fitter = FamilyFitter(rec, thresholds=[0.0, 30.0])
        >>> family = MultislopeIdentified(identify=False)
        >>> family.prepare(fitter) is family
        True
        """
        return identify_shape(fitter, self) if self.identify else self

    def refine(self, fitter: Any, fitted: Any) -> Any:
        """The chosen thresholds' fit with the shape refined with them (``fitted`` itself
        with explicit thresholds or ``identify=False``).

        Parameters
        ----------
        fitter : FamilyFitter
            The record and the options common to all families.
        fitted : FamilyFit
            The family's fit after the threshold search.

        Returns
        -------
        FamilyFit
            The refined fit.

        Examples
        --------
        >>> import numpy as np
        >>> import pihyst
        >>> from pihyst.identify._family_fit import FamilyFitter, FramedRecord
        >>> u = np.tile(np.r_[np.linspace(0, 150, 76), np.linspace(150, 0, 76)[1:]], 3)
        >>> y = pihyst.model.ClassicalPI([0, 30], [0.3, 0.2]).predict(u)
        >>> rec = FramedRecord(u, y, input_range=None, initial_state="zero",
        ...                    holdout=None, offset=True, through=None)
        >>> fitter = FamilyFitter(rec, thresholds=[0.0, 30.0])
        >>> family = MultislopeIdentified(identify=False)
        >>> fitted = family.fit(fitter)
        >>> family.refine(fitter, fitted) is fitted
        True
        """
        if not self.identify or fitted.threshold_choice is None:
            return fitted            # explicit thresholds: nothing was chosen
        return refine_shape(fitter, fitted)

    def _args(self) -> dict[str, Any]:
        return {"shape": self._shape_dict(), "identify": self.identify}


class PolylineFamily(Family):
    """A family whose operators are polylines (``_polylines``): its models are
    PiecewiseLinearPI, moved by lo along the input axis in the raw frame."""

    @abstractmethod
    def _polylines(self, thresholds: Any, S: float) -> tuple[list[Any], list[Any]]:
        """(rising, falling) polylines of the operators on [0, S]."""

    def template(self, thresholds: Any, S: float) -> PiecewiseLinearPI:
        """A :class:`PiecewiseLinearPI` of v on [0, S] with unit weights.

        Parameters
        ----------
        thresholds : array_like or list of (int, int)
            The operators' thresholds (or, for kp, kernels).
        S : float
            The span of the input range.

        Returns
        -------
        PiecewiseLinearPI
            The thresholds' operators, then the family's fixed ones.

        Examples
        --------
        >>> from pihyst.identify import ModifiedPI
        >>> ModifiedPI(segments=2).template([30.0], 150.0).n_operators
        3
        """
        rising, falling = self._polylines(thresholds, S)
        return PiecewiseLinearPI(rising, falling, np.ones(len(rising)), input_range=(0.0, S))

    def final_model(self, thresholds: Any, weights: ArrayLike, offset: float,
                    state_v: ArrayLike, lo: float, S: float) -> PiecewiseLinearPI:
        """The fitted :class:`PiecewiseLinearPI` of the raw input u = v + lo: the same
        polylines moved by ``lo`` along the input axis.

        Parameters
        ----------
        thresholds : array_like or list of (int, int)
            The operators' thresholds (or, for kp, kernels).
        weights : array_like
            The fitted weights.
        offset : float
            The fitted offset.
        state_v : array_like
            The operator state before the first sample.
        lo : float
            The bottom of the input range.
        S : float
            The span of the input range.

        Returns
        -------
        PiecewiseLinearPI
            The model of u on [lo, lo + S].

        Examples
        --------
        >>> from pihyst.identify import ModifiedPI
        >>> m = ModifiedPI(segments=1).final_model([30.0], [0.2, 0.4], 0.0, [0.0, 0.0],
        ...                                        10.0, 100.0)
        >>> m.input_range
        (10.0, 110.0)
        """
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
    piecewise-linear rather than polynomial input function).

    Parameters
    ----------
    segments : int
        Equal segments of the input function.

    Raises
    ------
    FitError
        If ``segments`` is not a positive integer.

    Examples
    --------
    >>> from pihyst.identify import ModifiedPI
    >>> ModifiedPI(segments=8).n_fixed
    8
    """

    name = "modified-pi"
    title = "classical PI + monotone input function"

    def __init__(self, segments: int = 4) -> None:
        if int(segments) != segments or segments < 1:
            raise FitError(f"{self.name}: segments must be a positive integer, got {segments}")
        self.segments = int(segments)

    @property
    def n_fixed(self) -> int:  # type: ignore[override]
        """The input function's operators, after the thresholds'."""
        return self.segments

    def candidates(self, S: float, n_candidates: int) -> NDArray[np.float64]:
        """The default candidate thresholds: ``n_candidates`` equally spaced inside
        (0, S/2).

        r = 0 is left out: that play is R = F = v, the sum of the input segments.

        Parameters
        ----------
        S : float
            The span of the input range.
        n_candidates : int
            How many candidates.

        Returns
        -------
        ndarray
            The candidate thresholds.

        Examples
        --------
        >>> ModifiedPI().candidates(100.0, 4).tolist()
        [10.0, 20.0, 30.0, 40.0]
        """
        return np.asarray(np.arange(1, n_candidates + 1) * (0.5 * S / (n_candidates + 1)),
                          dtype=np.float64)

    def max_threshold(self, S: float) -> float:
        """The largest useful threshold, S/2.

        Parameters
        ----------
        S : float
            The span of the input range.

        Returns
        -------
        float
            S/2.

        Examples
        --------
        >>> ModifiedPI().max_threshold(150.0)
        75.0
        """
        return 0.5 * S

    def _polylines(self, thresholds: Any, S: float) -> tuple[list[Any], list[Any]]:
        rising: list[Any] = []
        falling: list[Any] = []
        for r in thresholds:
            rising.append(_line(S, 1.0, -r))     # R(v) = v - r
            falling.append(_line(S, 1.0, r))     # F(v) = v + r
        edges = np.linspace(0.0, S, self.segments + 1)
        for s0, s1 in zip(edges[:-1], edges[1:]):
            g = _ramp(s0, s1 - s0, s1 - s0)      # R(v) = F(v) = clamp(v, s0, s1) - s0
            rising.append(g)
            falling.append(g)
        return rising, falling

    def options(self, S: float) -> dict[str, Any]:
        """The number of segments, as the report shows it.

        Parameters
        ----------
        S : float
            The span of the input range.

        Returns
        -------
        dict
            ``{"input_function_segments": segments}``.

        Examples
        --------
        >>> ModifiedPI(segments=2).options(150.0)
        {'input_function_segments': 2}
        """
        return {"input_function_segments": self.segments}

    def _args(self) -> dict[str, Any]:
        return {"segments": self.segments}


# weight of the reversible part's smoothness against the density's in the KP penalty
REVERSIBLE_SMOOTHING = 10.0


class KrasnoselskiiPokrovskii(PolylineFamily):
    """Krasnosel'skii-Pokrovskii kernels (docs/theory/identification.md): ramp-smoothed relays
    R(v) = sat((v - c_j)/w + 1/2), F(v) = sat((v - c_i)/w + 1/2), c_i <= c_j on a grid of
    ``grid`` centres over [0, S], width w = S/(grid - 1); sat clamps to [0, 1]. A
    Preisach-type basis: captures asymmetric loops; where the data cannot decide, its
    weights are regularized towards an additively separable density and a smooth
    reversible part (see :meth:`penalty`).

    Parameters
    ----------
    grid : int
        Kernel centres over the range (``grid * (grid + 1) / 2`` kernels).

    Raises
    ------
    FitError
        If ``grid`` is not an integer >= 2.

    Examples
    --------
    >>> from pihyst.identify import KrasnoselskiiPokrovskii
    >>> len(KrasnoselskiiPokrovskii(grid=4).pairs())
    10
    """

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

    def __init__(self, grid: int = 16) -> None:
        if int(grid) != grid or grid < 2:
            raise FitError(f"{self.name}: grid must be an integer >= 2, got {grid}")
        self.grid = int(grid)

    def fit(self, fitter: Any, rival_rms: float | None = None) -> Any:
        """Fit the kernel weights to ``fitter``'s record, regularized (the weight of the
        penalty chosen on the held-back data).

        Parameters
        ----------
        fitter : FamilyFitter
            The record and the options common to all families.
        rival_rms : float, optional
            The best judged RMS of the families fitted so far (not used by kp).

        Returns
        -------
        FamilyFit
            The family fitted on the fitted cycles.

        Examples
        --------
        >>> import numpy as np
        >>> import pihyst
        >>> from pihyst.identify._family_fit import FamilyFitter, FramedRecord
        >>> u = np.tile(np.r_[np.linspace(0, 150, 76), np.linspace(150, 0, 76)[1:]], 3)
        >>> y = pihyst.model.ClassicalPI([0, 30], [0.3, 0.2]).predict(u)
        >>> rec = FramedRecord(u, y, input_range=None, initial_state="zero",
        ...                    holdout=None, offset=True, through=None)
        >>> fitted = KrasnoselskiiPokrovskii(grid=3).fit(FamilyFitter(rec))
        >>> fitted.name, len(fitted.operators) <= 6
        ('kp', True)
        """
        return fitter.fit_kernels(self)

    def pairs(self) -> list[tuple[int, int]]:
        """The kernels: index pairs (i, j), i <= j, of the grid's centres.

        Returns
        -------
        list of (int, int)
            Every pair, row by row.

        Examples
        --------
        >>> KrasnoselskiiPokrovskii(grid=2).pairs()
        [(0, 0), (0, 1), (1, 1)]
        """
        return [(i, j) for i in range(self.grid) for j in range(i, self.grid)]

    def _polylines(self, pairs: Any, S: float) -> tuple[list[Any], list[Any]]:
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

    def penalty(self, pairs: list[tuple[int, int]],
                shape: str = "separable") -> NDArray[np.float64]:
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
        "width": w_ij - w_i+1,j+1, a density of the loop width alone (a PI density).

        Parameters
        ----------
        pairs : list of (int, int)
            The kernels, as :meth:`pairs` gives them.
        shape : {"separable", "width"}
            The penalty's shape (``PENALTIES``).

        Returns
        -------
        ndarray
            D^T D, one row and column per kernel.

        Raises
        ------
        FitError
            An unknown ``shape``.

        Examples
        --------
        >>> kp = KrasnoselskiiPokrovskii(grid=2)
        >>> kp.penalty(kp.pairs(), "width").tolist()
        [[1.0, 0.0, -1.0], [0.0, 0.0, 0.0], [-1.0, 0.0, 1.0]]
        """
        if shape not in self.PENALTIES:
            raise FitError(f"{self.name}: unknown penalty {shape!r}; expected one of "
                           f"{', '.join(self.PENALTIES)}")
        index = {p: k for k, p in enumerate(pairs)}
        rows: list[NDArray[np.float64]] = []

        def row(entries: list[tuple[Any, float]]) -> None:
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

    def options(self, S: float) -> dict[str, Any]:
        """The grid, as the report shows it.

        Parameters
        ----------
        S : float
            The span of the input range.

        Returns
        -------
        dict
            ``{"grid": grid}``.

        Examples
        --------
        >>> KrasnoselskiiPokrovskii(grid=4).options(150.0)
        {'grid': 4}
        """
        return {"grid": self.grid}

    def _args(self) -> dict[str, Any]:
        return {"grid": self.grid}


class BoucWen(Family):
    """Not a PI family: a :class:`pihyst.model.BoucWenModel` (remanence, minor loops that
    drift), its linear part by bounded least squares and its shape (beta, gamma, n) by an
    outer search (:mod:`pihyst.identify._boucwen`, docs/theory/bouc-wen.md). ``n``: a
    fixed exponent, or None to search it.

    Parameters
    ----------
    n : float, optional
        A fixed exponent, or None to search it.

    Examples
    --------
    >>> from pihyst.identify import BoucWen
    >>> BoucWen(n=1), BoucWen().options(150.0)
    (BoucWen(n=1.0), {'n': None})
    """

    name = "bouc-wen"
    title = "Bouc-Wen"
    has_thresholds = False
    # its minor loops follow from the shape (beta, gamma, n) the major loop identifies:
    # three parameters of a differential equation, none of them seen only inside the range
    minor_loops_fixed = True
    # its compensator iterates (Newton on the Runge-Kutta step): 0.2-6 us per tracking
    # sample, up to hundreds of us on jumps (benchmarks/bench_boucwen.py)
    piecewise_linear_inverse = False

    def __init__(self, n: float | None = None) -> None:
        self.n = None if n is None else float(n)

    def fit(self, fitter: Any, rival_rms: float | None = None) -> Any:
        """Fit a Bouc-Wen model to ``fitter``'s record: its linear part by bounded least
        squares, its shape by an outer search (docs/theory/bouc-wen.md).

        Parameters
        ----------
        fitter : FamilyFitter
            The record and the options common to all families.
        rival_rms : float, optional
            The best judged RMS of the PI families fitted so far: the search stops early
            when it cannot come near it.

        Returns
        -------
        FamilyFit
            The family fitted on the fitted cycles.

        Examples
        --------
        :func:`pihyst.fit` calls it for ``family="bouc-wen"``:

        >>> import numpy as np
        >>> import pihyst
        >>> u = np.tile(np.r_[np.linspace(0, 150, 31), np.linspace(150, 0, 31)[1:]], 3)
        >>> y = pihyst.model.ClassicalPI([0, 30], [0.3, 0.2]).predict(u)
        >>> res = pihyst.fit(u, y, family=BoucWen(n=1))
        >>> res.report.chosen
        'bouc-wen'
        """
        from pihyst.identify._boucwen import family_fit
        return family_fit(self, fitter, rival_rms)

    def template(self, thresholds: ArrayLike, S: float) -> PIModel:
        """Not defined: Bouc-Wen has no PI operators.

        Parameters
        ----------
        thresholds : array_like
            Not used.
        S : float
            Not used.

        Returns
        -------
        PIModel
            Never: it raises.

        Raises
        ------
        FitError
            Always (the family is fitted by its own search).

        Examples
        --------
        >>> BoucWen().template([0.0], 150.0)
        Traceback (most recent call last):
        ...
        pihyst.exceptions.FitError: bouc-wen has no PI operators (it is fitted by its own search)
        """
        raise FitError("bouc-wen has no PI operators (it is fitted by its own search)")

    def final_model(self, thresholds: ArrayLike, weights: ArrayLike, offset: float,
                    state_v: ArrayLike, lo: float, S: float) -> PIModel:
        """Not defined: Bouc-Wen has no PI operators.

        Parameters
        ----------
        thresholds : array_like
            Not used.
        weights : array_like
            Not used.
        offset : float
            Not used.
        state_v : array_like
            Not used.
        lo : float
            Not used.
        S : float
            Not used.

        Returns
        -------
        PIModel
            Never: it raises.

        Raises
        ------
        FitError
            Always (the family is fitted by its own search).

        Examples
        --------
        >>> BoucWen().final_model([0.0], [1.0], 0.0, [0.0], 0.0, 150.0)
        Traceback (most recent call last):
        ...
        pihyst.exceptions.FitError: bouc-wen has no PI operators (it is fitted by its own search)
        """
        raise FitError("bouc-wen has no PI operators (it is fitted by its own search)")

    def options(self, S: float) -> dict[str, Any]:
        """The exponent, as the report shows it.

        Parameters
        ----------
        S : float
            The span of the input range.

        Returns
        -------
        dict
            ``{"n": n}`` (None: searched).

        Examples
        --------
        >>> BoucWen(n=2).options(150.0)
        {'n': 2.0}
        """
        return {"n": self.n}

    def _args(self) -> dict[str, Any]:
        return {} if self.n is None else {"n": self.n}


FAMILIES = {cls.name: cls for cls in (Classical, Multislope, MultislopeIdentified,
                                        ModifiedPI, KrasnoselskiiPokrovskii, BoucWen)}
# the default comparison: every family
FAMILY_NAMES = tuple(FAMILIES)
# the PI families (models of play-type operators: thresholds, weights, the C export)
PI_FAMILY_NAMES = tuple(name for name in FAMILIES if name != BoucWen.name)
# the families whose models can carry creep (docs/theory/creep.md): every one
CREEP_FAMILIES = FAMILY_NAMES


def as_family(spec: Any) -> Family:
    """A family object from a name (its default options) or a family object."""
    if isinstance(spec, Family):
        return spec
    if isinstance(spec, str) and spec in FAMILIES:
        return FAMILIES[spec]()
    raise FitError(f"unknown model family {spec!r}; expected one of {', '.join(FAMILIES)} "
                   f"or a family object such as pihyst.identify.Classical()")
