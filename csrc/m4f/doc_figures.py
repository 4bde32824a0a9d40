"""The figures of docs/c-core.md that come from the build, regenerated or checked.

    python3 m4f/doc_figures.py write   # rewrite the generated tables in docs/c-core.md
    python3 m4f/doc_figures.py check   # exit 1 if the doc differs from what the build gives

(`make -C csrc doc` and `make -C csrc check-doc`, run from csrc/.) Three tables, each
between the markers <!-- figures:NAME --> and <!-- /figures:NAME -->:

  configurations  the compiler flags of every build `make test` and `make test-m4f` run,
                  read from the commands make would run (make -n -B), not typed in;
  m4f-sizes       code, data and bss of each single-precision core file for the
                  Cortex-M4F (`make m4f`, arm-none-eabi-size);
  bench-m4f       instructions per sample of every model kind on the emulated M4F
                  (tests/m4f/bench.out, written by `make bench-m4f`) with the highest
                  sample rate each fits at 168 MHz with half the CPU left for the rest of
                  the firmware, counting one cycle per instruction;
  m4f-targets     the same figures against the targets of issue 23 (a classical K = 16
                  compensator in 600 instructions per tracking sample, every path of
                  the default fit's models in 8,000).
"""

import re
import subprocess
import sys
from pathlib import Path

CSRC = Path(__file__).resolve().parents[1]
DOC = CSRC.parent / "docs" / "c-core.md"
BENCH_OUT = CSRC / "tests" / "m4f" / "bench.out"
MODELS_TXT = CSRC / "tests" / "m4f" / "gen" / "models.txt"
CLOCK_HZ = 168e6
SHARE = 0.5

# (what the doc calls it, make target, the command's output file)
CONFIGURATIONS = [
    ("double precision (`make test`)", "tests/run_tests"),
    ("single precision", "tests/run_tests_f32"),
    ("double, no aligned copy, portable loops", "tests/run_tests_unaligned"),
    ("single, firmware configuration (PIHYST_STATE_ALIGN=0, -O2)", "tests/run_tests_f32_firmware"),
    ("the firmware example", "tests/example"),
    ("Cortex-M4F core objects (`make m4f`, `test-m4f`)", "tests/m4f/obj/pihyst_model_f32.o"),
    ("Cortex-M4F test suite (`make test-m4f`)", "tests/m4f/obj/f32_test_main.o"),
    ("host twin of the target runs (`make test-m4f`)", "tests/m4f/host_run_tests_f32"),
    ("shared library (`make shared`)", "libpihyst.so"),
    ("Windows DLL (`make dll`, MinGW-w64)", "pihyst.dll"),
]


def make(*args):
    return subprocess.run(["make", "-s", "-C", str(CSRC), *args], check=True,
                          capture_output=True, text=True).stdout


def flags_of(target):
    """The options of the command that builds target (make -n -B), file names dropped."""
    out = make("-n", "-B", target)
    for line in out.replace("\\\n", " ").splitlines():
        words = line.split()
        if "-o" in words and words[words.index("-o") + 1] == target:
            compiler = words[0]
            opts = [w for w in words[1:] if w.startswith("-") and w != "-o"
                    and not w.startswith("-I") and not w.startswith("-Wl,")]
            return compiler, " ".join(opts)
    raise SystemExit(f"doc_figures: no command builds {target}")


def configurations():
    rows = ["| build | compiler | flags |", "| --- | --- | --- |"]
    for name, target in CONFIGURATIONS:
        compiler, opts = flags_of(target)
        rows.append(f"| {name} | `{compiler}` | `{opts}` |")
    return rows


def m4f_sizes():
    out = make("m4f")
    rows = ["| file (Cortex-M4F, `-O2`) | code + constants | data | bss |",
            "| --- | ---: | ---: | ---: |"]
    total = 0
    for line in out.splitlines():
        m = re.match(r"\s*(\d+)\s+(\d+)\s+(\d+)\s+\d+\s+[0-9a-f]+\s+tests/obj/m4f_(\w+)\.o", line)
        if m:
            text, data, bss, name = int(m[1]), int(m[2]), int(m[3]), m[4]
            total += text
            rows.append(f"| `pihyst_{name}.c` | {text / 1000:.1f} kB | {data} B | {bss} B |")
    if len(rows) == 2:
        raise SystemExit("doc_figures: make m4f printed no sizes")
    rows.append(f"| all {len(rows) - 2} | {total / 1000:.1f} kB | | |")
    return rows


def rate_text(hz):
    if hz >= 1e6:
        return f"{hz / 1e6:.1f} MHz"
    if hz >= 1e4:
        return f"{hz / 1e3:.0f} kHz"
    if hz >= 1e3:
        return f"{hz / 1e3:.1f} kHz"
    return f"{hz:.0f} Hz"


