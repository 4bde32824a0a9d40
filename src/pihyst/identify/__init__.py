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

Behind it, one private module per step (the order of docs/theory/identification.md's
table of decisions):

- ``_fit``: :func:`fit`: the options, the record's fit, creep; ``_options``: the options
  (``FitOptions``), checked once; ``_record_fit``: the steps in order for one record
  (``fit_record``); ``_decisions``: what each step decided, as frozen values;
  ``_constants``: every number that decides something, with the evidence for it;
  ``_responses``: what the record's input alone determines, computed once per fit;
  ``_progress``: each step's end, for the command line;
- ``_sufficiency``: whether the record can be fitted at all, and whether the fit explains it;
- ``_family_fit``: the record in the fitting frame (``FramedRecord``) and one family's fit
  (``FamilyFitter``); ``_family_result``: its :class:`FamilyFit`;
- ``_start_state``: the operator state before the first sample (``initial_state="auto"``);
- ``_cycles``: cutting a record into settle, fitted and held-back cycles (its turning
  points found in one pass in C by ``_turning``, a Cython extension);
- ``_delay``: the input-output delay;
- ``_families``: the fitting families (candidate operators, frames, how each is fitted);
- ``_gram``: normal equations; ``_qp``: constrained least squares;
- ``_subsets``: the threshold subset search; ``_shape``: the multislope shape search;
- ``_kernel_product``: the product-form kernel density (kp, records without minor loops);
- ``_kernel_pruning``: a kp model's final weights on fewer kernels, the same model;
- ``_boucwen``: the Bouc-Wen family; ``_boucwen_creep``: its shape fitted with creep;
- ``_assess``: errors per kind of held-back data, what the data cannot determine;
- ``_latency``: compensator cost, estimated from the model's structure;
- ``_choice``: which family is returned;
- ``_creep``: creep lags fitted with the weights, and whether to keep them;
  ``_record_start``: whether a record's lags started at rest;
- ``_report``: the result and its report.
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
