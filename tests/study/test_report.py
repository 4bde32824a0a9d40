"""The report folder (pihyst.study) and the commands demo and report."""

import base64
import json
import os
import re
import stat

import numpy as np
import pytest

from pihyst import paper
from pihyst.cli import main
from pihyst.io import load_model, read_columns

PNG = b"\x89PNG\r\n\x1a\n"


def test_every_promised_file_is_written(demo):
    study, out, files, lines = demo
    names = set(os.listdir(out))
    assert names == set(files)
    expected = {"report.html", "metrics.json", "loop.csv", "identification.csv",
                "validation.csv", "tracking_triangle.csv", "tracking_reversals.csv",
                "model_classical.json", "model_multislope.json", "model_best.json",
                # numbered as the paper's figures they reproduce; pihyst's own A1, A2, ...
                "fig7_loop.png", "fig8_fit_errors.png", "fig4_classical_operators.png",
                "fig5_multislope_operators.png", "figA1_validation.png", "fig11_voltages.png",
                "fig12_tracking.png", "figA2_tracking_reversals.png", "figA3_variants.png",
                "figA4_beams.png"}
    # each CSV's description in its sidecar (the CSV itself is plain)
    expected |= {f"{n}.json" for n in expected if n.endswith(".csv")
                 and f"{n}.json" in names}
    assert {"loop.csv.json", "tracking_triangle.csv.json"} <= names
    assert names == expected
    assert not [n for n in names if n.startswith(".pihyst-")]
    assert lines == ["drawing the figures ...", "writing data, models and metrics ..."]


def test_figures_reproducing_the_papers_carry_its_numbers(demo):
    _, out, files, _ = demo
    text = (out / "report.html").read_text(encoding="utf-8")
    titles = re.findall(r"<figcaption><b>(Figure [^<]*)</b>", text)
    assert len(titles) == len([n for n in files if n.endswith(".png")])
    for title in titles:
        number = re.match(r"Figure (\w+)\. ", title).group(1)
        reproduced = re.search(r"the paper's Fig\. (\d+), reproduced", title)
        if reproduced:
            assert number == reproduced.group(1), title
        else:
            assert number.startswith("A") and "not in the paper" in title, title
    assert len(set(titles)) == len(titles)


def test_pngs_are_images_readable_by_others(demo):
    _, out, files, _ = demo
    for name in files:
        if name.endswith(".png"):
            data = (out / name).read_bytes()
            assert data.startswith(PNG) and len(data) > 5000, name
            mode = stat.S_IMODE(os.stat(out / name).st_mode)
            assert mode & stat.S_IRUSR


def test_html_is_self_contained_and_embeds_every_figure(demo):
    _, out, files, _ = demo
    text = (out / "report.html").read_text(encoding="utf-8")
    sources = re.findall(r'<img src="([^"]+)"', text)
    pngs = sorted(n for n in files if n.endswith(".png"))
    assert len(sources) == len(pngs)
    for src in sources:
        assert src.startswith("data:image/png;base64,")
        assert base64.b64decode(src.split(",", 1)[1]).startswith(PNG)
    embedded = {base64.b64decode(s.split(",", 1)[1]) for s in sources}
    assert embedded == {(out / n).read_bytes() for n in pngs}
    # nothing is fetched from elsewhere
    assert not re.search(r'(src|href)="(?!data:|#)', text)
    assert "<script" not in text


def test_html_shows_every_metric_beside_the_papers(demo):
    study, out, _, _ = demo
    text = (out / "report.html").read_text(encoding="utf-8")
    numbers = [paper.FIT_MEAN_ABS_CLASSICAL_UM, paper.FIT_MEAN_ABS_MULTISLOPE_UM,
               paper.FIT_IMPROVEMENT_PCT, paper.TRACKING_MEAN_ABS_UM,
               *paper.TABLE1_CLASSICAL_WEIGHTS, *paper.TABLE1_MULTISLOPE_WEIGHTS]
    for number in numbers:
        assert f"{number:g}" in text, number
    assert f"{paper.TRACKING_RMS_UM:.4f}" in text
    assert " / ".join(f"{v:+.3g} µm" for v in paper.FIT_EXTREMES_CLASSICAL_UM.values()) in text
    m = study.metrics
    assert f'{m["fit"]["multislope"]["mean_abs"]:.4g}' in text
    assert f'{m["tracking"]["triangle"]["errors"]["multislope"]["mean_abs"]:.4g}' in text
    assert "never moves: left out" in text
    for fig in ("4", "5", "7", "8", "11", "12"):
        assert f"Figure {fig}. " in text and f"(the paper's Fig. {fig}, reproduced)" in text
    # pihyst's own figures numbered A1, A2, ... in the order of the page
    added = [n for n in re.findall(r"<figcaption><b>Figure (A\d+)\.", text)]
    assert added == [f"A{k}" for k in range(1, 5)]
    assert " um" not in text.split("<details>")[0]


def test_metrics_json_is_the_studys(demo):
    study, out, _, _ = demo
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["headline"] == pytest.approx(study.metrics["headline"])
    assert metrics["paper"]["fit"]["improvement_pct"] == 78.6
    assert set(metrics["fit"]) == {"classical", "multislope", "best"}


