"""Hammerstein model files: the JSON of :meth:`HammersteinModel.to_dict`, read through
the same checks as every model file (one-line errors with the file's line and column)::

    {
      "family": "hammerstein",
      "hysteresis": [{...a model file's keys...}, ...],   # one per input
      "a": [[1.0, a_1, ...], ...],                        # one A(q^-1) per output
      "b": [[[b_0, b_1, ...], ...], ...],                 # per output, one row per input
      "trusted_from": f_t,                                # optional, cycles per sample
      "order_trusted_from": [f_1, f_2, ...],              # optional, per harmonic order
      "static_offset": e_0                                # optional, output units
    }
"""

import os
from typing import Any

from pihyst.dynamics._hammerstein import HammersteinModel
from pihyst.io import read_model_dict


def load_hammerstein(path_or_dict: str | os.PathLike[str] | dict[str, Any]) -> HammersteinModel:
    """A :class:`HammersteinModel` from a JSON file path or a dict of the schema above.

    Parameters
    ----------
    path_or_dict : str, os.PathLike or dict
        A model file (:meth:`HammersteinModel.save`), or the dict it holds.

    Returns
    -------
    HammersteinModel
        The model.

    Raises
    ------
    InvalidModelError
        A file that cannot be read, is not valid JSON, or does not describe a valid
        model (one line, with the file and key or line and column).

    Examples
    --------
    >>> from pihyst.dynamics import load_hammerstein
    >>> model = load_hammerstein({"family": "hammerstein",
    ...                           "hysteresis": [{"family": "classical", "thresholds": [0],
    ...                                           "weights": [1.0]}],
    ...                           "a": [[1.0, -0.5]], "b": [[[0.5]]]})
    >>> model.static_gain()
    array([[1.]])
    """
    source = (os.fspath(path_or_dict) if isinstance(path_or_dict, (str, os.PathLike))
              else "model")
    return HammersteinModel.from_dict(read_model_dict(path_or_dict), source=source)
