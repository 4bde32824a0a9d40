"""pihyst: Prandtl-Ishlinskii hysteresis models, identification and feedforward
compensation for piezoelectric actuators (Xu, Zhang, Rong and Ni 2020, and beyond).

The package is laid out as the pipeline (docs/architecture.md):

- :mod:`pihyst.model`: models as values over the C core (operators, classes, JSON form);
- :mod:`pihyst.io`: model files and records;
- :mod:`pihyst.inverse`: the exact compensator and the analytic inverse;
- :mod:`pihyst.identify`: fitting models to records;
- :mod:`pihyst.sim`: simulated beams and test signals;
- :mod:`pihyst.study`: the paper's study and its report;
- :mod:`pihyst.fleet`: many records fitted at once, serially or on a Dask cluster;
- :mod:`pihyst.cli`: the ``pihyst`` command.

The names below are the public API of the README. The sub-packages are attributes too
(``pihyst.sim.make_plant``, ``pihyst.dynamics.fit_hammerstein``), imported on first use
so that ``import pihyst`` stays fast.
"""

from importlib import import_module as _import_module

from pihyst._version import __version__
from pihyst.exceptions import (
    CSVError,
    FitError,
    IllConditionedWarning,
    InfeasibleConstraintsError,
    InputRangeError,
    InvalidModelError,
    PihystWarning,
)
from pihyst.fleet import FleetResult, RecordOutcome, fit_many
from pihyst.identify import FitReport, FitResult, fit
from pihyst.inverse import BoucWenCompensator, CompensationResult, Compensator, compensate
from pihyst.io import load_model, save_model
from pihyst.model import (
    BoucWenModel,
    ClassicalPI,
    MultislopePI,
    PiecewiseLinearPI,
    PIModel,
    Response,
    Stepper,
)

__all__ = [
    "BoucWenCompensator",
    "BoucWenModel",
    "CSVError",
    "ClassicalPI",
    "CompensationResult",
    "Compensator",
    "FitError",
    "FitReport",
    "FitResult",
    "FleetResult",
    "IllConditionedWarning",
    "InfeasibleConstraintsError",
    "InputRangeError",
    "InvalidModelError",
    "MultislopePI",
    "PIModel",
    "PiecewiseLinearPI",
    "PihystWarning",
    "RecordOutcome",
    "Response",
    "Stepper",
    "__version__",
    "compensate",
    "fit",
    "fit_many",
    "load_model",
    "save_model",
]

# imported on first access (PEP 562): they bring SciPy, matplotlib or optional extras
_SUBPACKAGES = ("control", "dynamics", "fleet", "identify", "inverse", "io", "learn", "model",
                "rig", "sim", "study", "cli")


def __getattr__(name):
    if name in _SUBPACKAGES:
        return _import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_SUBPACKAGES))
