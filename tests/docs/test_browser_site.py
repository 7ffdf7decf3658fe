"""Every page of the built documentation, as a reader's browser shows it: each page is
opened in headless Chromium (one browser, a tab per page), offline, until MathJax has typeset it, and the
rendered page must show

- no MathJax error (a "Math input error", an ``merror`` node) and every formula typeset;
- no raw TeX in the text a reader sees (a ``$$`` display, ``\\frac``, ``^{``, ... outside the
  typeset formulas and the code);
- no missing image;
- no internal link to a page or an anchor that does not exist;

and no source page (``docs/*.md``, the gallery's and tutorials' scripts, the rendered HTML) holds
a control character (a form feed where ``\\frac`` was meant, a TAB for ``\\to``).

Runs on a built site (``docs/_build/html``, where .ci/run builds it, or the folder named by
``IMPACTBAR_DOCS_HTML``), with Debian's ``chromium`` (or the browser named by
``IMPACTBAR_CHROMIUM``); skipped without either, so .ci/run, which has both, requires it to pass."""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import tempfile
import threading
from concurrent.futures import ThreadPoolExecutor
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

import pytest

ROOT = Path(__file__).resolve().parents[2]
SITE = Path(os.environ.get("IMPACTBAR_DOCS_HTML", ROOT / "docs" / "_build" / "html")).resolve()
CHROMIUM = os.environ.get("IMPACTBAR_CHROMIUM") or next(
    (p for p in map(shutil.which, ("chromium", "chromium-browser", "google-chrome")) if p), None)

pytestmark = [
    pytest.mark.slow,  # every page rendered: minutes (.ci/run runs it with --runslow)
    pytest.mark.timeout(3600),  # the rendering of every page is the first test's fixture
    pytest.mark.skipif(not (SITE / "index.html").is_file(), reason=f"no built documentation at {SITE}"),
    pytest.mark.skipif(CHROMIUM is None, reason="no chromium (Debian: apt-get install chromium)"),
]

#: a headless browser that reaches nothing but the files it is given
FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--no-first-run", "--disable-background-networking",
         "--disable-component-update", "--disable-sync", "--disable-extensions",
         "--disable-background-timer-throttling", "--disable-renderer-backgrounding",
         "--disable-backgrounding-occluded-windows")
#: control characters: everything below 0x20 but TAB, LF and CR in HTML, everything but LF in the
#: Markdown and Python sources (a TAB there is an eaten ``\t``: ``\to``, ``\tau``, ``\theta``)
CONTROL_HTML = re.compile(r"[\x00-\x08\x0b\x0c\x0e-\x1f\x7f]")
CONTROL_SOURCE = re.compile(r"[\x00-\x09\x0b-\x1f\x7f]")
#: TeX a reader should never see as text
RAW_TEX = re.compile(r"\$\$|\\[()\[\]]|[_^]\{|\\(?:frac|dfrac|tfrac|sqrt|sum|prod|int|oint|mathrm|"
                     r"mathbf|mathsf|mathcal|operatorname|text|left|right|big|Big|bigl|bigr|Bigl|Bigr|"
                     r"qquad|quad|cdot|cdots|ldots|dots|infty|partial|nabla|varphi|varepsilon|alpha|"
                     r"beta|gamma|delta|lambda|kappa|sigma|omega|Omega|tau|theta|pi|mu|xi|le|ge|leq|"
                     r"geq|lesssim|approx|to|mapsto|pm|mp|times|bmod|begin|end|label|tag)(?![A-Za-z])")
#: elements whose text is not prose: code, scripts, and MathJax's own output
SKIP = {"script", "style", "code", "pre", "kbd", "samp", "mjx-container", "math", "svg", "textarea"}


