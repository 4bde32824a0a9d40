"""Identification: fit PI-type models to a measured voltage/displacement record.

:func:`fit` cuts the record into cycles, accumulates the normal equations of every
candidate operator once, fits the weights by a QP (w >= 0, so the model stays invertible),
chooses thresholds, shape and family on held-back cycles, and returns a
:class:`FitResult` (the model and a :class:`FitReport`). Theory:
docs/theory/identification.md.

Behind it, one private module per step: ``_cycles`` (cutting a record),
``_families`` (candidate operators of each family and the fitting frame), ``_gram``
(normal equations), ``_qp`` (constrained least squares), ``_subsets`` (threshold subset
search), ``_family_fit`` (one family's fit), ``_fit`` (every family, the choice),
``_report`` (the result).
"""

from pihyst.exceptions import FitError, IllConditionedWarning, InfeasibleConstraintsError
from pihyst.identify._families import FAMILY_NAMES
from pihyst.identify._family_fit import INITIAL_STATES, cycled_state
from pihyst.identify._fit import fit
from pihyst.identify._report import FitReport, FitResult

__all__ = ["FAMILY_NAMES", "INITIAL_STATES", "FitError", "FitReport", "FitResult",
           "IllConditionedWarning", "InfeasibleConstraintsError", "cycled_state", "fit"]
