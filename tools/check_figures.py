"""Check every figure that README.md and docs/ quote against the code that produces it.

docs/figures.toml lists the quoted figures: for each, the file, a quote (the text around
the numbers, with a ``{name}`` placeholder where each number stands) and the source
that produces the numbers (tools/figure_sources.py). A figure is true when the quoted
number equals the value the current code produces within the entry's tolerance (by
default half a unit of the last digit quoted: the value, rounded as printed).

    python tools/check_figures.py              # the quick sources
    python tools/check_figures.py --all        # also the slow ones (the demo, measured sets)
                                               # and the script-only ones (minutes each)
    python tools/check_figures.py --all --demo-metrics out/demo/metrics.json
    python tools/check_figures.py --coverage   # figures in the text that no entry covers

Exit status 0 when every checked figure is true, 1 when one is not (one line each:
file:line, the quoted number, the value now), 2 on a bad registry.
"""

import argparse
import math
import re
import sys
from dataclasses import dataclass, field
from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:          # Python 3.10: the same parser, as a package
    import tomli as tomllib

REPO = Path(__file__).resolve().parents[1]
REGISTRY = REPO / "docs" / "figures.toml"

# a quoted number: sign (ASCII or the minus sign), digits, decimals, an exponent as
# "10⁻¹³" is not one number and is not used in quotes
NUMBER = r"[-−]?\d+(?:\.\d+)?"
_PLACEHOLDER = re.compile(r"\{([A-Za-z_][\w.\[\]-]*)\}")


class RegistryError(Exception):
    """docs/figures.toml is malformed: an unknown source, a quote without placeholder."""


@dataclass
class Entry:
    """One quote of docs/figures.toml."""
    file: str
    quote: str
    source: str
    tolerance: dict = field(default_factory=dict)   # placeholder -> absolute tolerance
    rtol: float = 0.0                               # relative tolerance, every placeholder
    note: str = ""

    def pattern(self):
        """The quote as a regular expression: literal text, any run of whitespace for a
        space (Markdown wraps lines anywhere), a number for each placeholder."""
        parts, names, pos = [], [], 0
        for m in _PLACEHOLDER.finditer(self.quote):
            parts.append(_literal(self.quote[pos:m.start()]))
            parts.append(f"({NUMBER})")
            names.append(m.group(1))
            pos = m.end()
        parts.append(_literal(self.quote[pos:]))
        if not names:
            raise RegistryError(f"quote without a {{placeholder}}: {self.quote!r}")
        return re.compile("".join(parts)), names


def _literal(text):
    return r"\s+".join(re.escape(word) for word in re.split(r"\s+", text)) \
        if text.strip() else (r"\s+" if text else "")


@dataclass
class Mismatch:
    where: str
    message: str

    def __str__(self):
        return f"{self.where}: {self.message}"


def load_registry(path=REGISTRY):
    with open(path, "rb") as f:
        data = tomllib.load(f)
    entries = []
    for i, raw in enumerate(data.get("figure", [])):
        unknown = set(raw) - {"file", "quote", "source", "tolerance", "rtol", "note"}
        if unknown or not {"file", "quote", "source"} <= set(raw):
            raise RegistryError(f"{path.name}: figure {i + 1}: needs file, quote, source "
                                f"(unknown keys: {sorted(unknown)})")
        entries.append(Entry(**raw))
    return entries


def default_tolerance(quoted):
    """Half a unit of the last digit quoted: 82.6 -> 0.05, 134 -> 0.5."""
    decimals = len(quoted.split(".")[1]) if "." in quoted else 0
    return 0.5 * 10.0 ** -decimals


def lookup(values, name):
    """``values["a"]["b"][0]`` for the placeholder name ``a.b[0]``."""
    out = values
    for part in re.findall(r"[^.\[\]]+|\[\d+\]", name):
        out = out[int(part[1:-1])] if part.startswith("[") else out[part]
    return out


def find_quote(entry, text):
    """The matches of the entry's quote in ``text`` (none when the text changed)."""
    return list(entry.pattern()[0].finditer(text))


