"""Types of the one-pass turning-point search (_turning.pyx, a Cython extension)."""

import numpy as np
from numpy.typing import NDArray

def turning_points(v: NDArray[np.float64], tolerance: float) -> list[tuple[int, int]]: ...
