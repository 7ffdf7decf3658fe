"""The browser test's rendering of the built site (tests/docs/test_browser_site.py): a fresh
headless Chromium per page (``--dump-dom`` after a 30 s virtual-time budget, the test's former way)
against one browser with a tab per page (the test's way now), alternately, wall time of rendering
every page, and what the test reads from each page compared between the two (MathJax errors,
formulas left untypeset, ids, links, images, raw TeX in the text).

Run: ``python benchmarks/bench_browser_site.py [--site docs/_build/html] [--rounds N] [--pages K]``
(``--pages K``: the first K pages only;
``--every K``: every K-th page). Needs a built site and Debian's ``chromium``.
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "docs"))

import test_browser_site as t  # noqa: E402

#: the former flags: a browser per page, the DOM dumped after a 30 s virtual-time budget
_OLD_FLAGS = (*t.FLAGS, "--virtual-time-budget=30000", "--dump-dom")


def render_one_browser_per_page(page: Path) -> str:
    """The DOM of ``page`` from a fresh headless Chromium (the test's former ``_render``)."""
    with tempfile.TemporaryDirectory(prefix="impactbar-chromium-") as profile:
        out = subprocess.run([t.CHROMIUM, *_OLD_FLAGS, f"--user-data-dir={profile}", page.as_uri()],
                             capture_output=True, text=True, timeout=180, check=False)
    assert out.stdout.strip(), f"chromium rendered nothing for {page}: {out.stderr[-2000:]}"
    return out.stdout


def render_all(pages: list[Path], one_browser: bool) -> list[str]:
    workers = min(8, 2 * (os.cpu_count() or 1))
    if not one_browser:
        with ThreadPoolExecutor(max_workers=workers) as pool:
            return list(pool.map(render_one_browser_per_page, pages))
    with tempfile.TemporaryDirectory(prefix="impactbar-chromium-") as profile:
        browser = t._Browser(profile)
        try:
            with ThreadPoolExecutor(max_workers=workers) as pool:
                return list(pool.map(browser.render, pages))
        finally:
            browser.close()


def findings(dom: str) -> dict:
    """What the test reads from a rendered page."""
    p = t._Page()
    p.feed(dom)
    p.close()
    text = re.sub(r"\s+", " ", "".join(p.text))
    return {"errors": p.errors, "untypeset": p.untypeset, "ids": sorted(p.ids), "links": p.links,
            "images": p.images, "raw_tex": [m.group() for m in t.RAW_TEX.finditer(text)],
            "typeset": dom.count("<mjx-container")}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--site", type=Path, default=t.SITE)
    ap.add_argument("--rounds", type=int, default=1)
    ap.add_argument("--pages", type=int, default=None)
    ap.add_argument("--every", type=int, default=1, help="render every K-th page only")
    a = ap.parse_args()
    pages = sorted(a.site.resolve().rglob("*.html"))[:: a.every][: a.pages]
    print(f"{len(pages)} pages, {os.cpu_count()} CPUs, load {os.getloadavg()[0]:.1f}")
    times = {"a browser per page": [], "one browser, a tab per page": []}
    doms = {}
    for _ in range(a.rounds):
        for name, one in (("a browser per page", False), ("one browser, a tab per page", True)):
            t0 = time.perf_counter()
            doms[name] = render_all(pages, one)
            times[name].append(time.perf_counter() - t0)
            print(f"  {name}: {times[name][-1]:.1f} s (load {os.getloadavg()[0]:.1f})", flush=True)
    old, new = (doms[k] for k in times)
    differ = [str(p.relative_to(a.site.resolve())) for p, x, y in zip(pages, old, new, strict=True)
              if findings(x) != findings(y)]
    for name, ts in times.items():
        print(f"{name}: best {min(ts):.1f} s of {len(ts)}")
    print(f"pages whose findings differ: {len(differ)} {differ[:10]}")
    print(f"typeset formulas: {sum(findings(d)['typeset'] for d in new)}; MathJax errors: "
          f"{sum(len(findings(d)['errors']) for d in new)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
