"""Records stored as arrays: NumPy ``.npy``/``.npz``, MATLAB ``.mat`` (v5 through SciPy,
v7.3 through h5py), HDF5 (h5py), Parquet (pyarrow), and the arrays a Python function
returns.

A quantity is one variable (a vector), ``NAME:K`` (column K, 1-based, of a matrix) or
``K`` alone (column K of the file's only matrix). Samples are named in messages by their
0-based index in the variable.
"""

import os
import struct
import tokenize
import zipfile
import zlib

import numpy as np

from pihyst.exceptions import RecordError
from pihyst.io._column_sinks import METADATA_KEY, SIDECAR_FORMAT, read_embedded_metadata

MAT_V73_SIGNATURE = b"\x89HDF\r\n\x1a\n"


class ArraySource:
    """Named arrays (1-D or 2-D with samples along the first axis), read lazily where the
    format allows (memory-mapped .npy, HDF5 datasets)."""

    def __init__(self, path, kind, variables, extra=None):
        self.path, self.kind = path, kind
        self.variables = variables      # name -> array-like (sliceable, .shape)
        self.extra = dict(extra or {})
        self.columns = tuple(name for name, a in variables.items() if len(a.shape) == 1)

    def metadata(self):
        return {"format": self.kind, **self.extra}

    def _matrix(self):
        matrices = [n for n, a in self.variables.items() if len(a.shape) == 2]
        if len(matrices) != 1:
            return None
        return matrices[0]

    def resolve(self, spec, quantity):
        """(variable, column or None) for a spec: a name, NAME:K, or K."""
        text = str(spec).strip()
        name, _, col = text.rpartition(":") if ":" in text else ("", "", "")
        if not name and text.isdigit():
            matrix = self._matrix()
            if matrix is None:
                raise RecordError(self.path, f"--{quantity} {text}: a column number needs a "
                                  f"file with exactly one matrix; name a variable "
                                  f"({self.inventory()})")
            name, col = matrix, text
        elif not name:
            name, col = text, ""
        if name not in self.variables:
            raise RecordError(self.path, f"no variable {name!r} for the {quantity} "
                              f"({self.inventory()})")
        shape = self.variables[name].shape
        if col:
            if len(shape) == 2 and shape[0] == 1 and shape[1] > 1:
                raise RecordError(self.path, f"--{quantity} {text}: {name!r} has shape "
                                  f"{shape}, one row: one sample of {shape[1]} columns, or "
                                  f"{shape[1]} samples of one quantity? Save samples along "
                                  f"the first axis (shape (n, k)), or each quantity as a "
                                  f"vector")
            if not col.isdigit() or len(shape) != 2 or not 1 <= int(col) <= shape[1]:
                columns = shape[1] if len(shape) == 2 else 0
                raise RecordError(self.path, f"--{quantity} {text}: {name!r} has shape "
                                  f"{shape}; column K must be 1..{columns} of a matrix")
            return name, int(col) - 1
        if len(shape) == 2 and 1 in shape:
            return name, 0
        if len(shape) != 1:
            raise RecordError(self.path, f"{name!r} has shape {shape}: name one column "
                              f"as {name}:K for the {quantity}")
        return name, None

    def default(self, names):
        """The first of ``names`` the file has as a vector, else None."""
        for n in names:
            if n in self.variables and len(self.variables[n].shape) == 1:
                return n, None
        return None

    def inventory(self):
        parts = [f"{n} {tuple(a.shape)}" for n, a in self.variables.items()]
        return "variables: " + (", ".join(parts) if parts else "none")

    def length(self, ref):
        name, col = ref
        a = self.variables[name]
        if len(a.shape) == 2 and col is not None and a.shape[0] == 1:
            return a.shape[1]
        return a.shape[0]

    def label(self, ref):
        name, col = ref
        return repr(name) if col is None else f"'{name}' column {col + 1}"

    def read(self, ref, start, stop):
        name, col = ref
        a = self.variables[name]
        if len(a.shape) == 1:
            out = a[start:stop]
        elif a.shape[0] == 1 and a.shape[1] != 1:
            out = a[0, start:stop]
        else:
            out = a[start:stop, col]
        out = np.asarray(out)
        # (by kind: NumPy counts timedelta64 among the integers)
        if out.dtype.kind not in "fiub":
            raise RecordError(self.path, f"{self.label(ref)} holds {out.dtype} values, not "
                              "numbers")
        return out.astype(np.float64)

    def common_length(self, refs):
        """The one length of the quantities ``refs`` (RecordError if they differ or are
        empty)."""
        n = {self.length(r) for r in refs}
        if len(n) != 1:
            lengths = ", ".join(f"{self.label(r)} {self.length(r)}" for r in refs)
            raise RecordError(self.path, f"the quantities have different lengths ({lengths})")
        n = n.pop()
        if n == 0:
            raise RecordError(self.path, "no samples")
        return n

    def blocks(self, refs, block_rows, progress=None):
        n = self.common_length(refs)
        for start in range(0, n, block_rows):
            stop = min(n, start + block_rows)
            values = np.column_stack([self.read(r, start, stop) for r in refs])
            bad = ~np.isfinite(values)
            if bad.any():
                i, j = np.argwhere(bad)[0]
                raise RecordError(self.path, f"{self.label(refs[j])} sample {start + i}: "
                                  f"{values[i, j]} is not a finite number")
            if progress is not None:
                progress(stop, n)
            yield values

    def error(self, row, ref, message):
        return RecordError(self.path, f"{self.label(ref)} sample {row}: {message}")

    def close(self):
        closer = self.extra.pop("_close", None)
        if closer is not None:
            closer()