def check_entry(entry, values, text, line_of):
    """The mismatches of one entry against its source's ``values`` (a list, empty when
    every quoted number is true)."""
    pattern, names = entry.pattern()
    matches = list(pattern.finditer(text))
    if not matches:
        return [Mismatch(entry.file, f"quote not found (the text changed?): {entry.quote!r}")]
    problems = []
    for m in matches:
        where = f"{entry.file}:{line_of(m.start())}"
        for k, name in enumerate(names):
            quoted = m.group(k + 1).replace("−", "-")
            try:
                value = float(lookup(values, name))
            except (KeyError, IndexError, TypeError) as err:
                problems.append(Mismatch(where, f"source {entry.source!r} has no {name!r} "
                                                f"({type(err).__name__}: {err})"))
                continue
            tol = entry.tolerance.get(name, default_tolerance(quoted))
            tol = max(tol, entry.rtol * abs(value))
            if not math.isfinite(value) or abs(value - float(quoted)) > tol + 1e-12:
                problems.append(Mismatch(where, f"quotes {quoted} for {entry.source}:{name}, "
                                                f"which is {value:.6g} now (tolerance "
                                                f"{tol:.3g})"))
    return problems


def check(entries, *, slow=False, script=False, options=None):
    """Check ``entries`` whose source is quick (slow ones too when ``slow``, and those
    that only the script runs, taking minutes, when ``script`` as well); returns (number
    of figures checked, mismatches, {source skipped: why})."""
    from figure_sources import SOURCES  # tools/ on sys.path (main() puts it there)

    options = options or {}
    texts, checked, problems, skipped, cache = {}, 0, [], {}, {}
    for entry in entries:
        if entry.source not in SOURCES:
            raise RegistryError(f"unknown source {entry.source!r} (tools/figure_sources.py "
                                f"has {', '.join(sorted(SOURCES))})")
        src = SOURCES[entry.source]
        if src.slow and not slow and not src.available_from(options):
            skipped[entry.source] = "slow (--all)"
            continue
        if src.script and not script:
            skipped[entry.source] = "script only (--all)"
            continue
        if entry.source in skipped:
            continue
        if entry.source not in cache:
            try:
                cache[entry.source] = src.values(options)
            except LookupError as err:          # what it needs is not here (the data sets)
                skipped[entry.source] = str(err)
                continue
        if entry.file not in texts:
            texts[entry.file] = (REPO / entry.file).read_text(encoding="utf-8")
        text = texts[entry.file]

        def line_of(offset, text=text):
            return text.count("\n", 0, offset) + 1

        problems += check_entry(entry, cache[entry.source], text, line_of)
        checked += len(entry.pattern()[1])
    return checked, problems, skipped


# --------------------------------------------------------------------------- coverage
_FIGURE = re.compile(r"(?<![\w.])\d+(?:\.\d+)?(?=\s?(?:µm|%|ms|µs|ns|s\b|×|Hz|MB|V\b))")


def coverage(entries, files):
    """Per file: figures with a unit in the text, and how many of them the registry's
    quotes cover (code blocks included)."""
    rows = []
    for name in files:
        text = (REPO / name).read_text(encoding="utf-8")
        spans = []
        for entry in (e for e in entries if e.file == name):
            spans += [m.span() for m in entry.pattern()[0].finditer(text)]
        found = [m.start() for m in _FIGURE.finditer(text)]
        covered = sum(any(a <= pos < b for a, b in spans) for pos in found)
        rows.append((name, len(found), covered))
    return rows


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--all", action="store_true", help="also the slow sources")
    p.add_argument("--demo-metrics", metavar="JSON",
                   help="the demo's figures from this metrics.json (pihyst demo --out DIR "
                        "writes DIR/metrics.json) instead of running the study")
    p.add_argument("--coverage", action="store_true",
                   help="count the figures in README.md and docs/ that no entry covers")
    args = p.parse_args(argv)
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    try:
        entries = load_registry()
        if args.coverage:
            files = ["README.md"] + sorted(str(f.relative_to(REPO))
                                           for f in (REPO / "docs").rglob("*.md"))
            total = cov = 0
            for name, n, c in coverage(entries, files):
                total, cov = total + n, cov + c
                print(f"{name:<36} {c:>4} of {n:>4} figures with a unit covered")
            print(f"{'all':<36} {cov:>4} of {total:>4}")
            return 0
        options = {"demo_metrics": args.demo_metrics}
        n, problems, skipped = check(entries, slow=args.all, script=args.all, options=options)
    except RegistryError as err:
        print(f"check_figures: error: {err}", file=sys.stderr)
        return 2
    for problem in problems:
        print(problem)
    print(f"check_figures: {n} figures checked, {len(problems)} not true"
          + "".join(f"; {name} skipped: {why}" for name, why in sorted(skipped.items())))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
