"""Inversion: the exact feedforward compensator of any PI model with non-negative weights,
and the analytic inverse of the classical PI (theory: docs/theory/inverse.md).

Voltage limits and a slew limit hold for every output of the compensator, whatever its
input.
"""

from pihyst.inverse._bank import CompensatorBank
from pihyst.inverse._boucwen import BoucWenCompensator
from pihyst.inverse._choice import compensator_for
from pihyst.inverse._compensator import (
    FLAG_NAN,
    FLAG_SATURATED_HIGH,
    FLAG_SATURATED_LOW,
    FLAG_SLEW,
    CompensationResult,
    Compensator,
    PreviewRun,
    compensate,
)
from pihyst.model import classical_inverse, reachable_output_range

__all__ = ["BoucWenCompensator", "FLAG_NAN", "FLAG_SATURATED_HIGH", "FLAG_SATURATED_LOW",
           "FLAG_SLEW", "CompensationResult", "Compensator", "CompensatorBank", "PreviewRun",
           "classical_inverse", "compensate", "compensator_for", "reachable_output_range"]
