"""Shared by tests/fleet and tests/cli: a small fleet of records (one per actuator) and
a Dask LocalCluster fixture (imported by a test module, so started once per module)."""

import numpy as np
import pytest

import pihyst
from pihyst.io import write_columns


def ramps(levels, n=25):
    levels = np.asarray(levels, dtype=float)
    return np.concatenate([np.linspace(a, b, n, endpoint=False) for a, b in
                           zip(levels[:-1], levels[1:])] + [levels[-1:]])


def actuator_record(k):
    """Actuator k: a multislope loop with its own weights and sensor noise, as (u, y)."""
    u = ramps([0, 150, 0, 120, 30, 150, 0, 90, 10, 150, 0])
    model = pihyst.MultislopePI([0, 20, 30, 40],
                                np.array([0.196, 0.026, 0.046, 0.028]) * (1 + 0.05 * k))
    y = model.predict(u) + np.random.default_rng(k).normal(0, 0.01, u.size)
    return u, y


def write_record(path, u, y):
    write_columns(path, {"time_s": np.arange(u.size, dtype=float), "voltage_V": u,
                         "displacement_um": y})
    return path


def make_fleet_dir(tmp_path):
    """Three good records and two bad ones (text in a column; too short to fit)."""
    folder = tmp_path / "records"
    folder.mkdir()
    for k in range(3):
        write_record(folder / f"act{k}.csv", *actuator_record(k))
    (folder / "text.csv").write_text("voltage_V,displacement_um\n0,0\n1,abc\n",
                                     encoding="utf-8")
    write_record(folder / "short.csv", np.array([0.0, 1.0, 2.0]), np.array([0.0, 0.1, 0.2]))
    return folder


def local_client():
    """A client of a LocalCluster of 2 in-process workers (threads) on a loopback TCP
    address, for a module-scoped fixture (``yield from local_client()``); skips the
    module's Dask tests when dask.distributed is not installed."""
    distributed = pytest.importorskip(
        "distributed", reason="needs dask.distributed: pip install 'pihyst[dask]'")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address=":0", protocol="tcp",
                                  host="127.0.0.1") as cluster, \
            distributed.Client(cluster) as client:
        yield client