def open_array_source(path, kind):
    path = os.fspath(path)
    try:
        if kind == "npy":
            a = np.load(path, mmap_mode="r", allow_pickle=False)
            return ArraySource(path, kind, {"array": a})
        if kind == "npz":
            # (the file opened here, so that it is closed when the zip is refused)
            with open(path, "rb") as fh, np.load(fh, allow_pickle=False) as z:
                variables = {}
                for k in z.files:
                    try:
                        variables[k] = z[k]
                    except (ValueError, EOFError, zipfile.BadZipFile, zlib.error,
                            OSError) as err:
                        raise RecordError(path, f"{k!r}: cannot read it: "
                                          f"{_one_line(err)}") from None
                return ArraySource(path, kind, variables)
        if kind == "mat":
            return _open_mat(path)
        if kind == "hdf5":
            return _open_hdf5(path, transpose=False)
        if kind == "parquet":
            return _open_parquet(path)
    except RecordError:
        raise
    except OSError as err:
        raise RecordError(path, f"cannot read file: {err.strerror or err}") from None
    # what the libraries raise on a truncated, corrupt or mistyped file: the user's file
    except (ValueError, EOFError, zipfile.BadZipFile, zlib.error, KeyError, IndexError,
            TypeError, NotImplementedError, OverflowError, MemoryError, struct.error,
            UnicodeDecodeError, AttributeError, SyntaxError, tokenize.TokenError,
            RecursionError) as err:
        # (a .npy header is a Python literal: a corrupt one is a SyntaxError or TokenError)
        raise RecordError(path, f"cannot read {kind} file: {_one_line(err)}") from None
    except Exception as err:
        if type(err).__name__ == "MatReadError":     # scipy.io.matlab's (a ValueError
            raise RecordError(path, f"cannot read {kind} file: {_one_line(err)}") from None
        raise                                       # in recent SciPy; not in all)
    raise ValueError(f"unknown record kind {kind!r}")


def _one_line(err):
    text = " ".join(str(err).split())
    if isinstance(err, (EOFError, zipfile.BadZipFile, zlib.error, SyntaxError,
                        tokenize.TokenError)) or not text:
        text = f"{type(err).__name__}: {text}" if text else type(err).__name__
        return text + " (the file is truncated or corrupt)"
    return text


def _open_mat(path):
    with open(path, "rb") as f:
        head = f.read(520)
    if head[512:520] == MAT_V73_SIGNATURE:
        return _open_hdf5(path, transpose=True, kind="mat (v7.3)")
    data = _loadmat_guarded(path)
    variables = {k: v for k, v in data.items() if not k.startswith("__")
                 and isinstance(v, np.ndarray) and v.ndim in (1, 2)
                 and v.dtype.kind in "fiub"}
    return ArraySource(path, "mat (v5)", {k: _vector(v) for k, v in variables.items()})


def _loadmat(path):
    from scipy.io import loadmat
    try:
        data = loadmat(path)
    # loadmat raises NotImplementedError for MATLAB formats it cannot read (v4 variants,
    # some v7 compressed types): the user's file, not a gap in pihyst
    # whatever SciPy raises on a corrupt file is the file's fault (seen: MatReadError,
    # zlib.error, struct.error, even UnboundLocalError): one line, never its traceback
    except Exception as err:  # noqa: BLE001
        raise RecordError(path, f"cannot read MATLAB file: {_one_line(err)}") from None
    return {k: v for k, v in data.items() if not k.startswith("__")
            and isinstance(v, np.ndarray) and v.ndim in (1, 2) and v.dtype.kind in "fiub"}


def _loadmat_guarded(path):
    """SciPy's loadmat in a forked child: its C reader can crash (SIGSEGV) on a corrupt
    file (the fuzz test found bit flips that do), which must be a one-line error, not
    the end of pihyst. Without fork (Windows), called directly."""
    if not hasattr(os, "fork"):
        return _loadmat(path)
    import pickle
    import signal
    import warnings
    r, w = os.pipe()
    with warnings.catch_warnings():      # (Python 3.12 warns of fork with threads: the
        warnings.simplefilter("ignore")  # child only reads the file and exits)
        pid = os.fork()
    if pid == 0:                         # the child: read, send back, exit at once
        os.close(r)
        import faulthandler
        faulthandler.disable()           # its crash is the parent's one line, not a dump
        try:
            try:
                out = ("ok", _loadmat(path))
            except RecordError as err:
                out = ("error", err.message)
            with os.fdopen(w, "wb") as f:
                f.write(pickle.dumps(out, protocol=pickle.HIGHEST_PROTOCOL))
        finally:
            os._exit(0)
    os.close(w)
    with os.fdopen(r, "rb") as f:
        payload = f.read()
    _, status = os.waitpid(pid, 0)
    if os.WIFSIGNALED(status) or not payload:
        sig = os.WTERMSIG(status) if os.WIFSIGNALED(status) else 0
        name = signal.Signals(sig).name if sig else "no result"
        raise RecordError(path, f"cannot read MATLAB file: SciPy's reader crashed on it "
                          f"({name}): the file is corrupt")
    kind, value = pickle.loads(payload)
    if kind == "error":
        raise RecordError(path, value)
    return value


