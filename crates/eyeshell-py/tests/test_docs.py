"""The docstrings' examples run, docs/python-api.md is current, and the README's Python
(the notebook example and the solve_bvp side-by-side) runs as shown."""

import doctest
import os
import pathlib
import re
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


def readme_block(after):
    """The first ```python block of the README after the line `after`."""
    text = (ROOT / "README.md").read_text()
    rest = text[text.index(after):]
    return re.search(r"```python\n(.*?)```", rest, re.S).group(1)


def test_the_readme_notebook_example_runs(tmp_path, monkeypatch):
    optional("matplotlib")
    monkeypatch.setenv("MPLBACKEND", "Agg")
    monkeypatch.chdir(tmp_path)
    code = readme_block("### A notebook example")
    assert len(code.strip().splitlines()) <= 10
    exec(compile(code, "README.md", "exec"), {})
    assert (tmp_path / "shell.png").stat().st_size > 1000


def test_the_readme_shows_the_side_by_side_script_and_it_runs():
    optional("scipy")
    script = PY / "examples" / "solve_bvp_side_by_side.py"
    assert readme_block("### eyeshell.solve beside SciPy's solve_bvp") == script.read_text()
    r = subprocess.run([sys.executable, script], capture_output=True, text=True, check=True,
                       cwd=ROOT)
    rows = {line[:22].strip(): line[22:].split() for line in r.stdout.splitlines()[1:]}
    assert set(rows) == {"scipy solve_bvp 1e-6", "eyeshell.solve"}
    for name, (seconds, nodes, first_integral, error) in rows.items():
        assert float(first_integral) < 1e-8 and float(error) < 1e-8, (name, rows)
    # eyeshell on 1,001 nodes is the more accurate in r.
    assert float(rows["eyeshell.solve"][3]) < float(rows["scipy solve_bvp 1e-6"][3])
