"""Record outputs in Parquet and HDF5, for :class:`pihyst.io.ColumnWriter` when the output
name asks for them (``.parquet``; ``.h5``, ``.hdf5``): the same columns as the CSV, block
by block, and the metadata the CSV keeps in its sidecar inside the file itself -- the
Parquet file's key-value metadata ``pihyst`` and the HDF5 file's attribute ``pihyst``
(JSON text),
which pihyst's reader reads back into the record's metadata.

The file appears only once complete: it is written to a hidden ``.pihyst-*.tmp`` in the
target's folder (pyarrow and h5py write by path), renamed over the target at the end and
removed on any error; one left by a killed writer is removed by a later write in that
folder once an hour old (:mod:`pihyst._atomic`).
"""

import json
import os
import tempfile

import numpy as np

from pihyst._atomic import TEMP_PREFIX, TEMP_SUFFIX, _named, _remove_stale_temporaries
from pihyst.exceptions import InvalidArgumentError

METADATA_KEY = "pihyst"
#: the "format" entry of the metadata pihyst keeps with a record it writes
SIDECAR_FORMAT = "pihyst CSV metadata"
FORMATS = {".parquet": "parquet", ".h5": "hdf5", ".hdf5": "hdf5"}
_EXTRAS = {"parquet": ("pyarrow", "fast"), "hdf5": ("h5py", "hdf5")}


def output_format(path):
    """'parquet', 'hdf5' or 'csv': the format an output name asks for."""
    return FORMATS.get(os.path.splitext(os.fspath(path))[1].lower(), "csv")


def check_output_format(path):
    """An InvalidArgumentError naming the extra now, before any work, when the format
    ``path`` asks for needs a library that is not installed."""
    kind = output_format(path)
    if kind == "csv":
        return
    module, extra = _EXTRAS[kind]
    try:
        __import__(module)
    except ImportError:
        name = "HDF5" if kind == "hdf5" else "Parquet"
        raise InvalidArgumentError(f"{path}: writing {name} needs {module}: pip install "
                                   f"'pihyst[{extra}]'") from None


def metadata_text(metadata):
    return json.dumps(metadata, default=str)


def read_embedded_metadata(text):
    """The metadata dict of a ``pihyst`` key or attribute, or None when it is not one."""
    if isinstance(text, bytes):
        text = text.decode("utf-8", errors="replace")
    try:
        data = json.loads(text)
    except (TypeError, ValueError):
        return None
    return data if isinstance(data, dict) else None


class _TemporarySink:
    """A temporary beside ``path``, put in place by :meth:`commit`."""

    def __init__(self, path):
        self.path = os.fspath(path)
        folder = os.path.dirname(os.path.abspath(self.path))
        try:
            _remove_stale_temporaries(folder)
            fd, self._tmp = tempfile.mkstemp(dir=folder, prefix=TEMP_PREFIX, suffix=TEMP_SUFFIX)
            os.close(fd)
        except OSError as err:
            raise _named(err, self.path) from None

    def _replace(self):
        umask = os.umask(0)
        os.umask(umask)
        try:
            os.chmod(self._tmp, 0o666 & ~umask)
            os.replace(self._tmp, self.path)
        except OSError as err:
            self._unlink()
            raise _named(err, self.path) from None
        self._tmp = None

    def _unlink(self):
        if self._tmp is not None:
            try:
                os.unlink(self._tmp)
            except OSError:
                pass
            self._tmp = None


class ParquetSink(_TemporarySink):
    """Columns of float64 written as Parquet row groups, one per :meth:`write`."""

    def __init__(self, path, names, metadata):
        super().__init__(path)
        import pyarrow as pa
        import pyarrow.parquet as pq
        self._pa = pa
        self.names = list(names)
        schema = pa.schema([(n, pa.float64()) for n in self.names])
        try:
            self._writer = pq.ParquetWriter(self._tmp, schema)
        except BaseException:
            self._unlink()
            raise

    def write(self, data):
        self._writer.write_table(self._pa.table(dict(zip(self.names, data))))

    def commit(self, metadata):
        # in the file's key-value metadata (the footer), once the rows are known
        self._writer.add_key_value_metadata({METADATA_KEY: metadata_text(metadata)})
        self._writer.close()
        self._replace()

    def abort(self):
        try:
            self._writer.close()
        except Exception:     # noqa: BLE001 - giving up the file; the error is the caller's
            pass
        self._unlink()


class HDF5Sink(_TemporarySink):
    """One resizable float64 dataset per column (named as the CSV's header), grown by each
    :meth:`write`; the metadata as the file's attribute ``pihyst``."""

    def __init__(self, path, names, metadata):
        super().__init__(path)
        import h5py
        self.names = list(names)
        try:
            self._file = h5py.File(self._tmp, "w")
            for n in self.names:
                self._file.create_dataset(n, shape=(0,), maxshape=(None,), dtype="f8",
                                          chunks=(8192,))
        except BaseException:
            self._unlink()
            raise

    def write(self, data):
        for n, a in zip(self.names, data):
            d = self._file[n]
            start = d.shape[0]
            d.resize((start + len(a),))
            d[start:] = np.asarray(a, dtype=np.float64)

    def commit(self, metadata):
        self._file.attrs[METADATA_KEY] = metadata_text(metadata)
        self._file.close()
        self._replace()

    def abort(self):
        try:
            self._file.close()
        except Exception:     # noqa: BLE001 - giving up the file; the error is the caller's
            pass
        self._unlink()


SINKS = {"parquet": ParquetSink, "hdf5": HDF5Sink}
