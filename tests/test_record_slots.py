"""No kernel reads or writes a slot of a record by its number: the exact blow's records (``PR``,
``BS``, ``CI``, ``CT``, ``CNT``, the blocks ``WB``, ``WN``, the tangent's ``TCUR``, ...) are indexed
by the names of :mod:`impactbar.laws.rodrock._records`, where each slot is said once.

What counts as a slot by number: a short upper-case name of two to four characters (the records'
names) indexed by one integer literal, ``PR[3]``, ``CNT0[1]``, ``CH_T[1]``, in code (comments and
strings are prose). Single-letter names are the package's mathematical arrays, where ``[0]`` and
``[-1]`` are the first and last entries (``Z[-1]`` the last segment's impedance, ``U[-1]`` the
continuation's parameter), and ``NOT_RECORDS`` lists the longer ones."""

import io
import re
import tokenize
from pathlib import Path

import impactbar
from impactbar.laws.rodrock import _records

#: a record's slot by an integer literal
SLOT = re.compile(r"\b[A-Z][A-Z0-9_]{1,3}\[-?[0-9]+\]")
#: (module under impactbar/, name): arrays of that form that are no records
NOT_RECORDS = {("laws/wave/periodic.py", "DP")}  # the impact map's Jacobian (DP[0]: its first row)
_PROSE = {tokenize.COMMENT, tokenize.STRING} | {getattr(tokenize, "FSTRING_MIDDLE", tokenize.STRING)}


def _code(text):
    """``text``'s lines with its comments and strings blanked."""
    lines = [list(line) for line in text.splitlines()]
    for tok in tokenize.generate_tokens(io.StringIO(text).readline):
        if tok.type not in _PROSE:
            continue
        (r0, c0), (r1, c1) = tok.start, tok.end
        for r in range(r0, r1 + 1):
            row = lines[r - 1]
            lo = c0 if r == r0 else 0
            hi = c1 if r == r1 else len(row)
            row[lo:hi] = " " * (hi - lo)
    return ["".join(row) for row in lines]


def slots_by_number(text, module=""):
    """``(line, match)`` of every record slot indexed by a number in the source ``text``."""
    out = []
    for i, line in enumerate(_code(text), start=1):
        for m in SLOT.finditer(line):
            if (module, m.group().split("[")[0]) not in NOT_RECORDS:
                out.append((i, m.group()))
    return out


def test_the_scan_finds_a_slot_by_number_in_code_only():
    text = ('PR[3] = 1.0\n'
            'x = WB[0] + CNT0[-1] * CH_T[12]\n'
            '# PR[3] in a comment\n'
            's = "CT[9]" + BS[2]\n'
            '"""a docstring quoting CI[0]"""\n'
            'shape, z, n, y = (16, 4), Z[-1], a.shape[0], PR[PR_MASS] + WB[blk][0] + NSF[j, 0]\n')
    assert slots_by_number(text) == [(1, "PR[3]"), (2, "WB[0]"), (2, "CNT0[-1]"), (2, "CH_T[12]"),
                                     (4, "BS[2]")]
    assert slots_by_number("u = DP[0] @ v\n", "laws/wave/periodic.py") == []
    assert slots_by_number("u = DP[0] @ v\n") == [(1, "DP[0]")]


def test_no_kernel_reads_a_record_slot_by_its_number():
    top = Path(impactbar.__file__).parent
    found = []
    for path in sorted(top.rglob("*.py")):
        module = path.relative_to(top).as_posix()
        found += [f"{module}:{line}: {m}" for line, m in slots_by_number(path.read_text(), module)]
    assert found == [], "record slots by number (name them in laws/rodrock/_records.py):\n" + \
        "\n".join(found)


def test_each_record_names_its_slots_once_within_its_size():
    """The layout itself: within a record no two names share a slot, and every slot lies in the
    record's length (the sizes the workspace is made with)."""
    names = {k: v for k, v in vars(_records).items() if k.isupper() and isinstance(v, int)}
    sizes = {k[:-5]: v for k, v in names.items() if k.endswith("_SIZE")}
    sizes["B"] = names["BLOCKS"]
    assert set(sizes) == {"PR", "BS", "BI", "CI", "CT", "CNT", "TCUR", "B"}
    for rec, size in sizes.items():
        slots = {k: v for k, v in names.items()
                 if re.fullmatch(rec + r"_[A-Z0-9]+", k) and k != rec + "_SIZE"}
        assert slots, rec
        assert len(set(slots.values())) == len(slots), (rec, slots)
        assert all(0 <= v < size for v in slots.values()), (rec, slots)
    positions = [v for k, v in names.items() if k.startswith("WS_")]
    assert len(set(positions)) == len(positions)
