"""The range of a drifter's stop restitution, as the pages state it, is the one the code takes; and
what the page says of a plastic impact (``R = 0``) on the example circuit drifter is what ``orbit()``
does: refused, naming the rest on the stop that the one-impact orbit does not solve."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from impactbar.physical import build, read_config, with_values

pytest.importorskip("pint")

ROOT = Path(__file__).resolve().parents[2]
PAGE = (ROOT / "docs" / "physical.md").read_text(encoding="utf-8")
EXAMPLE = str(ROOT / "examples" / "circuit_drifter.toml")


def _ranges() -> set:
    """Every range the page states for a drifter's ``R``: ``[lo, hi)`` or ``lo <= R < hi``."""
    key_row = next(line for line in PAGE.splitlines()
                   if line.startswith("| `stop.restitution` / `stop.area`"))
    found = re.findall(r"`R` in `\[(\d+), (\d+)([)\]])`", key_row)
    found += [(lo, hi, ")" if op == "<" else "]")
              for lo, op, hi in re.findall(r"a drifter's `(\d+) <= R (<=?) (\d+)`", PAGE)]
    found += [(lo, hi, ")" if op == "<" else "]")
              for lo, op, hi in re.findall(r"`\[stop\] restitution \| area`, `(\d+) <= R (<=?) (\d+)`", PAGE)]
    assert len(found) == 3, found  # the key table, the hammer's table and the drifter's section
    return set(found)


@pytest.mark.parametrize("config", ["circuit-drifter", "hydraulic-drifter"])
def test_the_pages_range_of_a_drifters_restitution_is_the_codes(config):
    """physical.md gave a drifter's stop ``0 <= R <= 1`` (the hammer's range) where the drifters refuse 1."""
    (lo, hi, end), = _ranges()
    lo, hi = float(lo), float(hi)
    assert (lo, hi, end) == (0.0, 1.0, ")")
    base = read_config(config)[0]
    for accepted in (lo, float(np.nextafter(hi, lo))):
        build(with_values(base, {"stop.restitution": accepted}))
    with pytest.raises(ValueError, match=r"restitution must be in \[0, 1\); got 1"):
        build(with_values(base, {"stop.restitution": hi}))


def test_a_plastic_impact_on_the_example_is_refused_as_the_page_says():
    """The page's quoted refusal at ``R = 0`` (the rest on the stop and its length), the orbit found
    at 0.05 and none at 0.02, as the page states."""
    text = re.sub(r"\s+", " ", PAGE)
    quoted = re.search(r"e\.g\. on `examples/circuit_drifter\.toml`: `([^`]+)`", text).group(1)
    base = read_config(EXAMPLE)[0]
    with pytest.raises(ValueError) as info:
        build(with_values(base, {"stop.restitution": 0.0})).orbit()
    assert quoted in str(info.value)
    low, high = (float(x) for x in re.search(r"finds the orbit at `R = ([\d.]+)`, none at `R = ([\d.]+)`",
                                             text).groups())
    assert build(with_values(base, {"stop.restitution": low})).orbit().blow_frequency_Hz > 0.0
    with pytest.raises(ValueError):
        build(with_values(base, {"stop.restitution": high})).orbit()
