"""Models as JSON: ``load_model``, ``save_model``.

Schema (only ``family``, ``weights`` and, except for ``pwl``, ``thresholds`` are required)::

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
      "metadata": {...}                            # free-form, kept as is (fit reports...)
    }
"""

import json
import os
import tempfile

from pihyst.model import ClassicalPI, InvalidModelError, MultislopePI, PiecewiseLinearPI

SCHEMA_VERSION = 1
_COMMON = {"family", "weights", "offset", "input_range", "initial_state", "units", "metadata",
           "schema_version"}
_KEYS = {
    "classical": _COMMON | {"thresholds"},
    "multislope": _COMMON | {"thresholds", "U", "a", "b", "h"},
    "pwl": _COMMON | {"thresholds", "rising", "falling"},
}
_REQUIRED = {"classical": ("thresholds", "weights"), "multislope": ("thresholds", "weights"),
             "pwl": ("rising", "falling", "weights")}


def model_to_dict(model):
    d = {"schema_version": SCHEMA_VERSION, "family": model.family}
    if hasattr(model, "thresholds"):
        d["thresholds"] = model.thresholds.tolist()
    d["weights"] = model.weights.tolist()
    d["offset"] = model.offset
    if model.family == "multislope":
        d.update(U=model.U, a=model.a, b=model.b, h=model.h)
    if model.family == "pwl":
        d["rising"] = [{"x": x.tolist(), "y": y.tolist()} for x, y in model.rising]
        d["falling"] = [{"x": x.tolist(), "y": y.tolist()} for x, y in model.falling]
    d["input_range"] = list(model.input_range)
    d["initial_state"] = model.initial_state.tolist()
    d["units"] = dict(model.units)
    if getattr(model, "metadata", None):
        d["metadata"] = model.metadata
    return d


def model_from_dict(d, source="model"):
    """Build a model from a dict of the schema above; errors name ``source`` and the key."""
    if not isinstance(d, dict):
        raise InvalidModelError(f"{source}: a model must be a JSON object, got "
                                f"{type(d).__name__}")
    family = d.get("family")
    if family not in _KEYS:
        raise InvalidModelError(f"{source}: key 'family' must be one of "
                                f"{', '.join(sorted(_KEYS))}; got {family!r}")
    for key in _REQUIRED[family]:
        if key not in d:
            raise InvalidModelError(f"{source}: missing required key {key!r}")
    unknown = sorted(set(d) - _KEYS[family])
    if unknown:
        raise InvalidModelError(f"{source}: unknown key {unknown[0]!r} for family {family!r} "
                                f"(allowed: {', '.join(sorted(_KEYS[family]))})")
    common = {k: d[k] for k in ("offset", "input_range", "initial_state", "units") if k in d}
    try:
        if family == "classical":
            model = ClassicalPI(d["thresholds"], d["weights"], **common)
        elif family == "multislope":
            shape = {k: d[k] for k in ("U", "a", "b", "h") if k in d}
            model = MultislopePI(d["thresholds"], d["weights"], **shape, **common)
        else:
            model = PiecewiseLinearPI([_points(p, f"rising[{i}]") for i, p in
                                       enumerate(d["rising"])],
                                      [_points(p, f"falling[{i}]") for i, p in
                                       enumerate(d["falling"])], d["weights"], **common)
    except InvalidModelError as err:
        raise InvalidModelError(f"{source}: {err}") from None
    except (TypeError, ValueError) as err:
        raise InvalidModelError(f"{source}: {err}") from None
    model.metadata = d.get("metadata", {})
    return model


def _points(p, name):
    if not isinstance(p, dict) or "x" not in p or "y" not in p:
        raise InvalidModelError(f"{name} must be an object with lists 'x' and 'y'")
    return (p["x"], p["y"])


def load_model(path_or_dict):
    """A model from a JSON file path or from a dict of the schema in this module.

    Examples
    --------
    >>> m = load_model({"family": "classical", "thresholds": [0, 10, 30, 150],
    ...                 "weights": [0.008, 0.252, 0.019, 0.582]})
    >>> m.family, m.n_operators
    ('classical', 4)
    """
    if isinstance(path_or_dict, dict):
        return model_from_dict(path_or_dict)
    path = os.fspath(path_or_dict)
    try:
        with open(path, encoding="utf-8-sig") as f:  # tolerate a byte-order mark
            d = json.load(f)
    except OSError as err:
        raise InvalidModelError(f"{path}: cannot read model: {err.strerror}") from None
    except json.JSONDecodeError as err:
        raise InvalidModelError(f"{path}:{err.lineno}:{err.colno}: invalid JSON: {err.msg}") \
            from None
    return model_from_dict(d, source=path)


def save_model(model, path):
    """Write ``model`` as JSON; the file appears only once it is complete."""
    write_atomically(path, json.dumps(model_to_dict(model), indent=2) + "\n")


def write_atomically(path, text):
    """Write ``text`` to ``path`` through a temporary file in the same folder, so that
    an error never leaves a partial file behind."""
    path = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(dir=folder, prefix=".pihyst-", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="") as f:
            f.write(text)
        # mkstemp makes the file private (0600); give it the mode a plain open() would
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise

