"""Types of the fast text-block parser and writer (_fastcsv.pyx, a Cython extension)."""

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

def has_long_double_path() -> bool: ...
def parse_block(
    block: bytes, separator: str | None, n_fields: int, wanted: Sequence[int]
) -> NDArray[np.float64] | None: ...
def format_rows(columns: Sequence[ArrayLike]) -> bytes: ...
