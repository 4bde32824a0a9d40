"""Run logs as HDF5 (optional extra ``pihyst[hdf5]``, h5py): one dataset per column of
:data:`~pihyst.rig._log.COLUMNS` (strings for phase and statuses), grown and flushed
every tick; the metadata and the notes (why the run stopped) as attributes."""

from dataclasses import astuple

import numpy as np

from pihyst.rig._log import COLUMNS

_TEXT = ("phase", "sensor_status", "supply_status")


class Hdf5RunLog:
    """Same interface as :class:`~pihyst.rig._log.CsvRunLog`."""

    def __init__(self, path, metadata=(), fsync=False):
        try:
            import h5py
        except ImportError:
            raise ImportError("HDF5 logs need h5py: pip install 'pihyst[hdf5]'") from None
        self.path = path
        self._file = h5py.File(path, "w")
        self._file.attrs["metadata"] = [str(m) for m in metadata]
        self._file.attrs["notes"] = []
        text = h5py.string_dtype()
        for name in COLUMNS:
            dtype = text if name in _TEXT else (np.int64 if name in ("tick", "overrun")
                                                else np.float64)
            self._file.create_dataset(name, shape=(0,), maxshape=(None,), dtype=dtype,
                                      chunks=(256,))
        self._n = 0
        self._file.flush()

    def write(self, record):
        for name, value in zip(COLUMNS, astuple(record)):
            ds = self._file[name]
            ds.resize((self._n + 1,))
            ds[self._n] = value
        self._n += 1
        self._file.flush()

    def note(self, text):
        self._file.attrs["notes"] = list(self._file.attrs["notes"]) + [str(text)]
        self._file.flush()

    def close(self):
        if self._file.id.valid:
            self._file.close()