def _vector(a):
    if a.ndim == 2 and 1 in a.shape:
        return a.reshape(-1)
    return a


def need(module, extra, path):
    """Import ``module`` or raise a one-line RecordError naming the pip extra."""
    try:
        return __import__(module)
    except ImportError:
        raise RecordError(path, f"reading this file needs {module}: "
                          f"pip install 'pihyst[{extra}]'") from None


def _open_hdf5(path, transpose, kind="hdf5"):
    h5py = need("h5py", "hdf5", path)
    f = h5py.File(path, "r")
    variables = {}

    def visit(name, obj):
        if isinstance(obj, h5py.Dataset) and obj.ndim in (1, 2) and obj.dtype.kind in "fiub":
            if obj.ndim == 2 and 1 in obj.shape:
                variables[name] = _Flat(obj)
            else:
                variables[name] = _Transposed(obj) if transpose and obj.ndim == 2 else obj
    f.visititems(visit)
    extra = {"_close": f.close}
    written = _embedded(f.attrs.get(METADATA_KEY))
    if written is not None:      # an HDF5 file pihyst wrote: its metadata attribute
        extra["pihyst_metadata"] = written
    return ArraySource(path, kind, variables, extra)


def _embedded(text):
    """The metadata pihyst wrote into a file (a JSON string), or None."""
    if text is None:
        return None
    data = read_embedded_metadata(text)
    return data if data is not None and data.get("format") == SIDECAR_FORMAT else None


class _Flat:
    """A 2-D HDF5 dataset of one row or one column, read as a vector."""

    def __init__(self, dataset):
        self.dataset = dataset
        self.shape = (max(dataset.shape),)

    def __getitem__(self, key):
        row = self.dataset.shape[0] == 1
        return np.asarray(self.dataset[0, key] if row else self.dataset[key, 0])


class _Transposed:
    """A 2-D HDF5 dataset read transposed (MATLAB v7.3 stores matrices column-major)."""

    def __init__(self, dataset):
        self.dataset = dataset
        self.shape = dataset.shape[::-1]

    def __getitem__(self, key):
        if isinstance(key, tuple):
            return np.asarray(self.dataset[key[::-1]]).T
        return np.asarray(self.dataset[:, key]).T


def _open_parquet(path):
    need("pyarrow", "fast", path)
    import pyarrow.parquet as pq
    table = pq.read_table(path)
    variables = {name: table.column(name).to_numpy() for name in table.column_names
                 if table.schema.field(name).type.num_fields == 0}
    # a Parquet file pihyst wrote: its metadata in the file's key-value metadata
    meta = pq.ParquetFile(path).metadata.metadata or {}
    written = _embedded(meta.get(METADATA_KEY.encode()))
    return ArraySource(path, "parquet", variables,
                       None if written is None else {"pihyst_metadata": written})


def function_source(name, result):
    """The record a Python function returned: a mapping with ``voltage``,
    ``displacement``, ``time`` (arrays, each optional) and ``metadata``."""
    if hasattr(result, "voltage") and hasattr(result, "displacement"):
        result = {"voltage": result.voltage, "displacement": result.displacement,
                  "time": getattr(result, "time", None),
                  "metadata": dict(getattr(result, "metadata", {}) or {})}
    if not isinstance(result, dict):
        raise RecordError(name, f"the reader returned {type(result).__name__}; expected a "
                          "dict with 'voltage', 'displacement', 'time' and 'metadata' "
                          "or a pihyst.io.Record")
    unknown = set(result) - {"voltage", "displacement", "time", "metadata"}
    if unknown:
        raise RecordError(name, "the reader returned unknown keys "
                          + ", ".join(sorted(repr(k) for k in unknown)))
    metadata = result.get("metadata") or {}
    if not isinstance(metadata, dict):
        raise RecordError(name, f"the reader's 'metadata' is {type(metadata).__name__}, "
                          "expected a dict")
    variables = {}
    for key in ("voltage", "displacement", "time"):
        if result.get(key) is not None:
            try:
                a = np.asarray(result[key])
            except (ValueError, TypeError) as err:    # e.g. rows of different lengths
                raise RecordError(name, f"the reader's {key!r} is not an array of numbers "
                                  f"({err})") from None
            if a.ndim != 1:
                raise RecordError(name, f"the reader's {key!r} has shape {a.shape}, "
                                  "expected one dimension")
            variables[key] = a
    return ArraySource(name, "python function", variables,
                       {"found": dict(metadata)})
