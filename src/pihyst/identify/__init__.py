"""Identification: fit PI-type models to a measured voltage/displacement record.

:func:`fit` cuts the record into cycles, accumulates the normal equations of every
candidate operator once, fits the weights by a QP (w >= 0, so the model stays invertible),
chooses thresholds, shape and family on held-back cycles, and returns a
:class:`FitResult` (the model and a :class:`FitReport`). Theory:
docs/theory/identification.md.

A *fitting family* is a recipe for one model: :class:`Classical`, :class:`Multislope`,
:class:`MultislopeIdentified`, :class:`ModifiedPI`, :class:`KrasnoselskiiPokrovskii`,
and :class:`BoucWen` (not a PI model: remanence and drifting minor loops)
(``fit(u, y, family=ModifiedPI(segments=8))``; a name such as ``"modified-pi"`` stands
for the family with its default options). It is not the model's operator kind
(``model.family``: classical, multislope or pwl); ``model.metadata["fit"]["family"]``
records the fitting family.

Behind it, one private module per step: ``_cycles`` (cutting a record),
``_families`` (the fitting families: candidate operators, frames, how each is fitted),
``_gram`` (normal equations), ``_qp`` (constrained least squares), ``_subsets``
(threshold subset search), ``_shape`` (multislope shape search), ``_family_fit`` (one
family's fit) and ``_family_result`` (its :class:`FamilyFit`), ``_delay`` (the
input-output delay), ``_assess`` (errors per kind of held-back data, what the data
cannot determine), ``_latency`` (compensator cost), ``_choice`` (which family is
returned), ``_fit`` (all of it), ``_report`` (the result).
"""

from pihyst.exceptions import FitError, IllConditionedWarning, InfeasibleConstraintsError
from pihyst.identify._families import (
    FAMILY_NAMES,
    PI_FAMILY_NAMES,
    BoucWen,
    Classical,
    Family,
    KrasnoselskiiPokrovskii,
    ModifiedPI,
    Multislope,
    MultislopeIdentified,
)
from pihyst.identify._family_fit import INITIAL_STATES, cycled_state
from pihyst.identify._family_result import FamilyFit
from pihyst.identify._fit import fit
from pihyst.identify._report import FitReport, FitResult

__all__ = ["FAMILY_NAMES", "INITIAL_STATES", "PI_FAMILY_NAMES", "BoucWen", "Classical",
           "Family", "FamilyFit", "FitError", "FitReport", "FitResult", "IllConditionedWarning",
           "InfeasibleConstraintsError", "KrasnoselskiiPokrovskii", "ModifiedPI", "Multislope",
           "MultislopeIdentified", "cycled_state", "fit"]
