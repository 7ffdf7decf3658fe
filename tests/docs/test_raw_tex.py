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


DOCS = pathlib.Path(__file__).resolve().parents[2] / "docs"
#: a line that Markdown reads as a list item (up to three spaces, then -, + or * and a space)
ITEM = re.compile(r"^ {0,3}[-+*] ")


def _items_in_math(text):
    """The lines of ``text`` inside a ``$...$`` or ``$$...$$`` span that begin as a list item: Markdown
    ends the paragraph there, the span's dollars no longer pair and the page shows raw TeX."""
    found, open_ = [], False
    fence = False
    for number, line in enumerate(text.splitlines(), 1):
        if line.lstrip().startswith("```") or (line.strip() == "$$" and not open_):
            fence = not fence  # (a fenced block, or a display block opened on its own line: a block)
            continue
        if fence:
            continue
        if open_ and ITEM.match(line):
            found.append(number)
        body = re.sub(r"``.*?``|`[^`]*`", "", line.replace(r"\$", "")).replace("$$", "$")
        if not body.strip():
            open_ = False  # (a blank line ends a paragraph, and any span in it)
        open_ ^= body.count("$") % 2 == 1
    return found


def test_a_planted_list_item_in_math_is_found():
    assert _items_in_math("a $x\n- y$ b\n") == [2]
    assert _items_in_math("$$x =\n- y$$\n") == [2]
    assert _items_in_math("a $x$ b\n- a list item\n") == []
    assert _items_in_math("```\n$x\n- y\n```\n") == []
    assert _items_in_math("$$\nx =\n+ y\n$$\n") == []


def _display_in_a_paragraph(text):
    """The lines of ``text`` that open a ``$$`` display right after a line of text: MyST reads a
    display only as a block of its own (a blank line before it), else its dollars pair as inline math
    and the page shows raw TeX."""
    found, inside, fence, previous = [], False, False, ""
    for number, line in enumerate(text.splitlines(), 1):
        if line.lstrip().startswith("```"):
            fence = not fence
        elif not fence:
            if not inside and line.startswith("$$") and previous.strip():
                found.append(number)
            inside ^= line.count("$$") % 2 == 1
        previous = line
    return found


def test_a_planted_display_in_a_paragraph_is_found():
    assert _display_in_a_paragraph("moves as\n$$x = 1,$$\nthe rest\n") == [2]
    assert _display_in_a_paragraph("moves as\n\n$$x = 1,$$\n\nthe rest\n") == []
    assert _display_in_a_paragraph("\n$$\nx = 1\n$$\n") == []


def test_no_display_of_the_docs_sits_in_a_paragraph():
    bad = [f"{p.name}:{n}" for p in sorted(DOCS.glob("*.md"))
           for n in _display_in_a_paragraph(p.read_text("utf-8"))]
    assert not bad, f"a $$ display right after a line of text (give it a blank line before): {bad}"


def test_no_line_of_the_docs_math_begins_as_a_list_item():
    bad = [f"{p.name}:{n}" for p in sorted(DOCS.glob("*.md")) for n in _items_in_math(p.read_text("utf-8"))]
    assert not bad, f"a line inside math begins with '- ', '+ ' or '* ' (a list item to Markdown): {bad}"
