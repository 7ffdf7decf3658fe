"""Every Python example in README.md runs as it stands: executed as a script, and pasted line by line
into a plain interactive interpreter (where a compound statement must end with a blank line)."""

import code
import re
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[2] / "README.md"
BLOCKS = re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)


def test_the_readme_has_examples():
    assert len(BLOCKS) >= 5


@pytest.mark.parametrize("i", range(len(BLOCKS)))
def test_readme_example_runs_as_a_script(i, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # whatever an example writes stays out of the checkout
    exec(compile(BLOCKS[i], f"README.md, Python block {i}", "exec"), {"__name__": "__readme__"})


class _Console(code.InteractiveConsole):
    def __init__(self):
        super().__init__({"__name__": "__readme__"})
        self.errors = []

    def showsyntaxerror(self, filename=None, **kwargs):
        self.errors.append("SyntaxError")

    def showtraceback(self):
        import sys

        self.errors.append(repr(sys.exc_info()[1]))

    def write(self, data):
        pass


@pytest.mark.parametrize("i", range(len(BLOCKS)))
def test_readme_example_pastes_into_a_plain_repl(i, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    console = _Console()
    for line in BLOCKS[i].splitlines() + [""]:
        console.push(line)
    assert console.errors == []


def test_the_paste_check_can_fail():
    console = _Console()
    for line in ["for i in range(2):", "    x = i", "y = 1", ""]:
        console.push(line)
    assert console.errors == ["SyntaxError"]


def test_the_readme_opens_with_a_paragraph_and_a_figure_then_the_user_s_and_the_developer_s_command():
    """The user's command and the developer's stand apart, one line each, the user's first, so that
    pasting the first does not also run the test suite; the figure above them exists."""
    text = README.read_text()
    bash = re.findall(r"```bash\n(.*?)```", text, flags=re.S)
    user, dev = bash[0].strip(), bash[1].strip()
    assert "\n" not in user and 'pip install ".[all]"' in user and "impactbar paper" in user
    assert "pytest" not in user and "ruff" not in user
    assert "\n" not in dev and 'pip install -e ".[test]"' in dev and dev.endswith("python -m pytest -n auto")
    images = re.findall(r"!\[[^\]]*\]\(([^)\s]+)\)", text)
    assert images and all((README.parent / i).is_file() for i in images)
    assert text.index(images[0]) < text.index("```bash")
