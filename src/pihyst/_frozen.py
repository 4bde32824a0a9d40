"""Values that cannot be changed after a model is made (issue 24, item 11):

- :func:`frozen_array`: a NumPy array over immutable memory (a ``bytes`` object), so
  that ``a.setflags(write=True)`` fails too, not only ``a[0] = 1``;
- :func:`frozen`: metadata made deeply read-only: every mapping a :class:`FrozenDict`
  (a ``dict`` that refuses every change, so that ``json.dumps`` and ``isinstance(x,
  dict)`` still work), every list or tuple a :class:`FrozenList` (equal to a list),
  every array a frozen array.
"""

from types import MappingProxyType

import numpy as np

from pihyst.exceptions import InvalidArgumentError


def frozen_array(values, dtype=None):
    """A read-only copy of ``values`` that cannot be made writable again."""
    a = np.ascontiguousarray(values, dtype=dtype)
    return np.frombuffer(a.tobytes(), dtype=a.dtype).reshape(a.shape)


def _refuse(self, *args, **kwargs):
    # InvalidArgumentError is a TypeError too: what changing a dict or list of it raises
    raise InvalidArgumentError("a model's metadata is read-only: make a new model with "
                               "model.replace(metadata={...})")


class FrozenDict(dict):
    """A dict that cannot be changed (its items are frozen too when made by
    :func:`frozen`)."""

    __setitem__ = __delitem__ = __ior__ = _refuse
    clear = pop = popitem = setdefault = update = _refuse

    def __reduce__(self):          # pickle and copy without __setitem__
        return (FrozenDict, (dict(self),))

    def __repr__(self):
        return f"FrozenDict({dict.__repr__(self)})"


class FrozenList(list):
    """A list that cannot be changed (equal to the list of its items; JSON writes it
    as one)."""

    __setitem__ = __delitem__ = __iadd__ = __imul__ = _refuse
    append = extend = insert = pop = remove = clear = sort = reverse = _refuse

    def __reduce__(self):
        return (FrozenList, (list(self),))

    def __repr__(self):
        return f"FrozenList({list.__repr__(self)})"


def frozen(value):
    """``value`` deeply read-only (mappings, lists and tuples, arrays; other values, such
    as numbers and strings, are immutable already)."""
    if isinstance(value, (dict, MappingProxyType)):
        return FrozenDict({k: frozen(v) for k, v in value.items()})
    if isinstance(value, (list, tuple)):
        return FrozenList(frozen(v) for v in value)
    if isinstance(value, np.ndarray):
        return frozen_array(value)
    return value

