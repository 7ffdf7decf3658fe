"""The headline numbers README.md and the theory page quote ("What we found", "Findings against the
paper") are recomputed from the library: each quoted figure must be the computed one to the digits
quoted (Fig. 6's edges were once quoted at the grid point R = 0.5087 instead of R = 0.5)."""

import math
import re
from pathlib import Path

import numpy as np
import pytest

from impactbar import BarModel, CosineLoad
from impactbar.orbits.charts import (
    admissibility_edges,
    hydraulic_existence_edge,
    pneumatic_existence_edge,
    pneumatic_stability_curve,
)

ROOT = Path(__file__).resolve().parents[2]
PAGES = {"README.md": ROOT / "README.md", "theory.md": ROOT / "docs" / "theory.md"}
NUM = r"\$?`?([0-9]+\.[0-9]+)`?\$?"
RIGID = BarModel(s=1.0, d=0.0, R=0.0, n_modes=0)


def _quoted(page: str, pattern: str) -> list[str]:
    """The numbers the page quotes where ``pattern`` (with NUM groups) matches, whitespace-tolerant."""
    text = re.sub(r"\s+", " ", PAGES[page].read_text())
    m = re.search(pattern, text)
    assert m is not None, f"{page}: the quote {pattern!r} is gone; update this test with the text"
    return list(m.groups())


def _agrees(quoted: str, value: float) -> bool:
    """``quoted`` is ``value`` rounded to the digits quoted."""
    decimals = len(quoted.split(".")[1])
    return abs(float(quoted) - value) <= 0.5 * 10.0**-decimals * (1 + 1e-9)


@pytest.fixture(scope="module")
def fig6_edges():
    """The paper's and the exact stability edges at R = 0.5 for k = 10, s pi = 10.1 and 10.01."""
    out = {}
    for spi in (10.1, 10.01):
        model = BarModel(spi / math.pi, 0.0, 0.0, 8)
        out[spi] = (pneumatic_stability_curve(model, [0.5], 10, criterion="paper").y[0],
                    pneumatic_stability_curve(model, [0.5], 10).y[0])
    return out


@pytest.mark.parametrize("page", PAGES)
def test_fig6_edges_near_resonance_are_quoted_at_R_one_half(page, fig6_edges):
    paper, exact = fig6_edges[10.1]
    q = _quoted(page, r"at [`$]R = 0\.5[`$] is [`$]k p_?0/p_?k = ([0-9.]+)[`$]; the exact multipliers "
                r"of an 8-mode bar (?:\(\[§7\]\(theory-7\)\) )?put it at " + NUM)
    assert _agrees(q[0], paper) and _agrees(q[1], exact), (q, paper, exact)
    paper, exact = fig6_edges[10.01]
    q = _quoted(page, r"s ?\\?pi = 10\.01`?\$?: " + NUM + " against " + NUM)
    assert _agrees(q[0], paper) and _agrees(q[1], exact), (q, paper, exact)


@pytest.mark.parametrize("page", PAGES)
def test_far_from_resonance_the_criteria_agree_as_quoted(page):
    q = _quoted(page, r"the two agree to ([0-9]e-[0-9]+)")
    R = np.array([0.2, 0.5, 0.8])
    paper = pneumatic_stability_curve(RIGID, R, 10, criterion="paper").y
    exact = pneumatic_stability_curve(RIGID, R, 10).y
    assert np.all(np.abs(paper - exact) <= float(q[0]))


@pytest.mark.parametrize("page", PAGES)
def test_the_R0_stable_band_is_quoted_as_computed(page):
    fails, fold = _quoted(page, r"> 1/\\?sqrt[({]1 ?\+ ?\\?pi\^2[)}] = ([0-9.]+)[`$]: between there "
                          r"and the fold [`$]([0-9.]+)[`$]")
    lower, upper = _quoted(page, r"The admissible stable band at [`$]R = 0[`$] is [`$]([0-9.]+) < "
                           r"p_?0/p_?1 < ([0-9.]+)[`$]")
    assert fails == upper
    assert _agrees(fold, float(pneumatic_existence_edge(0.0, 0.0, 1)))
    assert _agrees(lower, pneumatic_stability_curve(RIGID, [0.0], 1).y[0])

    def stable(orbits):  # the stable branch strikes while the load pulls away (cos phase < 0)
        branch = [o for o in orbits if math.cos(o.phase) < 0]
        return branch[0] if branch else None

    edges = admissibility_edges(RIGID, lambda f: CosineLoad(f, 1.0), 0.27, 0.318, stable, xtol=1e-10)
    assert len(edges) == 1 and _agrees(fails, edges[0])


@pytest.mark.parametrize("page", PAGES)
def test_the_hydraulic_edge_at_R0_is_sqrt2(page):
    assert _quoted(page, r"(sqrt ?2[`$] at [`$]R = 0)")
    assert hydraulic_existence_edge(RIGID) == pytest.approx(math.sqrt(2), abs=2e-13)


def _readme_block(marker: str) -> tuple[str, dict]:
    """The README's Python block holding ``marker``, executed: its text and its namespace."""
    blocks = re.findall(r"```python\n(.*?)```", PAGES["README.md"].read_text(), flags=re.S)
    block = next(b for b in blocks if marker in b)
    namespace = {"__name__": "__readme__"}
    exec(compile(block, "README.md", "exec"), namespace)
    return block, namespace


