"""The docstrings' examples run, docs/python-api.md is current, and every Python block of
README.md and of the user guide (docs/guide/*.md) runs, printing what the page shows.

The fences are those tests/cli/docs.rs reads for the commands: a ```text block right after a
```python block (only blank lines between) is what the block prints, compared line by line
(a line `…` stands for any lines, `…` within a line for any text, whitespace runs are equal,
numbers equal within a relative 1e-6, or any number with ```text numbers=any);
```python file=PATH is that file verbatim, run by its own test below;
```python skip-test: REASON is not run."""

import contextlib
import doctest
import io
import os
import pathlib
import re
import shutil
import subprocess
import sys

import numpy as np
import pytest

import eyeshell
import eyeshell._api
from conftest import ROOT, SCENES, optional

PY = ROOT / "crates" / "eyeshell-py"


@pytest.mark.parametrize("module", [eyeshell, eyeshell._api], ids=["eyeshell", "eyeshell._api"])
def test_the_docstring_examples_run(module):
    globs = {"eyeshell": eyeshell, "np": np, "SCENES": str(SCENES)}
    failed, attempted = doctest.testmod(module, extraglobs=globs, optionflags=doctest.ELLIPSIS)
    assert attempted > 0 and failed == 0


def test_the_api_reference_is_current():
    r = subprocess.run([sys.executable, PY / "tools" / "api_docs.py"], capture_output=True,
                       text=True, check=True)
    written = (ROOT / "docs" / "python-api.md").read_text()
    assert r.stdout == written, "run: python3 crates/eyeshell-py/tools/api_docs.py --write"



DOCS = [ROOT / "README.md", *sorted((ROOT / "docs" / "guide").glob("*.md"))]


def fenced_blocks(text):
    """[(info, code, line, shown)]: each fenced block with the ```text block right after it."""
    found = []
    lines = text.splitlines()
    i = 0
    while i < len(lines):
        if lines[i].lstrip().startswith("```"):
            # A fence may be indented (inside a list item): its lines lose that indent.
            indent = len(lines[i]) - len(lines[i].lstrip())
            info, start, body = lines[i].strip()[3:].strip(), i + 1, []
            i += 1
            while i < len(lines) and lines[i].strip() != "```":
                line = lines[i]
                body.append(line[indent:] if not line[:indent].strip() else line.lstrip())
                i += 1
            found.append([info, "\n".join(body) + "\n", start, i + 1])  # i: the closing fence
        i += 1
    out = []
    for k, (info, code, line, end) in enumerate(found):
        shown = None
        if k + 1 < len(found):
            n_info, n_code, n_line, _ = found[k + 1]
            gap = lines[end:n_line - 1]
            if all(not g.strip() for g in gap) and n_info.split()[:1] == ["text"]:
                shown = (n_info, n_code)
        out.append((info, code, line, shown))
    return out


NUMBER = re.compile(r"\d+(?:\.\d+)?(?:[eE][-+]?\d+)?")


def tokens(line):
    out, i = [], 0
    while i < len(line):
        c = line[i]
        if c.isspace():
            i += 1
        elif c == "…":
            out.append(("any", None))
            i += 1
        elif c.isdigit():
            m = NUMBER.match(line, i)
            out.append(("num", m.group()))
            i = m.end()
        else:  # one character a token, so that … may stand for part of a word
            out.append(("text", c))
            i += 1
    return out


def tokens_match(shown, printed, any_number):
    if not shown:
        return not printed
    kind, value = shown[0]
    if kind == "any":
        return any(tokens_match(shown[1:], printed[k:], any_number) for k in range(len(printed) + 1))
    if not printed or printed[0][0] != kind:
        return False
    other = printed[0][1]
    if kind == "text" and value != other:
        return False
    if kind == "num" and not (any_number or value == other
                              or abs(float(value) - float(other)) <= 1e-6 * max(abs(float(value)), abs(float(other)))):
        return False
    return tokens_match(shown[1:], printed[1:], any_number)


def lines_match(shown, printed, any_number):
    if not shown:
        return not printed
    if shown[0].strip() == "…":
        return any(lines_match(shown[1:], printed[k:], any_number) for k in range(len(printed) + 1))
    return bool(printed) and tokens_match(tokens(shown[0]), tokens(printed[0]), any_number) \
        and lines_match(shown[1:], printed[1:], any_number)