def test_csv_and_models_reproduce_the_study(demo):
    study, out, _, _ = demo
    cols, _ = read_columns(out / "loop.csv", ["time_s", "voltage_V", "displacement_um",
                                              "multislope_um"])
    np.testing.assert_array_equal(cols["voltage_V"], study.loop.u)
    np.testing.assert_array_equal(cols["displacement_um"], study.loop.y)
    for key in ("classical", "multislope", "best"):
        model = load_model(out / f"model_{key}.json")
        np.testing.assert_allclose(model.predict(cols["voltage_V"]),
                                   study.predictions["loop"][key], atol=1e-9)
    tr, _ = read_columns(out / "tracking_triangle.csv",
                         ["time_s", "desired_um", "voltage_V_multislope",
                          "displacement_um_multislope", "voltage_V_none"])
    np.testing.assert_array_equal(tr["voltage_V_multislope"],
                                  study.tracking["triangle"]["voltage"]["multislope"])


def test_report_command_on_a_simulated_record(tmp_path, capsys):
    data = tmp_path / "loop.csv"
    assert main(["simulate", "--plant", "s-shaped", "--signal", "decaying-triangles",
                 "--dt", "1", "-o", str(data)]) == 0
    out = tmp_path / "rep"
    assert main(["report", str(data), "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "pihyst report: [1/3]" in printed and "report.html" in printed
    names = set(os.listdir(out))
    assert {"report.html", "metrics.json", "record.csv", "fig1_loop.png",
            "fig2_fit_errors.png", "model_best.json"} <= names
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["mode"] == "report" and metrics["threshold_scale"] == 1.0
    text = (out / "report.html").read_text(encoding="utf-8")
    # the user's study: no paper columns unless asked for
    assert "paper's beam" not in text and "Fig. 7" not in text and "Fig. 11" not in text
    assert "Figure 1. Measured loop and fitted models" in text
    assert main(["report", str(data), "--out", str(out), "--paper", "--figure-format", "svg",
                 "--figure-format", "pdf"]) == 0
    text = (out / "report.html").read_text(encoding="utf-8")
    assert "paper's beam" in text
    assert "Figure 7. Measured loop and fitted models (the paper's Fig. 7, reproduced)" in text
    assert (out / "fig7_loop.svg").read_text().lstrip().startswith("<?xml")
    assert (out / "fig8_fit_errors.pdf").read_bytes().startswith(b"%PDF")


def test_report_default_folder_is_next_to_the_data(tmp_path):
    data = tmp_path / "run1.csv"
    assert main(["simulate", "--dt", "2", "-o", str(data)]) == 0
    assert main(["report", str(data)]) == 0
    assert (tmp_path / "run1-report" / "report.html").exists()


@pytest.mark.parametrize("content, message", [
    ("voltage_V,displacement_um\n1,2\n1,3\n1,4\n", "voltage_V is constant"),
    ("voltage_V\n1\n2\n", "missing column 'displacement_um'"),
    ("voltage_V,displacement_um\n1,x\n", "is not a number"),
])
def test_report_command_bad_data(tmp_path, capsys, content, message):
    data = tmp_path / "bad.csv"
    data.write_text(content)
    out = tmp_path / "rep"
    assert main(["report", str(data), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1 and str(data) in err
    assert not out.exists()


def test_out_must_be_a_folder(tmp_path, capsys):
    data = tmp_path / "loop.csv"
    main(["simulate", "--dt", "2", "-o", str(data)])
    assert main(["report", str(data), "--out", str(data)]) == 2
    assert "exists and is not a folder" in capsys.readouterr().err


@pytest.mark.slow
def test_demo_command_is_the_papers_study(tmp_path, capsys):
    """The README's main-job command, end to end: under two minutes, progress shown,
    multislope beats the conventional PI as the paper says."""
    out = tmp_path / "demo"
    assert main(["demo", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "[1/9]" in printed and "[9/9]" in printed and "report.html" in printed
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["timing_s"]["total_computation"] < 120
    h = metrics["headline"]
    assert h["fit_improvement_pct"] > 60
    assert h["tracking_mean_abs_pct_of_range"] < 1.0
    assert len([n for n in os.listdir(out) if n.endswith(".png")]) == 11   # Fig. 17: the rig
    assert metrics["rig"]["tracking"]["feedback"]["mean_abs"] < \
        metrics["rig"]["tracking"]["open_loop"]["mean_abs"]


def test_report_shows_a_learning_run(tmp_path, capsys):
    """--learning: the error per trial and the tracking before and after, as figures, a
    table and metrics; a file that is not a learning run is a one-line error."""
    data, run = tmp_path / "loop.csv", tmp_path / "run.csv"
    assert main(["simulate", "--dt", "5", "-o", str(data)]) == 0
    assert main(["learn", "--scan", "500", "--mode", "2000,0.05", "--trials", "3",
                 "-o", str(run)]) == 0
    out = tmp_path / "rep"
    assert main(["report", str(data), "--out", str(out), "--learning", str(run)]) == 0
    text = (out / "report.html").read_text(encoding="utf-8")
    assert "<h2>Learning feedforward</h2>" in text and "Learning curve" in text
    names = set(os.listdir(out))
    assert any(n.endswith("_learning_curve.png") for n in names)
    assert any(n.endswith("_learning_tracking.png") for n in names)
    metrics = json.loads((out / "metrics.json").read_text())
    learning = metrics["learning"]
    assert learning["trials"] == 4 and len(learning["rms_um"]) == 4     # trial 0 and 3
    assert learning["rms_um"][learning["best_trial"]] == min(learning["rms_um"])
    capsys.readouterr()
    assert main(["report", str(data), "--out", str(out), "--learning", str(data)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "loop.csv" in err[0]
