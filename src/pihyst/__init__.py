"""pihyst: Prandtl-Ishlinskii hysteresis models, identification and feedforward
compensation for piezoelectric actuators (Xu, Zhang, Rong and Ni 2020, and beyond)."""

__version__ = "0.1.0"

from pihyst.compensate import CompensationResult, Compensator, compensate  # noqa: E402
from pihyst.exceptions import (  # noqa: E402
    FitError,
    IllConditionedWarning,
    InfeasibleConstraintsError,
    PihystWarning,
)
from pihyst.fit_report import FitReport, FitResult  # noqa: E402
from pihyst.identify import fit  # noqa: E402
from pihyst.io import load_model, save_model  # noqa: E402
from pihyst.model import (  # noqa: E402
    ClassicalPI,
    InputRangeError,
    InvalidModelError,
    MultislopePI,
    PiecewiseLinearPI,
    PIModel,
    Response,
)

__all__ = [
    "ClassicalPI",
    "CompensationResult",
    "Compensator",
    "FitError",
    "FitReport",
    "FitResult",
    "IllConditionedWarning",
    "InfeasibleConstraintsError",
    "InputRangeError",
    "InvalidModelError",
    "MultislopePI",
    "PIModel",
    "PiecewiseLinearPI",
    "PihystWarning",
    "Response",
    "compensate",
    "fit",
    "load_model",
    "save_model",
]
