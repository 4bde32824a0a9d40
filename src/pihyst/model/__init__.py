"""PI-type hysteresis models as values: the operators (over the C core), the model
classes, their JSON form and the analytic inverse of the classical model.

The lowest layer of pihyst with :mod:`pihyst.exceptions` and :mod:`pihyst.paper`: it
imports nothing else of the package. Theory: docs/theory/operators.md.
"""

from pihyst.exceptions import InputRangeError, InvalidModelError
from pihyst.model._bank import ModelBank
from pihyst.model._boucwen import BoucWenModel, BoucWenStepper
from pihyst.model._classical_inverse import classical_inverse, reachable_output_range
from pihyst.model._creep import Creep
from pihyst.model._models import (
    DEFAULT_INPUT_RANGE,
    SCHEMA_VERSION,
    ClassicalPI,
    MultislopePI,
    PiecewiseLinearPI,
    PIModel,
    Response,
    Stepper,
)

__all__ = [
    "BoucWenModel",
    "BoucWenStepper",
    "DEFAULT_INPUT_RANGE",
    "SCHEMA_VERSION",
    "ClassicalPI",
    "Creep",
    "InputRangeError",
    "InvalidModelError",
    "ModelBank",
    "MultislopePI",
    "PIModel",
    "PiecewiseLinearPI",
    "Response",
    "Stepper",
    "classical_inverse",
    "reachable_output_range",
]