def test_the_continuation_example_s_doubling_and_fold_are_quoted_as_computed():
    block, ns = _readme_block("continue_orbit(start")
    pd, fold = (float(x) for x in re.search(r"period doubling \(([0-9.]+)\) and a fold \(([0-9.]+)\)",
                                             block).groups())
    kinds = {e.kind: e.value for e in ns["branch"].events}
    assert abs(kinds["period-doubling"] - pd) <= 0.5e-4 and abs(kinds["fold"] - fold) <= 0.5e-4


def test_the_rod_rock_example_s_efficiency_and_lundbergs_optimum_are_quoted_as_computed():
    from scipy.optimize import brentq

    block, ns = _readme_block("single_blow(")
    quoted = re.search(r"blow\.efficiency  # ([0-9.]+)", block).group(1)
    alpha, gamma = 1.25, 10.0
    closed = 2 / alpha * (1 - math.exp(-alpha)) ** 2 * (1 - 1 / gamma)
    assert _agrees(quoted, ns["blow"].efficiency) and _agrees(quoted, closed)
    best, at = _quoted("README.md", r"the maximum ([0-9.]+) at alpha = ([0-9.]+)")
    a = brentq(lambda x: 2 * x * math.exp(-x) - (1 - math.exp(-x)), 0.5, 3.0, xtol=1e-14)
    assert _agrees(at, a) and _agrees(best, 2 / a * (1 - math.exp(-a)) ** 2)


def test_the_wave_law_s_multipliers_on_the_pneumatic_preset_are_quoted_as_computed():
    """README: on the pneumatic preset's stable orbit (8 flexible modes, as theory §4b measures it)
    the largest multiplier is 0.976 under eq. 10 and R e^(-pi d) = 0.115 under the wave law."""
    from impactbar import physical

    paper_q, wave_q = _quoted("README.md", r"multipliers drop from ([0-9.]+) \(eq\. 10\) to "
                              r"`R e\^\(-pi d\)` = ([0-9.]+)")
    largest = {}
    for law in ("paper", "wave"):
        h = physical.Hammer.from_config({**physical.PRESETS["pneumatic-drill"],
                                         "model": {"n_modes": 8, "impact": law}})
        largest[law] = [o.max_abs_multiplier for o in physical.orbits(h) if o.stable]
    assert len(largest["paper"]) == len(largest["wave"]) == 1
    assert _agrees(paper_q, largest["paper"][0]) and _agrees(wave_q, largest["wave"][0])
    assert _agrees(wave_q, h.R * math.exp(-math.pi * h.d))


def test_the_warmup_cost_is_quoted_as_the_performance_page_measured_it():
    """Getting started quotes ``impactbar warmup``'s cost as the performance page's table gives it
    (the benchmark's figure, which the README quotes too), not an older measurement."""
    perf = (ROOT / "docs" / "performance.md").read_text()
    row = next(r for r in perf.splitlines() if r.startswith("| `impactbar warmup`"))
    kernels, seconds = re.search(r"\(([0-9]+) kernels.*?\| ([0-9]+) s of CPU time at load", row).groups()
    for page in ("docs/getting_started.md", "README.md"):
        text = re.sub(r"\s+", " ", (ROOT / page).read_text())
        quote = re.search(r"`impactbar warmup` compiles every kernel at once "
                          r"\(([0-9]+) kernels in ([0-9]+) s of CPU time", text)
        assert quote is not None and quote.groups() == (kernels, seconds), (page, kernels, seconds)
    # and the wall times of two workers and of one process, measured in the same run
    walls = re.search(r"with `--jobs 2`, the default on 2 cores, ([0-9]+) s of wall time against ([0-9]+) s "
                      r"in one process", row)
    assert walls is not None, row
    for page in ("docs/getting_started.md", "README.md", "docs/performance.md"):
        text = re.sub(r"\s+", " ", (ROOT / page).read_text())
        quote = re.search(r"took ([0-9]+) s(?: of wall time)? against ([0-9]+) s", text)
        assert quote is not None and quote.groups() == walls.groups(), (page, walls.groups())


#: where the pages quote the warm-up's kernels: after the command's name in its sentence, or after
#: "every kernel" (the count in parentheses)
_WARMUP_KERNELS = (r"`impactbar warmup`[^.;]*?\(([0-9,]+) kernels", r"every kernel[^.;(]*\(([0-9,]+) kernels")


def test_every_quote_of_the_warmups_kernels_is_the_count_it_compiles():
    """Each page that quotes how many kernels ``impactbar warmup`` compiles quotes the warm-up's own
    count (:func:`impactbar.cli.warmup.kernel_count`, the per-call counts the slow warm-up test
    checks against the compiles), not the count of an older tree."""
    from impactbar.cli.warmup import kernel_count

    quotes = set()  # (page, where, count): a quote both patterns find, once
    for page in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]:
        text = re.sub(r"\s+", " ", page.read_text())
        quotes |= {(page.name, m.start(1), int(m.group(1).replace(",", ""))) for p in _WARMUP_KERNELS
                   for m in re.finditer(p, text)}
    assert {"README.md", "performance.md", "getting_started.md"} <= {page for page, _, _ in quotes}
    assert len(quotes) >= 4, sorted(quotes)
    assert all(n == kernel_count() for _, _, n in quotes), (kernel_count(), sorted(quotes))
