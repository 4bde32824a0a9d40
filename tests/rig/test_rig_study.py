"""The demo's experiment through the emulated instruments."""

import pytest

from pihyst.rig import read_run_log
from pihyst.study._rig_study import rig_figure, rig_html, rig_study


def test_rig_study(tmp_path):
    s = rig_study(period_s=30.0, realtime_s=0.5)
    assert all(r.completed for r in s.results.values())
    assert s.model.thresholds.tolist() == [0.0, 20.0, 30.0, 40.0]
    assert s.tracking["feedback"]["mean_abs"] < 0.5 * s.tracking["open_loop"]["mean_abs"]
    assert s.timing["record"]["overruns"] == 0 and s.timing["record"]["ticks"] == 301
    assert s.realtime["ticks"] >= 5
    names = s.write_logs(tmp_path)
    columns, notes = read_run_log(tmp_path / names[0])
    assert columns["tick"].size == 301
    html = rig_html(s, "<figure></figure>")
    assert "Loop timing" in html and "with feedback" in html
    rig_figure(s)


@pytest.mark.slow
def test_demo_with_the_rig(tmp_path):
    from pihyst.study import paper_study, write_report
    study = paper_study(dt=2.0, variants=False, rig=True, progress=None)
    files = write_report(study, tmp_path, command="test")
    assert {"fig17_rig_tracking.png", "rig_record.csv", "rig_feedback.csv"} <= set(files)
    assert "rig" in study.metrics and "Loop timing" in (tmp_path / "report.html").read_text()
