"""The input delay on the command line: fit adopts it by default (--delay auto) and the
model file carries it; predict and compensate honour it block by block (the pending
inputs and the preview cross block boundaries); another sample period is a one-line
error with exit status 2."""

import json

import numpy as np
import pytest

import pihyst
from pihyst.cli import main
from pihyst.exceptions import ResourceLimitError
from pihyst.io import _records, read_columns, write_columns

TRUE = pihyst.ClassicalPI([0, 20, 45], [0.3, 0.2, 0.1])
D = 3


def ramps(levels, n=40):
    levels = np.asarray(levels, dtype=float)
    return np.concatenate([np.linspace(a, b, n, endpoint=False) for a, b in
                           zip(levels[:-1], levels[1:])] + [levels[-1:]])


def lagged_record(tmp_path, period=1e-3):
    u = ramps([0, 150, 0, 110, 40, 150, 0, 90, 20, 150, 0, 130, 60, 150, 0])
    y = TRUE.replace(delay=D).predict(u)                 # y[k + D] = H[u](k)
    path = tmp_path / "lagged.csv"
    write_columns(path, {"time_s": period * np.arange(u.size), "voltage_V": u,
                         "displacement_um": y})
    return path, u, y


def test_fit_adopts_the_lag_by_default_and_the_file_carries_it(tmp_path, capsys):
    data, u, y = lagged_record(tmp_path)
    out = tmp_path / "m.json"
    assert main(["fit", str(data), "-o", str(out), "--model", "classical"]) == 0
    model = pihyst.load_model(out)
    assert model.delay == D and model.sample_period == pytest.approx(1e-3)
    delay = model.metadata["fit"]["data"]["delay"]
    assert delay["samples"] == D and delay["auto"] and delay["confirmation"]["samples"] == D
    half = u.size // 2                   # after the first cycles (the state is cycled)
    e = model.predict(u)[half:] - y[half:]
    assert np.sqrt(np.mean(e ** 2)) < 0.01 * np.ptp(y)
    assert main(["fit", str(data), "-o", str(out), "--model", "classical", "--delay",
                 "0"]) == 0
    given = pihyst.load_model(out).metadata["fit"]
    assert pihyst.load_model(out).delay == 0 and not given["data"]["delay"]["auto"]
    # the lag it was told to ignore is what the record favours: said undetermined
    assert given["data"]["delay"]["best"] == D and len(given["undetermined"]) == 1


@pytest.mark.parametrize("time_column", [False, True])
def test_fit_with_a_rate_carries_its_sample_period(tmp_path, time_column):
    data, u, y = lagged_record(tmp_path)
    if not time_column:
        write_columns(data, {"voltage_V": u, "displacement_um": y})
    out = tmp_path / "m.json"
    assert main(["fit", str(data), "-o", str(out), "--model", "classical", "--rate", "500",
                 "--no-creep"] + (["--time", "none"] if time_column else [])) == 0
    model = pihyst.load_model(out)
    assert model.delay == D and model.sample_period == 1 / 500     # exactly
    assert model.delay_at(1e-3) == 2 * D          # converted at another rate


@pytest.mark.parametrize("delay", [100, "n - 1", "n"])
def test_fit_with_a_delay_past_the_last_cycles(tmp_path, capsys, delay):
    data, u, y = lagged_record(tmp_path)
    out = tmp_path / "m.json"
    delay = {"n - 1": u.size - 1, "n": u.size}.get(delay, delay)
    status = main(["fit", str(data), "-o", str(out), "--model", "classical", "--delay",
                   str(delay)])
    err = capsys.readouterr().err
    assert status == 2 and not out.exists() and len(err.splitlines()) == 1
    if delay == 100:             # the record lags by 3, not 100: a poor fit, said so
        assert "the displacement does not follow the voltage" in err
    else:
        assert f"a delay of {delay} samples is too large for a record of {u.size}" in err


def test_predict_carries_the_pending_inputs_across_blocks(tmp_path, monkeypatch):
    data, u, y = lagged_record(tmp_path)
    model_path = tmp_path / "m.json"
    TRUE.replace(delay=D, sample_period=1e-3).save(model_path)
    monkeypatch.setattr(_records, "BLOCK_ROWS", 7)
    out = tmp_path / "p.csv"
    assert main(["predict", str(model_path), str(data), "-o", str(out)]) == 0
    cols, _ = read_columns(out, ["displacement_um"])
    np.testing.assert_allclose(cols["displacement_um"], y, rtol=0, atol=1e-12)


