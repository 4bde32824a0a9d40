"""Every page of docs/ is in its index: the table of docs/README.md (what GitHub shows)
and the toctree of docs/index.md (the built site; Sphinx also fails on a page left out)."""

import re
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parents[2] / "docs"
SITE_FILES = {"README.md", "index.md", "overview.md"}   # the index pages themselves


def _pages():
    return sorted(p.relative_to(DOCS).as_posix() for p in DOCS.rglob("*.md")
                  if not p.relative_to(DOCS).parts[0].startswith("_")
                  and p.relative_to(DOCS).parts[0] != "api")


@pytest.mark.skipif(not DOCS.exists(), reason="runs from a source checkout")
def test_docs_readme_lists_every_page():
    table = set(re.findall(r"^\| \[[^\]]+\]\(([^)#]+\.md)\)", (DOCS / "README.md").read_text(
        encoding="utf-8"), flags=re.M))
    missing = [p for p in _pages() if p not in SITE_FILES and p not in table]
    assert not missing, f"docs/README.md's table does not list {missing}"


@pytest.mark.skipif(not DOCS.exists(), reason="runs from a source checkout")
def test_site_index_lists_every_page():
    text = (DOCS / "index.md").read_text(encoding="utf-8")
    entries = set(re.findall(r"^([\w/.-]+)$", text, flags=re.M))
    missing = [p for p in _pages() if p != "index.md" and p[:-3] not in entries]
    assert not missing, f"docs/index.md's toctree does not list {missing}"
