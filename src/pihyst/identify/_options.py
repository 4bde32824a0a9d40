"""The options of one fit, checked once: :class:`FitOptions` (what :func:`pihyst.fit`
takes, as one frozen value the steps of ``_fit`` read and never change).
"""

from dataclasses import dataclass, replace
from typing import Optional

import numpy as np

from pihyst._arguments import check_fit_sizes
from pihyst.exceptions import FitError
from pihyst.identify._families import FAMILY_NAMES, Family, as_family
from pihyst.identify._family_fit import FamilyFitter, FramedRecord
from pihyst.identify._subsets import DEFAULT_MAX_EXHAUSTIVE
from pihyst.model._delay import MAX_DELAY_SAMPLES

DEFAULT_N_CANDIDATES = 16
CREEP_MODES = ("off", "auto", "always")


@dataclass(frozen=True, eq=False)
class FitOptions:
    """Every option of :func:`pihyst.fit` (its docstring says what each does), checked.

    ``families`` are family objects; ``explicit_family`` says whether the user named
    them (a named family's failure is an error, not a skipped row). ``creep`` is one of
    :data:`CREEP_MODES` (``"auto"``: decided on held-back data; ``"off"`` also when the
    record has no sample times) and ``time_constants`` the user's creep time constants.
    """

    families: tuple
    explicit_family: bool = False
    thresholds: Optional[np.ndarray] = None
    n_operators: Optional[int] = None
    candidates: Optional[np.ndarray] = None
    n_candidates: int = DEFAULT_N_CANDIDATES
    offset: object = True
    nonnegative: bool = True
    bounds: object = None
    through: object = None
    initial_state: object = "auto"
    holdout: object = "alternate"
    refit: bool = True
    input_range: object = None
    validate: object = None
    delay: object = "auto"
    max_operators: Optional[int] = None
    max_latency: Optional[float] = None
    max_exhaustive: int = DEFAULT_MAX_EXHAUSTIVE
    creep: str = "off"
    time_constants: Optional[tuple] = None

    @classmethod
    def from_arguments(cls, *, family=None, thresholds=None, n_operators=None,
                       candidates=None, n_candidates=DEFAULT_N_CANDIDATES, offset=True,
                       nonnegative=True, bounds=None, through=None, initial_state="auto",
                       holdout="alternate", refit=True, input_range=None, validate=None,
                       delay="auto", max_operators=None, max_latency=None,
                       max_exhaustive=DEFAULT_MAX_EXHAUSTIVE, has_times=False,
                       creep="auto"):
        """The options of ``fit(...)``'s keywords, or a FitError naming the first one
        that is wrong. ``has_times``: whether the record has sample times (creep needs
        them)."""
        check_fit_sizes(n_candidates=n_candidates, n_operators=n_operators,
                        thresholds=thresholds, candidates=candidates)
        families = _families(family)
        _check_choice_arguments(thresholds, candidates, n_operators)
        _check_bounds(max_operators, max_latency, delay)
        _check_weight_bounds(bounds)
        mode, time_constants = _creep_mode(creep, has_times)
        return cls(
            families=families, explicit_family=family is not None,
            thresholds=_sorted(thresholds, "thresholds"), n_operators=n_operators,
            candidates=_sorted(candidates, "candidates"), n_candidates=n_candidates, offset=offset,
            nonnegative=nonnegative, bounds=bounds, through=through,
            initial_state=initial_state, holdout=holdout, refit=refit,
            input_range=input_range, validate=validate, delay=delay,
            max_operators=max_operators, max_latency=max_latency,
            max_exhaustive=max_exhaustive, creep=mode, time_constants=time_constants)

    def but(self, **changes):
        """These options with ``changes`` (e.g. other families, a given delay)."""
        if "families" in changes:
            changes["families"] = tuple(as_family(f) for f in changes["families"])
        return replace(self, **changes)

    @property
    def chooses_thresholds(self):
        """Whether the user constrained the thresholds (given, candidates or a count)."""
        return (self.thresholds is not None or self.candidates is not None
                or self.n_operators is not None)

    def frame(self, u, y, initial_state=None):
        """The record ``(u, y)`` in the fitting frame, from ``initial_state`` (default:
        the option's)."""
        state = self.initial_state if initial_state is None else initial_state
        return FramedRecord(u, y, input_range=self.input_range, initial_state=state,
                            holdout=self.holdout, offset=self.offset, through=self.through)

    def fitter(self, rec, responses=None):
        """A :class:`FamilyFitter` of the framed record ``rec`` with these options,
        sharing ``responses`` (a ``_responses.Responses``) with the other fits of the
        same input."""
        return FamilyFitter(rec, thresholds=self.thresholds, candidates=self.candidates,
                            n_candidates=self.n_candidates, n_operators=self.n_operators,
                            nonnegative=self.nonnegative, bounds=self.bounds,
                            max_exhaustive=self.max_exhaustive, responses=responses)


