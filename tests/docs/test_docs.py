"""The documentation holds together: docs/CLI.md is what the commands print, every link of
the README and of docs/ leads to a page and a heading that exist, every page is reachable
from the README, and nothing cites a file outside the repository."""

from __future__ import annotations

import importlib.util
import re
from collections import Counter
from pathlib import Path

import pytest

from tests.helpers.paths import ROOT

DOCS = ROOT / "docs"
#: Every Markdown page of the project (the README and docs/), by its path from the root.
PAGES = [ROOT / "README.md", *sorted(DOCS.glob("*.md"))]
README_TEXT = (ROOT / "README.md").read_text()


def load_cli_reference_script():
    """docs/make_cli_reference.py as a module (docs/ is no package)."""
    spec = importlib.util.spec_from_file_location("make_cli_reference",
                                                  DOCS / "make_cli_reference.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_cli_reference_is_what_the_commands_print():
    """Regenerate docs/CLI.md in memory: it differs when a command's help changed and the
    page was not regenerated (``python docs/make_cli_reference.py``)."""
    script = load_cli_reference_script()
    text = script.reference()
    assert (DOCS / "CLI.md").read_text() == text, "run: python docs/make_cli_reference.py"
    for path in script.command_paths():
        assert f"## `{' '.join(['gsrwt', *path])}`" in text
    assert "Usage: gsrwt rectify [OPTIONS] INPUT..." in text


def without_code(text: str) -> str:
    """The page with its fenced code blocks and inline code spans emptied (a ``#`` comment in
    a block is no heading, ``[0](1)`` in code is no link)."""
    text = re.sub(r"^```.*?^```", "", text, flags=re.S | re.M)
    return re.sub(r"`[^`\n]*`", "", text)


def anchors(page: Path) -> set[str]:
    """The anchors GitHub gives the page's headings: lower case, punctuation other than ``-``
    and ``_`` dropped, spaces as ``-``, a repeated heading suffixed ``-1``, ``-2``..."""
    text = re.sub(r"^```.*?^```", "", page.read_text(), flags=re.S | re.M)
    seen: Counter[str] = Counter()
    found = set()
    for heading in re.findall(r"^#{1,6} +(.+?) *$", text, re.M):
        slug = re.sub(r"[^\w\- ]", "", heading.lower()).replace(" ", "-")
        found.add(f"{slug}-{seen[slug]}" if seen[slug] else slug)
        seen[slug] += 1
    return found


def local_links(page: Path) -> list[str]:
    """The targets of the page's Markdown links and images that are not URLs."""
    targets = re.findall(r"\]\(([^)\s]+)\)", without_code(page.read_text()))
    return [target for target in targets if not re.match(r"[a-z]+:", target)]


@pytest.mark.parametrize("page", PAGES, ids=lambda page: page.name)
def test_every_link_leads_to_a_file_and_heading_that_exist(page):
    for target in local_links(page):
        path, _, anchor = target.partition("#")
        linked = (page.parent / path).resolve() if path else page
        assert linked.is_file(), f"{page.name}: {target}: no such file"
        assert linked.is_relative_to(ROOT), f"{page.name}: {target} leads out of the project"
        if anchor:
            assert linked.suffix == ".md", f"{page.name}: {target}"
            assert anchor in anchors(linked), f"{page.name}: {target}: no such heading"


def test_the_readme_links_every_page_of_the_docs():
    linked = {(ROOT / target.partition("#")[0]).resolve()
              for target in local_links(ROOT / "README.md")}
    assert sorted(DOCS.glob("*.md"))
    for page in DOCS.glob("*.md"):
        assert page.resolve() in linked, f"the README does not link docs/{page.name}"
    assert len(README_TEXT.encode()) < 16_000, "the README is for a newcomer: keep it short"



def project_texts() -> list[Path]:
    """The documentation and the package's sources: every Markdown file of the project (its
    root, docs/, tests/data/, benchmarks/, sample_data/), the scripts in docs/ and the
    package's modules (their docstrings and --help texts)."""
    markdown = [*ROOT.glob("*.md")]
    for folder in ("docs", "tests", "benchmarks", "sample_data", ".ci"):
        markdown += (ROOT / folder).rglob("*.md")
    return [*markdown, *DOCS.glob("*.py"), *(ROOT / "gsrwt_cli").rglob("*.py")]


def test_nothing_cites_a_file_outside_the_repository():
    """The conventions are stated in docs/CONVENTIONS.md; no page, docstring or help text
    sends a reader to a spec file that is not in the repository."""
    texts = project_texts()
    assert ROOT / "README.md" in texts and DOCS / "CONVENTIONS.md" in texts
    assert ROOT / "gsrwt_cli" / "cli" / "__init__.py" in texts
    forbidden = re.compile(r"GSRWT\.md|shared/spec|spec sections?\b|\bthe spec\b|\bspec \d",
                           re.I)
    for path in texts:
        for number, line in enumerate(path.read_text().splitlines(), 1):
            assert not forbidden.search(line), f"{path.relative_to(ROOT)}:{number}: {line}"
