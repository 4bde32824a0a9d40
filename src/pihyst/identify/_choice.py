"""Which fitted family :func:`pihyst.fit` returns (docs/theory/identification.md,
"Choosing the family").

Each candidate has a judged error (``_assess``: the worst RMS over the record's held-back
cycles and a validation record), an operator count and a compensator latency estimated
from its structure (``_latency``: a cost model, never a clock). The rule:

1. **Eligible**: within ``max_operators`` and ``max_latency`` (worst case), if given;
   and, when the data do not determine the minor loops, only families whose structure
   fixes them (PI-type), unless no such family was fitted.
2. **Accurate enough**: judged RMS within ``TOLERANCE`` (2 %) of the lowest among the
   eligible.
3. **Fastest kind, then smallest**: of those, the families whose compensator solves a
   piecewise-linear equation per sample (every PI family) before those whose compensator
   iterates (Bouc-Wen: Newton on its Runge-Kutta step, 10-100 times the cost per sample,
   far more on jumps), so an iterative model is chosen only when it is more accurate by
   more than the tolerance; then the fewest operators, then the lowest judged error. The
   estimated latency bounds the choice (``max_latency``) and is reported; being computed
   from the model's structure, it is the same on every run, so the same record gives
   the same model.

With nothing held back and no validation record, step 2 compares the BIC on the fitted
data, n ln(RMS^2) + p ln n, instead (the lowest wins; p counts non-zero weights and the
fitted offset), since a fitted error always favours the larger model.
"""

import math
from dataclasses import dataclass, replace

from pihyst.exceptions import FitError
from pihyst.identify._constants import TOLERANCE
from pihyst.identify._decisions import Choice


@dataclass(frozen=True)
class Candidate:
    """A fitted family with what the choice needs."""

    fitted: object            # FamilyFit
    by_kind: dict
    judged_rms: float
    latency: object           # Latency
    excluded: str | None = None      # why it may not be chosen

    @property
    def name(self):
        return self.fitted.name

    @property
    def worst_latency(self):
        """Worst-case seconds per sample; inf without a compensator (negative weights)."""
        return float("inf") if self.latency is None else self.latency.worst


def choose(candidates, *, minor_loops_known, unknown_reason, judged_on_held_back,
           n_fitted, max_operators=None, max_latency=None):
    """The :class:`~pihyst.identify._decisions.Choice` among ``candidates``: the one
    chosen, every candidate with why it was excluded (if it was), the criterion."""
    trusted = any(c.fitted.family.minor_loops_fixed for c in candidates)
    candidates = tuple(replace(c, excluded=_exclusion(c, trusted, minor_loops_known,
                                                      unknown_reason, max_operators,
                                                      max_latency))
                       for c in candidates)
    eligible = [c for c in candidates if c.excluded is None]
    if not eligible:
        raise FitError("no fitted family meets the bounds: " + "; ".join(
            f"{c.name}: {c.excluded}" for c in candidates))
    if judged_on_held_back:
        best = min(c.judged_rms for c in eligible)
        near = [c for c in eligible if c.judged_rms <= best * (1 + TOLERANCE)]
        chosen = min(near, key=lambda c: (not c.fitted.family.piecewise_linear_inverse,
                                          c.fitted.n_operators, c.judged_rms, c.name))
        criterion = (f"a piecewise-linear compensator before an iterative one, then the "
                     f"fewest operators, then the lowest judged error, among the "
                     f"families within {100 * TOLERANCE:g} % of the lowest judged RMS error "
                     f"(the worst of held-back cycles and validation record)")
    else:
        # n ln(RMS^2) as 2 n ln(RMS): the square of a tiny RMS would underflow to 0
        chosen = min(eligible, key=lambda c: 2 * n_fitted * math.log(max(c.judged_rms, 1e-300))
                     + c.fitted.n_params * math.log(n_fitted))
        criterion = "lowest BIC on the fitted data (nothing held back)"
    bounds = [f"max_operators = {max_operators}" if max_operators is not None else None,
              f"max_latency = {1e6 * max_latency:.3g} µs" if max_latency is not None else None]
    bounds = [b for b in bounds if b]
    if bounds:
        criterion += f"; within {', '.join(bounds)}"
    return Choice(chosen=chosen, candidates=candidates, criterion=criterion)


def _exclusion(c, trusted, minor_loops_known, unknown_reason, max_operators, max_latency):
    """Why the candidate ``c`` may not be chosen, or None."""
    if max_operators is not None and c.fitted.n_operators > max_operators:
        return f"{c.fitted.n_operators} operators, more than max_operators = {max_operators}"
    if max_latency is not None and c.worst_latency > max_latency:
        return (f"worst-case compensator latency {1e6 * c.worst_latency:.3g} µs, more than "
                f"max_latency = {1e6 * max_latency:.3g} µs")
    if not minor_loops_known and not c.fitted.family.minor_loops_fixed and trusted:
        return (f"its minor loops are not fixed by its structure and the data cannot "
                f"determine them: {unknown_reason}")
    return None