def _sorted(values, name):
    if values is None:
        return None
    try:
        return np.sort(np.asarray(values, dtype=float))
    except (TypeError, ValueError):
        raise FitError(f"{name} must be a list of numbers, got {values!r:.40}") from None


def _families(family):
    specs = FAMILY_NAMES if family is None else (
        [family] if isinstance(family, (str, Family)) or not isinstance(family, (list, tuple))
        else list(family))
    families = tuple(as_family(f) for f in specs)
    if len({f.name for f in families}) < len(families):
        raise FitError("each family may be given once (their results are reported by name)")
    return families


def _check_choice_arguments(thresholds, candidates, n_operators):
    if thresholds is not None and candidates is not None:
        raise FitError("give thresholds (used as they are) or candidates (chosen from), "
                       "not both")
    if n_operators is not None and thresholds is not None:
        raise FitError("give thresholds or n_operators (how many to choose), not both")
    if n_operators is not None and (int(n_operators) != n_operators or n_operators < 1):
        raise FitError(f"n_operators must be a positive integer, got {n_operators}")


def _check_bounds(max_operators, max_latency, delay):
    if max_operators is not None and (int(max_operators) != max_operators
                                      or max_operators < 1):
        raise FitError(f"max_operators must be a positive integer, got {max_operators}")
    if max_latency is not None and not (isinstance(max_latency, (int, float))
                                        and max_latency > 0):
        raise FitError(f"max_latency must be a positive number of seconds, got {max_latency!r}")
    if delay != "auto" and not (isinstance(delay, (int, np.integer)) and delay >= 0):
        raise FitError(f"delay must be a number of samples >= 0 or 'auto', got {delay!r}")
    if delay != "auto" and delay > MAX_DELAY_SAMPLES:
        raise FitError(f"delay = {delay} is more than the {MAX_DELAY_SAMPLES:,} samples "
                       f"pihyst holds as an input delay")


def _check_weight_bounds(bounds):
    """``bounds`` as fit takes it: None, or (lower, upper) with each None, a number or
    one number per operator (their count is checked once the operators are known)."""
    if bounds is None:
        return
    if not isinstance(bounds, (list, tuple, np.ndarray)) or np.ndim(bounds) == 0 or \
            len(bounds) != 2:
        raise FitError(f"bounds must be a pair (lower, upper), got {bounds!r:.40}")
    for name, value in zip(("lower", "upper"), bounds):
        if value is None:
            continue
        a = np.asarray(value)
        if a.dtype.kind not in "iuf" or a.ndim > 1 or np.isnan(a).any():
            raise FitError(f"bounds: the {name} bound must be a number or one number per "
                           f"operator (None: no bound), got {value!r:.40}")


def _creep_mode(creep, has_times):
    """(mode, time constants) of fit's ``creep`` argument: "auto" decides on held-back
    data (and is "off" without sample times), True or time constants always fit it."""
    if isinstance(creep, str):
        if creep != "auto":
            raise FitError(f"creep must be 'auto', True, False or time constants (s), got "
                           f"{creep!r}")
        return ("auto" if has_times else "off"), None
    if creep is None or creep is False:
        return "off", None
    if creep is True:
        return "always", None
    try:
        tau = np.sort(np.asarray(creep, dtype=np.float64).ravel())
    except (TypeError, ValueError):
        raise FitError(f"creep must be 'auto', True, False or time constants (s), got "
                       f"{creep!r:.40}") from None
    if tau.size == 0 or not np.all(np.isfinite(tau)) or np.any(tau <= 0):
        raise FitError("creep time constants must be finite and > 0 s")
    return "always", tuple(tau.tolist())
