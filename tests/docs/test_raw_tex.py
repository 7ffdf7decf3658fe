"""TeX in the package's strings is written in raw strings (``r"..."``), so that a backslash is never
an escape that happens to work."""

import io
import pathlib
import re
import tokenize

import impactbar

SRC = pathlib.Path(impactbar.__file__).parent
#: a TeX command (a backslash and two or more letters) written with an escaped backslash
TEX = re.compile(r"\\\\[a-zA-Z]{2,}")


def _unraw_tex(text):
    found = []
    for tok in tokenize.generate_tokens(io.StringIO(text).readline):
        if tok.type == tokenize.STRING:
            prefix = re.match(r"[a-zA-Z]*", tok.string).group(0).lower()
            if "r" not in prefix and TEX.search(tok.string):
                found.append(tok.start[0])
    return found


def test_a_planted_escaped_command_is_found():
    assert _unraw_tex('x = "$\\\\alpha$"\n') == [1]
    assert _unraw_tex('x = r"$\\alpha$"\n') == []
    assert _unraw_tex('x = "line\\n"\n') == []


def test_tex_in_the_package_is_in_raw_strings():
    bad = [f"{p.relative_to(SRC)}:{line}" for p in sorted(SRC.rglob("*.py"))
           for line in _unraw_tex(p.read_text(encoding="utf-8"))]
    assert not bad, f"TeX in a string that is not raw (write r\"...\"): {bad}"
