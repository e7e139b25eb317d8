"""The switch that keeps CI honest: a test needing an optional package (here SciPy) skips
without it, and fails instead under EYESHELL_REQUIRE_SCIPY=1, which .ci/run sets. Shown by
running such a test again in a child pytest whose `scipy` cannot be imported."""

import os
import pathlib
import subprocess
import sys

TEST = "test_pandas.py::test_file_refusals_name_python_arguments"


def _child(tmp_path, require):
    blocker = tmp_path / "blocker" / "scipy"
    blocker.mkdir(parents=True, exist_ok=True)
    (blocker / "__init__.py").write_text('raise ModuleNotFoundError("No module named scipy (blocked)", name="scipy")\n')
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(blocker.parent), env.get("PYTHONPATH")]))
    env.pop("EYESHELL_REQUIRE_SCIPY", None)
    if require:
        env["EYESHELL_REQUIRE_SCIPY"] = "1"
    here = pathlib.Path(__file__).resolve().parent
    return subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-rs", TEST],
        cwd=here, env=env, capture_output=True, text=True,
    )


def test_a_missing_optional_package_skips_by_default_and_fails_when_required(tmp_path):
    r = _child(tmp_path, require=False)
    assert r.returncode == 0 and "1 skipped" in r.stdout, r.stdout + r.stderr
    r = _child(tmp_path, require=True)
    assert r.returncode == 1 and "1 failed" in r.stdout, r.stdout + r.stderr
    assert "scipy.io is needed and EYESHELL_REQUIRE_SCIPY=1" in r.stdout, r.stdout
