"""Records written as Parquet or HDF5 when the output name asks for it: the same columns as
the CSV, the metadata inside the file (no sidecar), read back by pihyst."""

import os
import sys

import numpy as np
import pytest

from pihyst.cli import main
from pihyst.exceptions import InvalidArgumentError
from pihyst.io import ColumnWriter, read_record

FORMATS = [pytest.param(".parquet", "pyarrow", id="parquet"),
           pytest.param(".h5", "h5py", id="hdf5")]


def columns(n=1000, seed=0):
    rng = np.random.default_rng(seed)
    return {"time_s": np.arange(n) / 1e3, "voltage_V": rng.uniform(0, 150, n),
            "displacement_um": rng.normal(10, 5, n)}


@pytest.mark.parametrize("ext,module", FORMATS)
def test_written_in_blocks_read_back_exactly_with_the_metadata(tmp_path, ext, module):
    pytest.importorskip(module)
    path = tmp_path / f"rec{ext}"
    data = columns()
    with ColumnWriter(path, list(data), comments=["made by a test"],
                      metadata={"model": "m.json"}) as w:
        for start in range(0, 1000, 300):
            w.write({k: v[start:start + 300] for k, v in data.items()})
    assert sorted(os.listdir(tmp_path)) == [path.name]          # no sidecar, no temporary
    rec = read_record(path)
    for name, got in (("time_s", rec.time), ("voltage_V", rec.voltage),
                      ("displacement_um", rec.displacement)):
        np.testing.assert_array_equal(got, data[name])
    meta = rec.metadata["pihyst_metadata"]
    assert meta["rows"] == 1000 and meta["columns"] == list(data)
    assert meta["comments"] == ["made by a test"] and meta["model"] == "m.json"
    assert meta["file"] == path.name


@pytest.mark.parametrize("ext,module", FORMATS)
def test_an_aborted_write_leaves_nothing(tmp_path, ext, module):
    pytest.importorskip(module)
    path = tmp_path / f"rec{ext}"
    with pytest.raises(RuntimeError):
        with ColumnWriter(path, ["voltage_V"]) as w:
            w.write({"voltage_V": np.zeros(10)})
            raise RuntimeError("stopped")
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("ext,module", FORMATS)
def test_without_the_library_one_line_naming_the_extra(tmp_path, monkeypatch, ext, module):
    monkeypatch.setitem(sys.modules, module, None)
    with pytest.raises(InvalidArgumentError, match=r"needs .*pip install 'pihyst\["):
        ColumnWriter(tmp_path / f"rec{ext}", ["voltage_V"])
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("ext,module", FORMATS)
def test_predict_writes_the_format_asked_for_and_reads_it_back(tmp_path, capsys, ext,
                                                                 module):
    pytest.importorskip(module)
    model = "examples/paper_table1_classical.json"
    out = tmp_path / f"pred{ext}"
    assert main(["predict", model, "examples/triangle_0_150V.csv", "-o", str(out)]) == 0
    assert main(["predict", model, str(out), "-o", str(tmp_path / "again.csv")]) == 0
    said = capsys.readouterr().out
    assert f"read {out}" in said and "metadata from its" in said
    first, again = read_record(out, need=("voltage", "displacement")), \
        read_record(tmp_path / "again.csv", need=("voltage", "displacement"))
    np.testing.assert_array_equal(first.displacement, again.displacement)
    assert "predict" in first.metadata["pihyst_metadata"]["comments"][0]
