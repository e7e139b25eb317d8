"""docs/python-api.md from the docstrings of the installed package `eyeshell`.

    python3 crates/eyeshell-py/tools/api_docs.py --write   # regenerate docs/python-api.md
    python3 crates/eyeshell-py/tools/api_docs.py           # print it

crates/eyeshell-py/tests/test_docs.py checks that the file in the repository is current.
"""

import inspect
import pathlib
import sys

import eyeshell

OUT = pathlib.Path(__file__).resolve().parents[3] / "docs" / "python-api.md"

HEADER = """# Python API reference

Generated from the docstrings of the `eyeshell` package (crates/eyeshell-py) by
`python3 crates/eyeshell-py/tools/api_docs.py --write`; a test fails when this file is not
current. In the examples, `SCENES` is the repository's `scenes/` folder and `np` is NumPy;
every example runs as a doctest in the pytest suite.
"""


def signature(obj, name):
    try:
        return f"{name}{inspect.signature(obj)}".replace("'", "")
    except (TypeError, ValueError):
        return name


def doc(obj):
    text = inspect.getdoc(obj) or ""
    # Examples as Python code blocks, prose as it is.
    out, in_example = [], False
    for line in text.splitlines():
        starts = line.startswith(">>>")
        if starts and not in_example:
            out.append("```python")
            in_example = True
        elif in_example and not line.strip():
            out.append("```")
            in_example = False
        out.append(line)
    if in_example:
        out.append("```")
    return "\n".join(out)


def render():
    parts = [HEADER, doc(eyeshell), ""]
    names = [n for n in eyeshell.__all__ if not n.startswith("__")]
    functions = [n for n in names if inspect.isfunction(getattr(eyeshell, n))]
    classes = [n for n in names if inspect.isclass(getattr(eyeshell, n))]
    parts.append("## Functions\n")
    for n in functions:
        f = getattr(eyeshell, n)
        parts += [f"### `eyeshell.{signature(f, n)}`\n", doc(f), ""]
    parts.append("## Classes\n")
    for n in classes:
        c = getattr(eyeshell, n)
        parts += [f"### `eyeshell.{n}`\n", doc(c), ""]
        for m, member in inspect.getmembers(c):
            if m.startswith("_") or m in getattr(BaseException, "__dict__", {}) or not (inspect.getdoc(member) or "").strip():
                continue
            if issubclass(c, BaseException):
                continue
            if isinstance(member, property):
                parts += [f"#### `{n}.{m}` (property)\n", doc(member), ""]
            elif callable(member):
                parts += [f"#### `{n}.{signature(member, m)}`\n", doc(member), ""]
    return "\n".join(parts).rstrip() + "\n"


if __name__ == "__main__":
    text = render()
    if "--write" in sys.argv:
        OUT.write_text(text)
        print(f"wrote {OUT}")
    else:
        sys.stdout.write(text)