class _Page(HTMLParser):
    """One pass over a rendered page (Chromium's serialised DOM, so every element is closed): its
    ids, links, images, the text a reader sees outside formulas and code, the formulas MathJax left
    untypeset, and its MathJax errors."""

    VOID = {"area", "base", "br", "col", "embed", "hr", "img", "input", "link", "meta", "source",
            "track", "wbr"}

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.ids: set[str] = set()
        self.links: list[str] = []
        self.images: list[str] = []
        self.text: list[str] = []
        self.errors: list[str] = []
        self.untypeset: list[str] = []
        self._stack: list[str] = []
        self._skip = 0            # depth inside SKIP elements
        self._math: list | None = None  # the open formula: [its depth, typeset?, its text]

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        for key in ("id", "name"):
            if a.get(key):
                self.ids.add(a[key])
        if tag == "a" and a.get("href"):
            self.links.append(a["href"])
        if tag == "img" and a.get("src"):
            self.images.append(a["src"])
        if tag in {"mjx-merror", "merror"}:
            self.errors.append(a.get("data-mjx-error") or a.get("title") or tag)
        if tag in self.VOID:
            return
        self._stack.append(tag)
        if self._math is None and tag in {"span", "div"} and "math" in (a.get("class") or "").split():
            self._math = [len(self._stack), False, ""]
        if tag == "mjx-container" and self._math is not None:
            self._math[1] = True
        if tag in SKIP:
            self._skip += 1

    def handle_endtag(self, tag):
        if tag in self.VOID or tag not in self._stack:
            return
        while self._stack:
            t = self._stack.pop()
            if t in SKIP:
                self._skip -= 1
            if self._math is not None and len(self._stack) < self._math[0]:
                if not self._math[1]:
                    self.untypeset.append(self._math[2].strip()[:160])
                self._math = None
            if t == tag:
                break

    def handle_data(self, data):
        if "Math input error" in data:
            self.errors.append("Math input error")
        if self._math is not None:
            self._math[2] += data
            if self._math[1]:
                return  # the typeset formula's own text (MathJax's assistive copy)
        if not self._skip:
            self.text.append(data)


#: run in a page once it has navigated: the page's DOM (as ``--dump-dom`` serialises it) once the load
#: event has fired and MathJax, where the page has it, has typeset every formula
_SETTLED = r"""new Promise(resolve => {
  const dom = () => (document.doctype ? new XMLSerializer().serializeToString(document.doctype) + '\n' : '')
                    + document.documentElement.outerHTML;
  const settle = () => setTimeout(() => resolve(dom()), 0);
  const typeset = () => {
    if (!window.MathJax) return settle();
    const started = Date.now();
    const poll = () => {  // the MathJax script sets MathJax.startup when it runs
      if (MathJax.startup && MathJax.startup.promise) MathJax.startup.promise.then(settle, settle);
      else if (Date.now() - started > 60000) settle();  // never started: its formulas show untypeset
      else setTimeout(poll, 20);
    };
    poll();
  };
  if (document.readyState === 'complete') typeset(); else addEventListener('load', typeset, {once: true});
})"""


