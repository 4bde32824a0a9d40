"""Model files: ``load_model``, ``save_model`` (JSON).

Schema (docs/interfaces.md; only ``family``, ``weights`` and, except for ``pwl``,
``thresholds`` are required)::

    {
      "family": "classical" | "multislope" | "pwl",
      "thresholds": [r_0, ...],                    # V, strictly increasing, >= 0
      "weights": [w_0, ...],
      "offset": 0.0,                               # um, added to the output
      "U": 150.0, "a": 0.8, "b": 1.2, "h": 0.5,    # multislope shape (paper's defaults)
      "rising":  [{"x": [...], "y": [...]}, ...],  # pwl: one polyline per operator
      "falling": [{"x": [...], "y": [...]}, ...],
      "input_range": [0.0, 150.0],                 # V (multislope default: [0, U])
      "initial_state": [f_0, ...],                 # operator outputs before the first
                                                   # sample (default: zeros)
      "units": {"input": "V", "output": "um"},
      "metadata": {...}                            # free-form (fit reports...); NumPy values
                                                   # written as numbers and lists
    }

Each model class reads and writes its own keys (``to_dict``/``from_dict``); this module
only turns files into dicts and back, reporting a broken file as one line with its line
and column.
"""

import json
import os
from typing import Any

from pihyst.exceptions import InvalidArgumentError, InvalidModelError, RecordError
from pihyst.io._inputs import read_small
from pihyst.model import PIModel


def load_model(path_or_dict: str | os.PathLike[str] | dict[str, Any]) -> PIModel:
    """A model from a JSON file path or from a dict of the schema in this module.

    Parameters
    ----------
    path_or_dict : str, os.PathLike or dict
        A JSON model file, or the dict it would hold.

    Returns
    -------
    PIModel
        The model (ClassicalPI, MultislopePI, PiecewiseLinearPI or BoucWenModel).

    Raises
    ------
    InvalidModelError
        A file that cannot be read, is not valid JSON (with its line and column), or does
        not describe a valid model.
    InvalidArgumentError
        ``path_or_dict`` is neither a path nor a dict.

    Examples
    --------
    >>> m = load_model({"family": "classical", "thresholds": [0, 10, 30, 150],
    ...                 "weights": [0.008, 0.252, 0.019, 0.582]})
    >>> m.family, m.n_operators
    ('classical', 4)
    """
    if isinstance(path_or_dict, dict):
        return PIModel.from_dict(path_or_dict)
    path = os.fspath(path_or_dict) if isinstance(path_or_dict, (str, os.PathLike)) else None
    return PIModel.from_dict(read_model_dict(path_or_dict), source=path)


def read_model_dict(path_or_dict: str | os.PathLike[str] | dict[str, Any]) -> dict[str, Any]:
    """The dict a JSON model file holds (any family, e.g. ``hammerstein`` for
    :func:`pihyst.dynamics.load_hammerstein`), its file errors reported as one line;
    a dict is returned as it is.

    Parameters
    ----------
    path_or_dict : str, os.PathLike or dict
        A JSON file, or a dict.

    Returns
    -------
    dict
        What the file holds (not checked against a model's schema).

    Raises
    ------
    InvalidModelError
        A file that cannot be read or is not valid JSON (with its line and column).
    InvalidArgumentError
        ``path_or_dict`` is neither a path nor a dict.

    Examples
    --------
    >>> import os, tempfile
    >>> from pathlib import Path
    >>> from pihyst.io import read_model_dict
    >>> path = Path(tempfile.mkdtemp()) / "model.json"
    >>> _ = path.write_text('{"family": "hammerstein", "order": 2}')
    >>> read_model_dict(path)
    {'family': 'hammerstein', 'order': 2}
    """
    if isinstance(path_or_dict, dict):
        return path_or_dict
    try:
        path = os.fspath(path_or_dict)
    except TypeError:
        raise InvalidArgumentError(f"load_model needs a file path or a dict, got "
                                   f"{type(path_or_dict).__name__}") from None
    try:
        raw = read_small(path)
    except OSError as err:
        raise InvalidModelError(f"{path}: cannot read model: {err.strerror}") from None
    except RecordError as err:      # a stream too large or too slow, a folder
        raise InvalidModelError(f"{path}: cannot read model: {err.message}") from None
    return _parse_json(raw, path)


def _parse_json(raw, path):
    if raw.startswith(b"\xef\xbb\xbf"):  # a byte-order mark, as some editors write
        raw = raw[3:]
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as err:
        line = raw.count(b"\n", 0, err.start) + 1
        column = err.start - (raw.rfind(b"\n", 0, err.start) + 1) + 1
        raise InvalidModelError(f"{path}:{line}:{column}: not UTF-8 text (byte "
                                f"0x{raw[err.start]:02x})") from None
    try:
        return json.loads(text, parse_constant=_no_constant, object_pairs_hook=_unique_keys)
    except json.JSONDecodeError as err:
        raise InvalidModelError(f"{path}:{err.lineno}:{err.colno}: invalid JSON: {err.msg}") \
            from None
    except RecursionError:
        raise InvalidModelError(f"{path}: invalid JSON: nested too deeply") from None
    except _KeyError as err:
        raise InvalidModelError(f"{path}:{_where(text, err.token, err.last)}: {err}") \
            from None
    except ValueError as err:  # e.g. an integer with more digits than Python converts
        raise InvalidModelError(f"{path}: invalid JSON: {err}") from None


class _KeyError(ValueError):
    """A JSON token that is valid syntax but not a valid model file (``token`` is
    searched for in the text to say where)."""

    def __init__(self, message, token, last=False):
        super().__init__(message)
        self.token, self.last = token, last


def _no_constant(name):
    raise _KeyError(f"invalid JSON: {name} is not a number in JSON (use a finite number)",
                    name)


def _unique_keys(pairs):
    seen = set()
    for key, _ in pairs:
        if key in seen:
            raise _KeyError(f"duplicate key {key!r}: which value is meant?",
                            json.dumps(key), last=True)
        seen.add(key)
    return dict(pairs)


def _where(text, token, last):
    """LINE:COLUMN of the first (or ``last``) occurrence of ``token`` in ``text``, 1:1
    when not found."""
    i = text.rfind(token) if last else text.find(token)
    if i < 0:
        return "1:1"
    line = text.count("\n", 0, i) + 1
    return f"{line}:{i - (text.rfind(chr(10), 0, i) + 1) + 1}"


def save_model(model: Any, path: str | os.PathLike[str]) -> None:
    """Write ``model`` as JSON; the file appears only once it is complete.

    Parameters
    ----------
    model : PIModel or BoucWenModel
        Any model with a ``save`` method (pihyst's models).
    path : str or os.PathLike
        The JSON file to write.

    Examples
    --------
    >>> import os, tempfile
    >>> import pihyst
    >>> path = os.path.join(tempfile.mkdtemp(), "model.json")
    >>> pihyst.save_model(pihyst.ClassicalPI([0, 10], [0.5, 0.25]), path)
    >>> pihyst.load_model(path).thresholds.tolist()
    [0.0, 10.0]
    """
    model.save(path)
