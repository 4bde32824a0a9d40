"""What fitting one family returns: :class:`FamilyFit`, a small typed result."""

from dataclasses import dataclass, field
from typing import Callable, Optional

import numpy as np


@dataclass(frozen=True)
class FamilyFit:
    """One family fitted to a record (on the fitted cycles), before any refit.

    Attributes
    ----------
    family : Family
        The fitting family, with what was identified (e.g. the multislope shape).
    model : PIModel
        The fitted model of the raw input.
    operators : tuple
        Its thresholds (floats) or kernels ((i, j) pairs), in the model's order.
    weights : ndarray
        The operator weights (thresholds' operators, then the family's fixed ones).
    offset : float
    errors : dict
        ``"fit"`` and ``"held_back"`` -> :func:`pihyst.metrics.error_summary` (or None).
    judged_rms : float
        RMS error the choices were judged by: held-back, or fitted if nothing is.
    n_params : int
        Non-zero weights plus the fitted offset.
    threshold_choice, regularization : dict or None
        How the thresholds (subset search) or the KP regularization were chosen.
    notes, warnings : tuple of str
    """

    family: object
    model: object
    operators: tuple
    weights: np.ndarray
    offset: float
    errors: dict
    judged_rms: float
    n_params: int
    threshold_choice: Optional[dict] = None
    regularization: Optional[dict] = None
    notes: tuple = ()
    warnings: tuple = ()
    # the same structure with its weights fitted on fitted and held-back cycles together
    refit: Callable[[], object] = field(default=None, repr=False, compare=False)
    # the FamilyFitter whose record the errors are measured on, when not the record's own
    # (a model slow to run is fitted and judged on a subsampled record)
    judged_on: object = field(default=None, repr=False, compare=False)

    @property
    def name(self):
        return self.family.name

    @property
    def n_operators(self):
        """Operators in the model (thresholds' and the family's fixed ones)."""
        return self.model.n_operators