class _Browser:
    """One headless Chromium for every page, driven over the DevTools protocol on a pipe (its file
    descriptors 3 and 4, messages ended by a NUL byte): each page is rendered in a tab of its own,
    several at a time, instead of a browser started per page."""

    def __init__(self, profile: str):
        to_child, self._to_browser = os.pipe()
        self._from_browser, from_child = os.pipe()

        def pipes():  # in the child: its fd 3 reads the commands, its fd 4 writes the answers
            a, b = os.dup(to_child), os.dup(from_child)  # above 4, so that the dup2s clobber nothing
            os.dup2(a, 3)
            os.dup2(b, 4)

        self.proc = subprocess.Popen(
            [CHROMIUM, *FLAGS, "--remote-debugging-pipe", f"--user-data-dir={profile}", "about:blank"],
            preexec_fn=pipes, pass_fds=(3, 4), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        os.close(to_child)
        os.close(from_child)
        self._send_lock = threading.Lock()
        self._done = threading.Condition()
        self._answers: dict[int, dict] = {}
        self._closed = False
        self._id = 0
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        buffer = b""
        with os.fdopen(self._from_browser, "rb", buffering=0) as pipe:
            while chunk := pipe.read(1 << 20):
                buffer += chunk
                *messages, buffer = buffer.split(b"\0")
                answers = [m for m in map(json.loads, messages) if "id" in m]  # (events are not used)
                with self._done:
                    self._answers.update((m["id"], m) for m in answers)
                    self._done.notify_all()
        with self._done:
            self._closed = True
            self._done.notify_all()

    def call(self, method: str, params: dict | None = None, session: str | None = None,
             timeout: float = 180.0) -> dict:
        """Send one command (to the tab of ``session``) and return its result."""
        with self._send_lock:
            self._id += 1
            key = self._id
            message = {"id": key, "method": method, "params": params or {}}
            if session is not None:
                message["sessionId"] = session
            os.write(self._to_browser, json.dumps(message).encode() + b"\0")
        with self._done:
            answered = self._done.wait_for(lambda: key in self._answers or self._closed, timeout)
            assert answered and key in self._answers, f"chromium did not answer {method}"
            answer = self._answers.pop(key)
        assert "error" not in answer, f"{method}: {answer['error']}"
        return answer["result"]

    def render(self, page: Path) -> str:
        """The DOM of ``page`` once its scripts (MathJax) have run, from a tab of its own."""
        tab = self.call("Target.createTarget", {"url": "about:blank"})["targetId"]
        try:
            session = self.call("Target.attachToTarget", {"targetId": tab, "flatten": True})["sessionId"]
            opened = self.call("Page.navigate", {"url": page.as_uri()}, session)
            assert "errorText" not in opened, f"chromium could not open {page}: {opened['errorText']}"
            dom = self.call("Runtime.evaluate", {"expression": _SETTLED, "returnByValue": True,
                                                 "awaitPromise": True}, session)
            assert "exceptionDetails" not in dom, f"{page}: {dom['exceptionDetails']}"
        finally:
            self.call("Target.closeTarget", {"targetId": tab})
        assert dom["result"]["value"].strip(), f"chromium rendered nothing for {page}"
        return dom["result"]["value"]

    def close(self) -> None:
        try:
            self.call("Browser.close", timeout=30)
        except AssertionError:
            pass
        try:
            self.proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        os.close(self._to_browser)


@pytest.fixture(scope="module")
def site() -> dict[str, _Page]:
    """Every page of the site, rendered and parsed, by its path relative to the site."""
    pages = sorted(SITE.rglob("*.html"))
    with tempfile.TemporaryDirectory(prefix="impactbar-chromium-") as profile:
        browser = _Browser(profile)
        try:
            with ThreadPoolExecutor(max_workers=min(8, 2 * (os.cpu_count() or 1))) as pool:
                doms = list(pool.map(browser.render, pages))
        finally:
            browser.close()
    out = {}
    for page, dom in zip(pages, doms, strict=True):
        parsed = _Page()
        parsed.feed(dom)
        parsed.close()
        out[page.relative_to(SITE).as_posix()] = parsed
    return out


def _report(bad: list[str], what: str) -> str:
    return f"{len(bad)} {what}:\n" + "\n".join(bad[:60]) + ("\n..." if len(bad) > 60 else "")


def test_every_formula_is_typeset_without_a_mathjax_error(site):
    bad = [f"{name}: MathJax error: {e}" for name, p in site.items() for e in p.errors]
    bad += [f"{name}: not typeset: {t!r}" for name, p in site.items() for t in p.untypeset]
    assert not bad, _report(bad, "formulas not rendered")


def test_no_raw_tex_in_the_rendered_text(site):
    bad = []
    for name, p in site.items():
        text = re.sub(r"\s+", " ", "".join(p.text))
        for m in RAW_TEX.finditer(text):
            bad.append(f"{name}: {text[max(0, m.start() - 60):m.end() + 40]!r}")
    assert not bad, _report(bad, "raw TeX in the text")


def test_no_control_characters_in_the_sources_or_the_pages():
    bad = []
    sources = [*(ROOT / "docs").glob("*.md"), *(ROOT / "docs").glob("*_src/*.py"),
               *(ROOT / "docs").glob("*_src/*.rst"), ROOT / "README.md"]
    for path, pattern in [*((p, CONTROL_SOURCE) for p in sources),
                          *((p, CONTROL_HTML) for p in SITE.rglob("*.html"))]:
        text = path.read_text(errors="replace")
        for m in pattern.finditer(text):
            line = text.count("\n", 0, m.start()) + 1
            bad.append(f"{path.relative_to(ROOT) if path.is_relative_to(ROOT) else path}:{line}: "
                       f"{m.group()!r} in {text[max(0, m.start() - 40):m.end() + 40]!r}")
    assert not bad, _report(bad, "control characters")


def _local(base: str, url: str) -> tuple[Path, str] | None:
    """The file and fragment a link or image of page ``base`` points to on this site; ``None`` for
    another host or scheme."""
    parts = urlsplit(url)
    if parts.scheme or parts.netloc:
        return None
    path = (SITE / base).parent / unquote(parts.path) if parts.path else SITE / base
    return path.resolve(), unquote(parts.fragment)


def test_every_image_exists(site):
    bad = []
    for name, p in site.items():
        for src in p.images:
            if src.startswith("data:"):
                continue
            target = _local(name, src)
            if target is not None and not (target[0].is_file() and target[0].stat().st_size > 0):
                bad.append(f"{name}: {src}")
    assert not bad, _report(bad, "missing images")


def test_every_internal_link_and_anchor_exists(site):
    bad = []
    for name, p in site.items():
        for href in p.links:
            target = _local(name, href)
            if target is None:
                continue
            path, fragment = target
            if path.is_dir():
                path = path / "index.html"
            if not path.exists():
                bad.append(f"{name}: {href} (no such file)")
                continue
            if not fragment or path.suffix != ".html":
                continue
            key = path.relative_to(SITE).as_posix() if path.is_relative_to(SITE) else None
            if key not in site or fragment not in site[key].ids:
                bad.append(f"{name}: {href} (no such anchor)")
    assert not bad, _report(bad, "internal links to nothing")
