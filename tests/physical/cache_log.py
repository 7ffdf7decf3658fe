"""A cache file's contents for the tests: the designs and gradients of the problem its log names."""

from __future__ import annotations

import json

from impactbar.physical.optimize_cache import DesignCache


def cache_log(path) -> tuple[str, list, dict]:
    """The problem's tag a cache log names on its first line, its designs' records in the order
    first written, and its gradients by ``(id, kind)``."""
    with open(path, encoding="utf-8") as f:
        tag = json.loads(f.readline())["problem"]
    cache = DesignCache(path, tag)
    return tag, list(cache.designs.values()), cache.gradients
