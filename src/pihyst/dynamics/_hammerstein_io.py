"""Hammerstein model files: the JSON of :meth:`HammersteinModel.to_dict`, read through
the same checks as every model file (one-line errors with the file's line and column)::

    {
      "family": "hammerstein",
      "hysteresis": [{...a model file's keys...}, ...],   # one per input
      "a": [[1.0, a_1, ...], ...],                        # one A(q^-1) per output
      "b": [[[b_0, b_1, ...], ...], ...]                  # per output, one row per input
    }
"""

import os

from pihyst.dynamics._hammerstein import HammersteinModel
from pihyst.io import read_model_dict


def load_hammerstein(path_or_dict):
    """A :class:`HammersteinModel` from a JSON file path or a dict of the schema above."""
    source = (os.fspath(path_or_dict) if isinstance(path_or_dict, (str, os.PathLike))
              else "model")
    return HammersteinModel.from_dict(read_model_dict(path_or_dict), source=source)
