"""Shared fixtures: the repository's folders and the command line's release binary."""

import importlib
import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]

# .ci/run installs every optional package these tests use and sets this: a skip there would
# hide a check CI promises, so it is a failure instead.
REQUIRE_OPTIONAL = os.environ.get("EYESHELL_REQUIRE_SCIPY") == "1"


def optional(module: str):
    """Import an optional test dependency (SciPy, pandas, matplotlib, Dask): skip the test
    without it, or fail it when EYESHELL_REQUIRE_SCIPY=1."""
    if REQUIRE_OPTIONAL:
        try:
            return importlib.import_module(module)
        except ImportError as e:
            pytest.fail(f"{module} is needed and EYESHELL_REQUIRE_SCIPY=1: {e}")
    return pytest.importorskip(module)
SCENES = ROOT / "scenes"


def _cli_path() -> pathlib.Path:
    if os.environ.get("EYESHELL_BIN"):
        return pathlib.Path(os.environ["EYESHELL_BIN"])
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    if not target.is_absolute():
        target = ROOT / target
    return target / "release" / "eyeshell"


@pytest.fixture(scope="session")
def cli():
    """Run the command line (built from this checkout, as the README's test command does
    before pytest; built here if it is missing): cli(*args) -> CompletedProcess."""
    path = _cli_path()
    if not path.is_file():
        subprocess.run(["cargo", "build", "--release", "--bin", "eyeshell"], cwd=ROOT, check=True)

    def run(*args, check=True):
        r = subprocess.run([str(path), *map(str, args)], capture_output=True, text=True)
        if check and r.returncode != 0:
            raise AssertionError(f"eyeshell {' '.join(map(str, args))}: exit {r.returncode}: {r.stderr}")
        return r

    return run


def read_csv(path):
    """A CSV file of eyeshell's as {column: list}, numbers parsed exactly (Python's float
    reads the shortest round-trip digits back to the same double)."""
    lines = pathlib.Path(path).read_text().splitlines()
    header = lines[0].split(",")
    columns = {h: [] for h in header}
    for line in lines[1:]:
        for h, cell in zip(header, line.split(",")):
            try:
                columns[h].append(float(cell))
            except ValueError:
                columns[h].append(cell)
    return columns
