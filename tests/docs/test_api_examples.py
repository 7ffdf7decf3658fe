"""Every public function and class of the top-level ``impactbar`` namespace shows an example that
runs (the examples run as doctests with the suite)."""

import inspect

import impactbar


def test_every_public_callable_has_an_examples_section():
    missing = []
    for name in impactbar.__all__:
        obj = getattr(impactbar, name)
        if not (inspect.isclass(obj) or inspect.isfunction(obj)):
            continue
        doc = inspect.getdoc(obj) or ""
        if "Examples\n--------\n>>> " not in doc:
            missing.append(name)
    assert missing == []