def test_predict_at_another_sample_period(tmp_path, capsys):
    model_path = tmp_path / "m.json"
    TRUE.replace(delay=D, sample_period=1e-3).save(model_path)
    data, u, _ = lagged_record(tmp_path, period=5e-4)       # twice the rate: 2 D samples
    out = tmp_path / "p.csv"
    assert main(["predict", str(model_path), str(data), "-o", str(out)]) == 0
    cols, _ = read_columns(out, ["displacement_um"])
    np.testing.assert_allclose(cols["displacement_um"], TRUE.replace(delay=2 * D).predict(u),
                               rtol=0, atol=1e-12)
    data, _, _ = lagged_record(tmp_path, period=7e-4)
    assert main(["predict", str(model_path), str(data), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "not a whole number of samples at 0.0007 s" in err and len(err.splitlines()) == 1


def record_at(tmp_path, period, lag):
    """A record sampled every ``period`` s whose displacement lags by ``lag`` samples."""
    u = ramps([0, 150, 0, 110, 40, 150, 0, 90, 20, 150, 0])
    y = TRUE.replace(delay=lag).predict(u)
    path = tmp_path / f"at_{period:g}.csv"
    write_columns(path, {"time_s": period * np.arange(u.size), "voltage_V": u,
                         "displacement_um": y})
    return path, u, y


def test_validate_compensate_and_track_convert_the_delay_to_the_record_period(tmp_path,
                                                                             capsys):
    model_path = tmp_path / "m.json"
    model = TRUE.replace(delay=D, sample_period=1e-3)
    model.save(model_path)
    data, u, y = record_at(tmp_path, 5e-4, 2 * D)        # twice the rate: 2 D samples
    assert main(["validate", str(model_path), str(data)]) == 0
    as_is = next(line for line in capsys.readouterr().out.splitlines()
                 if "as the model is" in line)
    assert as_is.split()[4:] == ["0", "0", "0", "0", "%", "0", "%", "0", "%"]   # exact
    at_rate = TRUE.replace(delay=2 * D)
    ref = pihyst.compensate(at_rate, y)
    out = tmp_path / "c.csv"
    assert main(["compensate", str(model_path), str(data), "-o", str(out)]) == 0
    cols, _ = read_columns(out, ["voltage_V"])
    np.testing.assert_allclose(cols["voltage_V"], ref.voltage, rtol=0, atol=1e-12)
    assert main(["track", str(model_path), str(data), "-o", str(out)]) == 0
    cols, _ = read_columns(out, ["voltage_V"])
    np.testing.assert_allclose(cols["voltage_V"], ref.voltage, rtol=0, atol=1e-12)


@pytest.mark.parametrize("command", ["predict", "validate", "compensate", "track"])
def test_a_delay_that_is_no_whole_number_of_samples_is_refused_naming_the_record(
        tmp_path, capsys, command):
    model_path = tmp_path / "m.json"
    TRUE.replace(delay=2, sample_period=0.1).save(model_path)
    data, _, _ = record_at(tmp_path, 0.3, 0)
    out = tmp_path / "out.csv"
    args = [command, str(model_path), str(data)] + ([] if command == "validate" else
                                                    ["-o", str(out)])
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err == (f"pihyst: error: {data}: the model's delay of 2 samples at 0.1 s (0.2 s) "
                   f"is not a whole number of samples at 0.3 s: run it at 0.1 s or "
                   f"resample\n")
    assert not out.exists()


def test_compensate_previews_across_blocks(tmp_path, monkeypatch, capsys):
    data, u, y = lagged_record(tmp_path)
    model = TRUE.replace(delay=D)
    model_path = tmp_path / "m.json"
    model.save(model_path)
    monkeypatch.setattr(_records, "BLOCK_ROWS", 5)
    out = tmp_path / "c.csv"
    assert main(["compensate", str(model_path), str(data), "-o", str(out)]) == 0
    cols, _ = read_columns(out, ["time_s", "voltage_V", "displacement_um", "saturated"])
    ref = pihyst.compensate(model, y)
    np.testing.assert_array_equal(cols["time_s"], 1e-3 * np.arange(u.size))
    np.testing.assert_allclose(cols["voltage_V"], ref.voltage, rtol=0, atol=1e-12)
    np.testing.assert_allclose(cols["displacement_um"], ref.displacement, rtol=0, atol=1e-12)
    np.testing.assert_allclose(model.predict(cols["voltage_V"])[D:], y[D:], atol=1e-9)
    assert f"wrote {u.size} samples" in capsys.readouterr().out


def test_compensate_says_a_delayed_models_reach_as_the_undelayed_ones(tmp_path, capsys):
    desired = tmp_path / "far.csv"
    write_columns(desired, {"displacement_um": np.linspace(0, 120, 50)})   # past the top
    lines = {}
    for d in (0, D):
        model_path = tmp_path / f"m{d}.json"
        TRUE.replace(delay=d).save(model_path)
        assert main(["compensate", str(model_path), str(desired), "-o",
                     str(tmp_path / "c.csv"), "--saturate"]) == 0
        lines[d] = [line for line in capsys.readouterr().out.splitlines()
                    if "reach" in line]
    assert lines[D] == lines[0]
    assert lines[D][0].startswith("reachable displacement: [8.5, 81.5] µm")
    assert any("the trajectory spans 120 µm, more than the 73 µm the model reaches" in line
               for line in lines[D])


@pytest.mark.parametrize("mode", ["bottom", "top"])
def test_a_delayed_model_starts_at_rest_as_the_undelayed_one(tmp_path, mode):
    data, u, _ = lagged_record(tmp_path)
    model_path = tmp_path / "m.json"
    TRUE.replace(delay=D).save(model_path)
    out = tmp_path / "p.csv"
    assert main(["predict", str(model_path), str(data), "-o", str(out), "--initial-state",
                 mode]) == 0
    cols, _ = read_columns(out, ["displacement_um"])
    path = [0, 150, 0] if mode == "bottom" else [150, 0, 150]
    at_rest = TRUE.simulate(np.array(path, dtype=float),
                            initial_state=np.zeros(3)).final_state
    expected = TRUE.replace(delay=D).predict(u, initial_state=at_rest)
    np.testing.assert_allclose(cols["displacement_um"], expected, rtol=0, atol=1e-12)


def test_fit_many_takes_the_delay_option(tmp_path, capsys):
    folder = tmp_path / "records"
    folder.mkdir()
    data, _, _ = lagged_record(folder)
    models = tmp_path / "models"
    assert main(["fit-many", str(folder), "-o", str(models), "--model", "classical"]) == 0
    model = pihyst.load_model(models / "lagged.json")
    assert model.delay == D and model.sample_period == pytest.approx(1e-3)  # the record's
    assert main(["fit-many", str(folder), "-o", str(models), "--model", "classical",
                 "--delay", "0"]) == 0
    assert pihyst.load_model(models / "lagged.json").delay == 0
    assert main(["fit-many", str(folder), "-o", str(models), "--delay", "-1"]) == 2


# ------------------------------------------------------------------ delays too long to hold
def _delayed_file(tmp_path, **keys):
    d = TRUE.to_dict()
    d.update(keys)
    path = tmp_path / "m.json"
    path.write_text(json.dumps(d))
    return path


@pytest.mark.parametrize("value", [1e12, 10 ** 12, 1_000_001])
@pytest.mark.parametrize("command", ["predict", "compensate", "track", "validate", "export"])
def test_a_delay_too_long_to_hold_is_refused_naming_file_field_and_limit(tmp_path, capsys,
                                                                         command, value):
    model = _delayed_file(tmp_path, delay_samples=value)
    data, _, _ = lagged_record(tmp_path)
    out = tmp_path / "out.csv"
    argv = {"predict": ["predict", model, data, "-o", out],
            "compensate": ["compensate", model, data, "-o", out],
            "track": ["track", model, data, "-o", out],
            "validate": ["validate", model, data],
            "export": ["export", model, "--c", "-o", out]}[command]
    assert main([str(a) for a in argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert f"{model}: delay_samples = {value:.6g} is more than the 1,000,000 samples" in err
    assert not out.exists()


def test_a_delay_converted_to_too_many_samples_is_refused(tmp_path, capsys):
    # 3 samples at 1 s are 3e12 samples at 1 ps: refused before anything is allocated
    model = _delayed_file(tmp_path, delay_samples=3, sample_period_s=1.0)
    data = tmp_path / "fast.csv"
    write_columns(data, {"voltage_V": np.linspace(0, 100, 50)})
    out = tmp_path / "out.csv"
    for rate in ("1e12", "1e300"):
        assert main(["predict", str(model), str(data), "--rate", rate, "-o", str(out)]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and f"{data}: the model's delay of 3 samples at 1 s" in err
        assert "more than the 1,000,000 pihyst holds as an input delay" in err
        assert not out.exists()


def test_the_api_refuses_delays_too_long_to_hold():
    with pytest.raises(pihyst.InvalidModelError, match="delay = 2e\\+06 is more than"):
        TRUE.replace(delay=2_000_000)
    with pytest.raises(pihyst.InvalidModelError, match="m.json: delay_samples = 1e\\+12"):
        pihyst.PIModel.from_dict({**TRUE.to_dict(), "delay_samples": 1e12}, source="m.json")
    with pytest.raises(ResourceLimitError, match="3e\\+09 samples at 1e-09 s"):
        TRUE.replace(delay=3, sample_period=1.0).delay_at(1e-9)
    with pytest.raises(pihyst.FitError, match="delay = 2000000 is more than"):
        pihyst.fit(np.zeros(10), np.zeros(10), delay=2_000_000)
