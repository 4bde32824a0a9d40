"""What fitting one family returns: :class:`FamilyFit`, a small typed result."""

from dataclasses import dataclass, field
from typing import Any, Callable, Optional

import numpy as np


@dataclass(frozen=True)
class FamilyFit:
    """One family fitted to a record (on the fitted cycles), before any refit.

    The families' ``fit`` methods build it; :func:`pihyst.fit` compares them.

    Parameters
    ----------
    family : Family
        The fitting family, with what was identified (e.g. the multislope shape).
    model : PIModel or BoucWenModel
        The fitted model of the raw input.
    operators : tuple
        Its thresholds (floats) or kernels ((i, j) pairs), in the model's order.
    weights : ndarray
        The operator weights (thresholds' operators, then the family's fixed ones).
    offset : float
        The model's offset.
    errors : dict
        ``"fit"`` and ``"held_back"`` -> :func:`pihyst.metrics.error_summary` (or None).
    judged_rms : float
        RMS error the choices were judged by: held-back, or fitted if nothing is.
    n_params : int
        Non-zero weights plus the fitted offset.
    threshold_choice : dict, optional
        How the thresholds were chosen (subset search), or None.
    regularization : dict, optional
        How the KP regularization was chosen, or None.
    notes : tuple of str
        Notes for the report.
    warnings : tuple of str
        Warnings for the report.
    refit : callable, optional
        Returns the same structure with its weights fitted on fitted and held-back
        cycles together.
    judged_on : FamilyFitter, optional
        The fitter whose record the errors are measured on, when not the record's own
        (a model slow to run is fitted and judged on a subsampled record).

    Examples
    --------
    >>> import numpy as np
    >>> from pihyst.identify import Classical
    >>> from pihyst.model import ClassicalPI
    >>> model = ClassicalPI([0.0], [0.5], input_range=(0, 150))
    >>> ff = FamilyFit(Classical(), model, (0.0,), np.array([0.5]), 0.0,
    ...                {"fit": None, "held_back": None}, 0.0, 1)
    >>> ff.name, ff.n_operators
    ('classical', 1)
    """

    family: Any
    model: Any
    operators: tuple[Any, ...]
    weights: np.ndarray
    offset: float
    errors: dict[str, Any]
    judged_rms: float
    n_params: int
    threshold_choice: Optional[dict[str, Any]] = None
    regularization: Optional[dict[str, Any]] = None
    notes: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()
    # the same structure with its weights fitted on fitted and held-back cycles together
    refit: Optional[Callable[[], Any]] = field(default=None, repr=False, compare=False)
    # the FamilyFitter whose record the errors are measured on, when not the record's own
    # (a model slow to run is fitted and judged on a subsampled record)
    judged_on: Any = field(default=None, repr=False, compare=False)

    @property
    def name(self) -> str:
        """The fitting family's name."""
        return str(self.family.name)

    @property
    def n_operators(self) -> int:
        """Operators in the model (thresholds' and the family's fixed ones)."""
        return int(self.model.n_operators)
