"""Every figure README.md and docs/ quote is what the current code produces: the
registry docs/figures.toml names, for each quoted number, the source that computes it
(tools/figure_sources.py), and tools/check_figures.py compares. The quick sources run
here; the slow ones (the demo's study) in the slow suite."""

import importlib
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
TOOLS = REPO / "tools"
pytestmark = pytest.mark.skipif(not (TOOLS / "check_figures.py").exists(),
                                reason="runs from a source checkout (tools/)")


@pytest.fixture(scope="module")
def checker():
    sys.path.insert(0, str(TOOLS))
    try:
        yield importlib.import_module("check_figures")
    finally:
        sys.path.remove(str(TOOLS))


@pytest.fixture(scope="module")
def entries(checker):
    return checker.load_registry()


def test_every_quote_of_the_registry_is_in_its_file(checker, entries):
    from figure_sources import SOURCES
    missing = []
    for e in entries:
        assert e.source in SOURCES, f"unknown source {e.source!r}"
        text = (REPO / e.file).read_text(encoding="utf-8")
        if not checker.find_quote(e, text):
            missing.append(f"{e.file}: {e.quote!r}")
    assert not missing, "quotes no longer in the text (update docs/figures.toml):\n" + \
        "\n".join(missing)


def test_the_quick_figures_are_true(checker, entries):
    n, problems, skipped = checker.check(entries, slow=False)
    assert n > 0
    assert not problems, "\n".join(map(str, problems))
    from figure_sources import SOURCES

    from pihyst.io import datasets
    slow = {name for name, src in SOURCES.items() if src.slow}
    data = {name for name, src in SOURCES.items() if src.data}
    assert set(skipped) <= slow | (data if datasets.data_root() is None else set())


@pytest.mark.slow
def test_the_slow_figures_are_true(checker, entries):
    n, problems, skipped = checker.check(entries, slow=True)
    # only what needs the measured data sets may be left out, and only without them
    from figure_sources import SOURCES

    from pihyst.io import datasets
    data = {name for name, src in SOURCES.items() if src.data}
    script = {name for name, src in SOURCES.items() if src.script}
    assert set(skipped) - script <= (data if datasets.data_root() is None else set())
    assert not problems, "\n".join(map(str, problems))


# ------------------------------------------------------------------ the checker itself
def _entry(checker, quote, **kw):
    return checker.Entry(file="X.md", quote=quote, source="s", **kw)


@pytest.mark.parametrize("quoted, tol", [("82.6", 0.05), ("134", 0.5), ("0.2828", 5e-5),
                                         ("-3.09", 0.005)])
def test_default_tolerance_is_half_the_last_digit(checker, quoted, tol):
    assert checker.default_tolerance(quoted) == pytest.approx(tol)


def test_a_figure_within_the_rounding_is_true_and_one_beyond_is_not(checker):
    e = _entry(checker, "fits with {a.b} % less error")
    text = "the multislope PI fits with\n82.6 % less error"
    line = lambda offset: 1  # noqa: E731
    assert checker.check_entry(e, {"a": {"b": 82.64}}, text, line) == []
    wrong = checker.check_entry(e, {"a": {"b": 82.66}}, text, line)
    assert len(wrong) == 1 and "quotes 82.6" in str(wrong[0]) and "82.66" in str(wrong[0])


def test_a_stated_tolerance_widens_one_figure(checker):
    e = _entry(checker, "{x} µm and {y} µm", tolerance={"x": 0.1})
    line = lambda offset: 1  # noqa: E731
    problems = checker.check_entry(e, {"x": 1.08, "y": 2.08}, "1.0 µm and 2.0 µm", line)
    assert [str(p) for p in problems] == [
        "X.md:1: quotes 2.0 for s:y, which is 2.08 now (tolerance 0.05)"]


def test_a_changed_text_or_a_missing_value_fails(checker):
    line = lambda offset: 1  # noqa: E731
    gone = checker.check_entry(_entry(checker, "peak {p} µm"), {"p": 1}, "top 1 µm", line)
    assert len(gone) == 1 and "quote not found" in str(gone[0])
    nokey = checker.check_entry(_entry(checker, "peak {p} µm"), {}, "peak 1 µm", line)
    assert len(nokey) == 1 and "has no 'p'" in str(nokey[0])


def test_negative_numbers_with_the_minus_sign(checker):
    e = _entry(checker, "error {e} µm")
    line = lambda offset: 1  # noqa: E731
    assert checker.check_entry(e, {"e": -3.09}, "error −3.09 µm", line) == []


def test_every_occurrence_is_checked(checker):
    e = _entry(checker, "peak {p} µm")
    line = lambda offset: offset  # noqa: E731
    problems = checker.check_entry(e, {"p": 41.38}, "peak 41.38 µm; later peak 41.3 µm", line)
    assert len(problems) == 1 and "quotes 41.3 " in str(problems[0])


def test_script_only_sources_run_only_when_asked(checker, monkeypatch):
    import figure_sources

    calls = []

    def compute(options):
        calls.append(options)
        return {"x": 78.6}

    monkeypatch.setitem(figure_sources.SOURCES, "fake", figure_sources.Source(
        "fake", compute, slow=True, doc="", data=False, script=True))
    e = checker.Entry(file="README.md", quote="(paper: {x} %), and its inverse", source="fake")
    n, problems, skipped = checker.check([e], slow=True)
    assert (n, problems, calls) == (0, [], []) and skipped == {"fake": "script only (--all)"}
    n, problems, skipped = checker.check([e], slow=True, script=True)
    assert (n, problems, skipped, len(calls)) == (1, [], {}, 1)
