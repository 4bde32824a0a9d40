"""Xu, Zhang, Rong and Ni (2020), in one place: what pihyst takes from the paper.

"Multislope PI Modeling and Feedforward Compensation for Piezoelectric Beam",
Mathematical Problems in Engineering 2020, 6404971. Everything else in pihyst that needs
the paper's shape, its Table 1, its drive or its published numbers imports them from here
(docs/paper.md explains each number and the paper's errors that pihyst corrects).
"""

from types import MappingProxyType
from typing import Any

__all__ = ["BEAM_MAX_DISPLACEMENT_UM", "CITATION", "DRIVE_PERIOD_S", "DRIVE_U_MAX_V",
           "DRIVE_U_MIN_V", "FIT_EXTREMES_CLASSICAL_UM", "FIT_IMPROVEMENT_PCT",
           "FIT_MEAN_ABS_CLASSICAL_UM", "FIT_MEAN_ABS_MULTISLOPE_UM", "SHAPE", "SUPPLY_STEP_V",
           "TABLE1_CLASSICAL_THRESHOLDS", "TABLE1_CLASSICAL_WEIGHTS",
           "TABLE1_MULTISLOPE_THRESHOLDS", "TABLE1_MULTISLOPE_WEIGHTS", "TRACKING_MEAN_ABS_UM",
           "TRACKING_RMS_UM", "published"]

CITATION = ("Xu, Zhang, Rong and Ni, Multislope PI Modeling and Feedforward Compensation "
            "for Piezoelectric Beam, Mathematical Problems in Engineering 2020, 6404971")

#: The multislope play's shape (paper eq. 6): top of the drive U (V), slopes a < 1 < b,
#: and h, the share of the threshold that sets the falling envelope's kink.
SHAPE = MappingProxyType({"U": 150.0, "a": 0.8, "b": 1.2, "h": 0.5})

#: The drive: the 0 -> 150 -> 0 V triangle of 300 s period, from a DC supply with 10 mV steps.
DRIVE_U_MIN_V = 0.0
DRIVE_U_MAX_V = 150.0
DRIVE_PERIOD_S = 300.0
SUPPLY_STEP_V = 0.01

#: The beam's displacement at 150 V as the paper states it (its Table 1 models peak near 41).
BEAM_MAX_DISPLACEMENT_UM = 45.0

#: Table 1: the identified conventional and multislope PI models (the text's multislope
#: thresholds "0, 20, 40 and 40" are a typo for 0, 20, 30, 40).
TABLE1_CLASSICAL_THRESHOLDS = (0.0, 10.0, 30.0, 150.0)
TABLE1_CLASSICAL_WEIGHTS = (0.008, 0.252, 0.019, 0.582)
TABLE1_MULTISLOPE_THRESHOLDS = (0.0, 20.0, 30.0, 40.0)
TABLE1_MULTISLOPE_WEIGHTS = (0.196, 0.026, 0.046, 0.028)

#: Fitting errors (um, measured minus model) of the Table 1 models on the recorded loop.
FIT_MEAN_ABS_CLASSICAL_UM = 0.9397
FIT_MEAN_ABS_MULTISLOPE_UM = 0.2013
FIT_EXTREMES_CLASSICAL_UM = MappingProxyType({"low": -3.09, "middle": -2.0, "high": 2.4})
FIT_IMPROVEMENT_PCT = 78.6

#: Tracking of a triangular displacement through the multislope inverse (um).
TRACKING_MEAN_ABS_UM = 0.2828
TRACKING_RMS_UM = 0.3100


def published() -> dict[str, Any]:
    """The paper's numbers as a JSON-ready dict (reports show them beside pihyst's).

    Returns
    -------
    dict
        The citation, the beam, Table 1's models and the published errors.

    Examples
    --------
    >>> published()["beam"]["max_displacement_um"]
    45.0
    """
    return {
        "source": CITATION,
        "beam": {"max_displacement_um": BEAM_MAX_DISPLACEMENT_UM,
                 "drive_V": [DRIVE_U_MIN_V, DRIVE_U_MAX_V], "period_s": DRIVE_PERIOD_S},
        "table1": {
            "classical": {"thresholds": list(TABLE1_CLASSICAL_THRESHOLDS),
                          "weights": list(TABLE1_CLASSICAL_WEIGHTS)},
            "multislope": {"thresholds": list(TABLE1_MULTISLOPE_THRESHOLDS),
                           "weights": list(TABLE1_MULTISLOPE_WEIGHTS)},
        },
        "fit": {
            "classical": {"mean_abs": FIT_MEAN_ABS_CLASSICAL_UM,
                          "extremes": dict(FIT_EXTREMES_CLASSICAL_UM)},
            "multislope": {"mean_abs": FIT_MEAN_ABS_MULTISLOPE_UM},
            "improvement_pct": FIT_IMPROVEMENT_PCT,
        },
        "tracking": {"mean_abs": TRACKING_MEAN_ABS_UM, "rms": TRACKING_RMS_UM,
                     "mean_abs_pct_of_range": 100 * TRACKING_MEAN_ABS_UM
                     / BEAM_MAX_DISPLACEMENT_UM},
    }