def bench_figures():
    if not BENCH_OUT.exists():
        raise SystemExit(f"doc_figures: {BENCH_OUT} missing: run make -C csrc bench-m4f first")
    figures = {}
    for line in BENCH_OUT.read_text().splitlines():
        m = re.match(r"m4f: (\S+) (\S+) (\d+) instructions/sample$", line)
        if m:
            figures.setdefault(m[1], {})[m[2]] = int(m[3])
    return figures


# item 4 of issue 23: a classical K = 16 compensator in at most 600 instructions per
# tracking sample; no path of a model the default fit produces above 8,000
def m4f_targets():
    figures = bench_figures()
    rows = ["| model | path | instructions/sample | target | |", "| --- | --- | ---: | ---: | --- |"]

    def row(name, path, n, target):
        rows.append(f"| {name} | {path} | {n:,} | ≤ {target:,} | "
                    f"{'met' if n <= target else '**above**'} |")

    row("classical-K16", "compensator-tracking", figures["classical-K16"]["compensator-tracking"], 600)
    for name, by_path in figures.items():
        if name.startswith("kp-"):
            for path, n in by_path.items():
                row(name, path, n, 8000)
    return rows


def bench_m4f():
    figures = bench_figures()
    paths = ["model-tracking", "model-worst", "compensator-tracking", "compensator-worst"]
    rows = ["| model | model step, tracking | model step, worst | compensator, tracking "
            "| compensator, worst |", "| --- | ---: | ---: | ---: | ---: |"]

    def cell(n):
        return "" if n is None else f"{n:,} ({rate_text(SHARE * CLOCK_HZ / n)})"

    for name, by_path in figures.items():
        if not any(p in by_path for p in paths):
            continue
        rows.append(f"| {name} | " + " | ".join(cell(by_path.get(p)) for p in paths) + " |")
    extra = [f"| {name} | " + ", ".join(f"{p} {n:,}" for p, n in by_path.items()) + " | | | |"
             for name, by_path in figures.items() if not any(p in by_path for p in paths)]
    rows.extend(extra)
    if MODELS_TXT.exists():
        rows.append("")
        rows.append("The default fit's models in this run (`csrc/m4f/models.sh`): " + "; ".join(
            line.strip() for line in MODELS_TXT.read_text().splitlines() if line.strip()) + ".")
    return rows


TABLES = {"configurations": configurations, "m4f-sizes": m4f_sizes, "bench-m4f": bench_m4f,
          "m4f-targets": m4f_targets}


def render(text, names):
    for name in names:
        begin, end = f"<!-- figures:{name} -->", f"<!-- /figures:{name} -->"
        pattern = re.compile(re.escape(begin) + r"\n.*?" + re.escape(end), re.S)
        if not pattern.search(text):
            raise SystemExit(f"doc_figures: {DOC.name} has no {begin} ... {end}")
        body = "\n".join(TABLES[name]())
        text = pattern.sub(lambda _: f"{begin}\n{body}\n{end}", text)
    return text


# The bench tables' counts may move by this fraction before the doc counts as stale: a
# change of the default fit or of the core moves them by a few instructions (and the
# counter's tick is 40 instructions), a change worth rewriting the doc by much more.
# Everything else (flags, sizes, words) must match exactly.
BENCH_TOLERANCE = 0.10
NUMBER = re.compile(r"\d[\d,]*(?:\.\d+)?")


def _same(old, new):
    """Whether the doc's tables equal the build's: exactly, but for the bench tables'
    numbers, which may differ by BENCH_TOLERANCE."""
    if old == new:
        return True
    for name in ("bench-m4f", "m4f-targets"):
        begin, end = f"<!-- figures:{name} -->", f"<!-- /figures:{name} -->"
        a, b = (t[t.index(begin):t.index(end)] for t in (old, new))
        if NUMBER.sub("#", a) != NUMBER.sub("#", b):
            return False
        for x, y in zip(NUMBER.findall(a), NUMBER.findall(b)):
            x, y = float(x.replace(",", "")), float(y.replace(",", ""))
            if abs(x - y) > BENCH_TOLERANCE * max(abs(x), abs(y)):
                return False
        old, new = old.replace(a, ""), new.replace(b, "")
    return old == new


def main(argv):
    if len(argv) < 2 or argv[1] not in ("write", "check"):
        raise SystemExit(__doc__)
    names = argv[2:] or list(TABLES)
    old = DOC.read_text(encoding="utf-8")
    new = render(old, names)
    if argv[1] == "write":
        DOC.write_text(new, encoding="utf-8")
        print(f"doc_figures: {DOC.name}: {', '.join(names)} written")
        return 0
    if not _same(old, new):
        import difflib
        sys.stdout.writelines(difflib.unified_diff(old.splitlines(True), new.splitlines(True),
                                                   "docs/c-core.md", "from the build"))
        print("doc_figures: docs/c-core.md differs from the build: make -C csrc doc")
        return 1
    print(f"doc_figures: docs/c-core.md matches the build ({', '.join(names)})")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
