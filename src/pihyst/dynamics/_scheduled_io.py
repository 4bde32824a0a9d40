"""Scheduled state-space model files: every field of :class:`ScheduledStateSpace` under
its own name, read through the same checks as every model file (one-line errors naming
the file and the key, or the line and column of broken JSON)::

    {
      "family": "scheduled_state_space",
      "amplitudes": {"shape": [K], "values": [a_1, ...]},
      "poles": {"shape": [K, P], "real": [[...], ...], "imag": [[...], ...]},
      "c":     {"shape": [K, P, p], "real": ..., "imag": ...},
      "b":     {"shape": [K, P, m], "real": ..., "imag": ...},
      "real_poles": {"shape": [K, R], "values": ...},
      "real_c": {"shape": [K, R, p], "values": ...},
      "real_b": {"shape": [K, R, m], "values": ...},
      "D": {"shape": [K, p, m], "values": ...},
      "window": 1024.0,
      "exponent": 1.0,                             # optional (1 when absent)
      "metadata": {...}                            # optional, free-form, not read
    }

An array is its nested lists with its shape beside them (so that an empty axis, e.g. no
real poles, keeps the sizes after it); a complex array is its real and imaginary parts.
The fields are found from the dataclass itself (:func:`dataclasses.fields`): a field
added to the model is written and read without a change here (an array, complex when
its annotation names a complex type, or a number). Python's ``json`` writes every float
as the shortest text that reads back as the same double, so a model survives the
round trip bit for bit.
"""

import dataclasses
import os
from typing import Any

import numpy as np

from pihyst.dynamics._scheduled import ScheduledStateSpace
from pihyst.exceptions import InvalidArgumentError, InvalidModelError
from pihyst.io import read_model_dict

FAMILY = "scheduled_state_space"
OPTIONAL_KEYS = ("metadata", "units")   # free-form keys a file may carry


def _is_complex(field):
    return "complex" in str(field.type)


def _is_number(field):
    return field.type in (float, int, "float", "int")


def _array_to_json(value, complex_):
    value = np.asarray(value)
    if complex_:
        return {"shape": list(value.shape), "real": value.real.tolist(),
                "imag": value.imag.tolist()}
    return {"shape": list(value.shape), "values": value.tolist()}


def scheduled_to_dict(model: ScheduledStateSpace) -> dict[str, Any]:
    """The model as JSON values (the schema of the module notes).

    Parameters
    ----------
    model : ScheduledStateSpace
        The model.

    Returns
    -------
    dict
        ``family`` and one key per field of the model.

    Examples
    --------
    >>> import numpy as np
    >>> from pihyst.dynamics import ScheduledStateSpace
    >>> from pihyst.dynamics._scheduled_io import scheduled_to_dict
    >>> m = ScheduledStateSpace([1.0, 3.0], [[0.5j], [0.7j]], [[[1.0]], [[1.0]]],
    ...                         [[[1.0]], [[1.0]]], np.zeros((2, 0)), np.zeros((2, 0, 1)),
    ...                         np.zeros((2, 0, 1)), [[[0.0]], [[0.0]]], window=100)
    >>> d = scheduled_to_dict(m)
    >>> d["poles"]
    {'shape': [2, 1], 'real': [[0.0], [0.0]], 'imag': [[0.5], [0.7]]}
    >>> d["real_c"], d["window"]        # no real poles: the shape keeps p = 1
    ({'shape': [2, 0, 1], 'values': [[], []]}, 100)
    """
    d: dict[str, Any] = {"family": FAMILY}
    for field in dataclasses.fields(model):
        value = getattr(model, field.name)
        d[field.name] = (np.asarray(value).item() if _is_number(field)
                         else _array_to_json(value, _is_complex(field)))
    return d


def _bad(source, key, what):
    raise InvalidModelError(f"{source}: key {key!r} must be {what}")


def _nested(value, shape, source, key, part):
    """A JSON nested list as a float array of ``shape``."""
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        _bad(source, key, f"an object whose {part!r} is nested lists of numbers")
    if arr.size != int(np.prod(shape)) or (arr.size and arr.shape != tuple(shape)):
        _bad(source, key, f"an object whose {part!r} has the shape {list(shape)} it gives, "
                          f"not {list(arr.shape)}")
    return arr.reshape(shape)


def _array_from_json(value, complex_, source, key):
    parts = ("real", "imag") if complex_ else ("values",)
    if not isinstance(value, dict) or set(value) != {"shape", *parts}:
        _bad(source, key, "an object with the keys 'shape', "
                          + ", ".join(repr(p) for p in parts))
    shape = value["shape"]
    if (not isinstance(shape, list) or
            not all(isinstance(n, int) and not isinstance(n, bool) and 0 <= n < 2 ** 31
                    for n in shape)):
        _bad(source, key, "an object whose 'shape' is a list of sizes (integers >= 0)")
    arrays = [_nested(value[p], shape, source, key, p) for p in parts]
    if not complex_:
        return arrays[0]
    out = np.empty(arrays[0].shape, complex)   # not re + 1j * im: that loses -0.0
    out.real, out.imag = arrays
    return out


