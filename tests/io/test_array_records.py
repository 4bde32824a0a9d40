"""Array records: .npy, .npz, .mat v5 (SciPy) and v7.3 (h5py), HDF5, Parquet, and the
arrays a Python function returns; written small in each test."""

import numpy as np
import pytest

from pihyst.io import RecordError, read_record

U = np.array([0.0, 1.5, 3.0, 1.5, 0.25])
Y = np.array([0.0, 2.0, 5.0, 3.0, 0.5])
T = np.arange(5) * 0.01


def check(rec, time=True):
    np.testing.assert_array_equal(rec.voltage, U)
    np.testing.assert_array_equal(rec.displacement, Y)
    if time:
        np.testing.assert_array_equal(rec.time, T)


def test_npz_by_default_names_and_by_given_names(tmp_path):
    path = tmp_path / "r.npz"
    np.savez(path, voltage_V=U, displacement_um=Y, time_s=T)
    check(read_record(path))
    np.savez(path, u=U, y=Y * 1e-6)
    rec = read_record(path, voltage="u", displacement="y", displacement_unit="m", rate=100)
    np.testing.assert_allclose(rec.displacement, Y, rtol=1e-15)
    np.testing.assert_allclose(rec.time, T)


def test_npy_matrix_columns_by_position(tmp_path, small_blocks):
    path = tmp_path / "r.npy"
    np.save(path, np.column_stack([T, U, Y]))
    check(read_record(path, time=1, voltage=2, displacement=3))
    with pytest.raises(RecordError, match="no 'voltage_V' for the voltage"):
        read_record(path)
    with pytest.raises(RecordError, match="column K must be 1..3"):
        read_record(path, time=1, voltage="array:4", displacement=3)


def test_mat_v5(tmp_path):
    from scipy.io import savemat
    path = tmp_path / "r.mat"
    savemat(path, {"u": U.reshape(-1, 1), "y": Y, "data": np.column_stack([T, U, Y])})
    rec = read_record(path, voltage="u", displacement="y")
    check(rec, time=False)
    assert rec.metadata["format"] == "mat (v5)"
    check(read_record(path, time="data:1", voltage="data:2", displacement="data:3"))


def _mat73(path, variables):
    """A MATLAB v7.3 file as MATLAB writes it: HDF5 after a 512-byte header, matrices
    stored column-major (so transposed in HDF5)."""
    h5py = pytest.importorskip("h5py")
    with h5py.File(path, "w", userblock_size=512) as f:
        for name, a in variables.items():
            f[name] = np.asarray(a).T
    with open(path, "r+b") as f:
        f.write(b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: test HDF5 schema 1.00 .")


def test_mat_v73(tmp_path):
    path = tmp_path / "r.mat"
    _mat73(path, {"u": U.reshape(-1, 1), "y": Y.reshape(-1, 1),
                  "data": np.column_stack([T, U, Y])})
    rec = read_record(path, voltage="u", displacement="y")
    check(rec, time=False)
    assert rec.metadata["format"] == "mat (v7.3)"
    check(read_record(path, time="data:1", voltage="data:2", displacement="data:3"))
    check(read_record(path, time=1, voltage=2, displacement=3))


def test_hdf5_nested_datasets(tmp_path, small_blocks):
    h5py = pytest.importorskip("h5py")
    path = tmp_path / "r.h5"
    with h5py.File(path, "w") as f:
        f["run/voltage"] = U
        f["run/position_nm"] = Y * 1000
        f["run/t"] = T
    rec = read_record(path, voltage="run/voltage", displacement="run/position_nm",
                      time="run/t")
    np.testing.assert_allclose(rec.displacement, Y, rtol=1e-15)
    assert rec.metadata["displacement_unit"] == "nm"   # from the name


def test_parquet(tmp_path):
    pa = pytest.importorskip("pyarrow")
    import pyarrow.parquet as pq
    path = tmp_path / "r.parquet"
    pq.write_table(pa.table({"time_s": T, "voltage_V": U, "displacement_um": Y}), path)
    check(read_record(path))


def test_function_reader(tmp_path):
    module = tmp_path / "my_rig.py"
    module.write_text("import numpy as np\n"
                      "def load(path):\n"
                      "    a = np.load(path)\n"
                      "    return {'voltage': a[1], 'displacement': a[2] / 1000, "
                      "'metadata': {'rate': 100.0, 'sensor': 'capacitive'}}\n")
    data = tmp_path / "raw.npy"
    np.save(data, np.vstack([T, U, Y * 1000]))
    rec = read_record(data, reader=f"{module}:load")
    check(rec)
    assert rec.metadata["format"] == "python function" and rec.metadata["rate_hz"] == 100.0

    def direct(path):
        return {"voltage": U, "displacement": Y}
    check(read_record("anything", reader=direct), time=False)


@pytest.mark.parametrize("bad,message", [
    ({"u": np.array([0.0, np.nan]), "y": np.zeros(2)}, r"'u' sample 1: nan is not a finite"),
    ({"u": np.zeros(3), "y": np.zeros(2)}, "different lengths"),
    ({"u": np.array(["a", "b"]), "y": np.zeros(2)}, "not numbers"),
])
def test_bad_arrays_name_variable_and_sample(tmp_path, bad, message):
    path = tmp_path / "r.npz"
    np.savez(path, **bad)
    with pytest.raises(RecordError, match=message):
        read_record(path, voltage="u", displacement="y")


def test_unreadable_files(tmp_path):
    bad = tmp_path / "r.mat"
    bad.write_bytes(b"not a mat file at all" * 10)
    with pytest.raises(RecordError, match="r.mat: cannot read"):
        read_record(bad, voltage="u", displacement="y")
    with pytest.raises(RecordError, match="cannot read file"):
        read_record(tmp_path / "missing.npz")
