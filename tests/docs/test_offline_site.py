"""The built documentation works without a network: no page loads a script, a style
sheet or a font from another host, and the equations are typeset by the MathJax shipped in the site;
and what the pages show is whole: API summaries not cut at "(eq.", no stray
``<Axes ...>`` outputs in the gallery.

Runs on a built site: ``docs/_build/html`` (where .ci/run builds it) or the folder named by the
environment variable ``IMPACTBAR_DOCS_HTML``; skipped when there is none."""

import os
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SITE = Path(os.environ.get("IMPACTBAR_DOCS_HTML", ROOT / "docs" / "_build" / "html"))

pytestmark = pytest.mark.skipif(not (SITE / "index.html").is_file(),
                                reason=f"no built documentation at {SITE}")

#: a resource loaded from another host: <script src="http...">, <link href="http..."> (style sheets,
#: fonts), or a protocol-relative //host/...
REMOTE = re.compile(r"<(script|link|img|iframe)\b[^>]*\b(?:src|href)\s*=\s*[\"']?(?:https?:)?//", re.I)
#: hyperlinks a reader follows on purpose are fine (<a href="https://...">); <link rel="canonical"> too
CANONICAL = re.compile(r"<link\b[^>]*rel\s*=\s*[\"']?canonical", re.I)


def _pages():
    return sorted(SITE.rglob("*.html"))


def test_no_page_loads_anything_from_another_host():
    bad = []
    for page in _pages():
        for m in REMOTE.finditer(page.read_text(errors="replace")):
            tag = page.read_text(errors="replace")[m.start():m.start() + 200].split(">")[0]
            if not CANONICAL.match(tag):
                bad.append(f"{page.relative_to(SITE)}: {tag}>")
    assert not bad, "\n".join(bad[:20])


def test_the_equations_are_typeset_by_the_mathjax_shipped_with_the_site():
    theory = (SITE / "theory.html").read_text()
    src = re.findall(r"<script[^>]*src=\"([^\"]*mathjax[^\"]*)\"", theory, flags=re.I)
    assert src, "theory.html loads no MathJax"
    for s in src:
        assert not re.match(r"(https?:)?//", s)
        assert (SITE / s.split("?")[0]).is_file(), s  # Sphinx may append "?v=<checksum>"
    assert "\\(" in theory or "\\[" in theory  # the equations are there for it to typeset
    fonts = list((SITE / "_static" / "mathjax").rglob("*.woff"))
    assert fonts, "MathJax's fonts are not shipped"


def test_api_summaries_are_not_cut_at_an_abbreviation():
    api = (SITE / "api.html").read_text()
    cells = re.findall(r"<tr class=\"row-(?:odd|even)\"><td>.*?</td>\s*<td>(.*?)</td>", api, flags=re.S)
    assert len(cells) > 50
    cut = [c for c in (re.sub(r"<[^>]+>", "", c).strip() for c in cells)
           if re.search(r"\b(eqs?|Figs?)\.$", c)]
    assert not cut, cut


def test_gallery_pages_show_no_stray_reprs_of_axes():
    pages = [*(SITE / "gallery").glob("*.html"), *(SITE / "tutorials").glob("*.html")]
    assert pages
    stray = [p.name for p in pages if "&lt;Axes" in p.read_text()]
    assert not stray, stray