def scheduled_from_dict(d: dict[str, Any], source: str = "model") -> ScheduledStateSpace:
    """The model of a dict of :func:`scheduled_to_dict`'s keys.

    Parameters
    ----------
    d : dict
        ``family`` ("scheduled_state_space") and one key per field of the model.
    source : str
        What the dict came from, for the messages.

    Returns
    -------
    ScheduledStateSpace
        The model.

    Raises
    ------
    InvalidModelError
        A missing, unknown or malformed key, or fields that do not make a valid model
        (e.g. a pole outside the unit circle), named by ``source`` and the key.

    Examples
    --------
    >>> from pihyst.dynamics._scheduled_io import scheduled_from_dict
    >>> scheduled_from_dict({"family": "scheduled_state_space"}, "m.json")
    Traceback (most recent call last):
    ...
    pihyst.exceptions.InvalidModelError: m.json: key 'amplitudes' is missing
    """
    if not isinstance(d, dict) or d.get("family") != FAMILY:
        family = d.get("family") if isinstance(d, dict) else None
        raise InvalidModelError(f"{source}: key 'family' must be {FAMILY!r}; got "
                                f"{family!r:.40}")
    fields = dataclasses.fields(ScheduledStateSpace)
    known = {f.name for f in fields} | {"family", *OPTIONAL_KEYS}
    unknown = sorted(set(d) - known)
    if unknown:
        raise InvalidModelError(f"{source}: unknown key {unknown[0]!r:.60} (a "
                                f"{FAMILY} file has " + ", ".join(sorted(known)) + ")")
    values = {}
    for field in fields:
        if field.name not in d:
            if (field.default is dataclasses.MISSING
                    and field.default_factory is dataclasses.MISSING):
                raise InvalidModelError(f"{source}: key {field.name!r} is missing")
            continue
        value = d[field.name]
        if _is_number(field):
            if (isinstance(value, bool) or not isinstance(value, (int, float))
                    or not np.isfinite(value)):
                _bad(source, field.name, "a finite number")
            values[field.name] = value
        else:
            values[field.name] = _array_from_json(value, _is_complex(field), source,
                                                  field.name)
    try:
        return ScheduledStateSpace(**values)
    except InvalidArgumentError as err:
        raise InvalidModelError(f"{source}: {err}") from None


def load_scheduled_state_space(path_or_dict: str | os.PathLike[str] | dict[str, Any]
                               ) -> ScheduledStateSpace:
    """A :class:`ScheduledStateSpace` from a JSON file path or a dict of the schema above.

    Parameters
    ----------
    path_or_dict : str, os.PathLike or dict
        A model file (:func:`save_scheduled_state_space`), or the dict it holds.

    Returns
    -------
    ScheduledStateSpace
        The model, bit for bit the one saved.

    Raises
    ------
    InvalidModelError
        A file that cannot be read, is not valid JSON (its line and column), or does not
        describe a valid model (the file and the key).

    Examples
    --------
    >>> import os, tempfile
    >>> import numpy as np
    >>> from pihyst.dynamics import ScheduledStateSpace, load_scheduled_state_space
    >>> from pihyst.dynamics import save_scheduled_state_space
    >>> m = ScheduledStateSpace([1.0, 3.0], [[0.5j], [0.7j]], [[[1.0]], [[1.0]]],
    ...                         [[[1.0]], [[1.0]]], np.zeros((2, 0)), np.zeros((2, 0, 1)),
    ...                         np.zeros((2, 0, 1)), [[[0.0]], [[0.0]]], window=100)
    >>> path = os.path.join(tempfile.mkdtemp(), "fsm.json")
    >>> save_scheduled_state_space(m, path)
    >>> load_scheduled_state_space(path).poles.tolist()
    [[0.5j], [0.7j]]
    """
    source = (os.fspath(path_or_dict) if isinstance(path_or_dict, (str, os.PathLike))
              else "model")
    return scheduled_from_dict(read_model_dict(path_or_dict), source=source)


def save_scheduled_state_space(model: ScheduledStateSpace,
                               path: str | os.PathLike[str]) -> None:
    """Write the model as JSON to ``path`` (the file appears only once complete).

    Parameters
    ----------
    model : ScheduledStateSpace
        The model.
    path : str or os.PathLike
        The file to write.

    Examples
    --------
    >>> import os, tempfile
    >>> import numpy as np
    >>> from pihyst.dynamics import ScheduledStateSpace, load_scheduled_state_space
    >>> from pihyst.dynamics import save_scheduled_state_space
    >>> m = ScheduledStateSpace([2.0], [[0.5j]], [[[1.0]]], [[[1.0]]], np.zeros((1, 0)),
    ...                         np.zeros((1, 0, 1)), np.zeros((1, 0, 1)), [[[0.0]]],
    ...                         window=10)
    >>> path = os.path.join(tempfile.mkdtemp(), "m.json")
    >>> save_scheduled_state_space(m, path)
    >>> load_scheduled_state_space(path).window
    10
    """
    import json

    from pihyst._atomic import write_atomically
    write_atomically(path, json.dumps(scheduled_to_dict(model), indent=1) + "\n")
