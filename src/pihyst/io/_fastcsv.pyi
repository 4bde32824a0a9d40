"""Types of the fast text-block parser (_fastcsv.pyx, a Cython extension)."""

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

def parse_block(
    block: bytes, separator: str | None, n_fields: int, wanted: Sequence[int]
) -> NDArray[np.float64] | None: ...