def output_matches(shown, printed, any_number=False):
    def trim(text):
        lines = [line.rstrip() for line in text.splitlines()]
        while lines and not lines[-1]:
            lines.pop()
        return lines
    return lines_match(trim(shown), trim(printed), any_number)


def test_shown_output_is_compared_as_documented():
    assert output_matches("a 1.0 b\n", "a  1.0000001 b\n")
    assert not output_matches("a 1.0 b\n", "a 1.1 b\n")
    assert output_matches("a 1.0 b", "a 7 b", any_number=True)
    assert output_matches("x\n…\nz", "x\ny1\ny2\nz") and output_matches("x\n…\nz", "x\nz")
    assert not output_matches("x\n…\nz", "x\ny")
    assert output_matches("time … s", "time 0.208 s") and not output_matches("one", "one\ntwo")
    assert output_matches("limit 16.1 kPa (…)", "limit 16.1 kPa (the rest)")


# What a page's blocks must have left behind, beyond what they print.
AFTERWARDS = {"python.md": lambda d: (d / "shell.png").stat().st_size > 1000}


def python_blocks(page):
    return [b for b in fenced_blocks(page.read_text()) if b[0].split()[:1] == ["python"]]


PAGES = [p for p in DOCS if python_blocks(p)]


def test_the_readme_and_the_python_chapter_hold_python():
    names = [str(p.relative_to(ROOT)) for p in PAGES]
    assert "README.md" in names and "docs/guide/python.md" in names, names


@pytest.mark.parametrize("page", PAGES, ids=[str(p.relative_to(ROOT)) for p in PAGES])
def test_every_python_block_of_the_readme_and_the_guide_runs(page, tmp_path, monkeypatch):
    """The page's Python blocks run in order, in one namespace (as in a notebook), in a fresh
    directory holding a copy of scenes/, and print what the page shows."""
    blocks = python_blocks(page)
    shutil.copytree(SCENES, tmp_path / "scenes")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    namespace = {"__name__": "__main__"}
    ran = 0
    for info, code, line, shown in blocks:
        options = info.split(None, 1)[1] if " " in info else ""
        where = f"{page.relative_to(ROOT)}:{line}"
        if options.startswith("file="):
            path = ROOT / options[len("file="):].split()[0]
            assert code == path.read_text(), f"{where} is not {path.relative_to(ROOT)} verbatim"
            continue
        if options.startswith("skip-test"):
            assert options.split(":", 1)[-1].strip(), f"{where}: skip-test needs a reason"
            continue
        assert not options, f"{where}: unknown fence options {options!r}"
        printed = io.StringIO()
        try:
            with contextlib.redirect_stdout(printed):
                exec(compile(code, where, "exec"), namespace)
        except ModuleNotFoundError as e:
            if e.name in {"matplotlib", "scipy", "pandas", "distributed", "dask"}:
                pytest.skip(f"{where} needs {e.name}")
            raise
        ran += 1
        if shown is not None:
            s_info, s_code = shown
            assert output_matches(s_code, printed.getvalue(), "numbers=any" in s_info.split()), \
                f"{where} prints\n{printed.getvalue()}\nnot what the page shows:\n{s_code}"
    check = AFTERWARDS.get(page.name)
    assert ran > 0 and (check is None or check(tmp_path))


def test_the_side_by_side_script_runs():
    """crates/eyeshell-py/examples/solve_bvp_side_by_side.py, shown in docs/guide/python.md
    (the test above checks it is shown verbatim): both solvers within 1e-8, eyeshell the more
    accurate in r."""
    optional("scipy")
    script = PY / "examples" / "solve_bvp_side_by_side.py"
    r = subprocess.run([sys.executable, script], capture_output=True, text=True, check=True,
                       cwd=ROOT)
    rows = {line[:22].strip(): line[22:].split() for line in r.stdout.splitlines()[1:]}
    assert set(rows) == {"scipy solve_bvp 1e-6", "eyeshell.solve"}
    for name, (seconds, nodes, first_integral, error) in rows.items():
        assert float(first_integral) < 1e-8 and float(error) < 1e-8, (name, rows)
    # eyeshell on 1,001 nodes is the more accurate in r.
    assert float(rows["eyeshell.solve"][3]) < float(rows["scipy solve_bvp 1e-6"][3])
    guide = (ROOT / "docs" / "guide" / "python.md").read_text()
    shown = [s for info, _, _, s in fenced_blocks(guide) if info.startswith("python file=")]
    assert len(shown) == 1 and output_matches(shown[0][1], r.stdout, any_number=True)
