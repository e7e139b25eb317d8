"""A column added to the table of outputs alone reaches the Python frames: Growth.series,
Growth.history and SweepResults.to_frame() (the files and docs/guide/outputs.md:
crates/eyeshell/tests/output_column.rs). The column is registered for one process, so
the check runs in a process of its own and no other test sees it."""

import subprocess
import sys
import textwrap

import eyeshell

CHECK = textwrap.dedent(
    """
    import math
    import eyeshell
    from eyeshell import _eyeshell

    names = [q["name"] for q in _eyeshell.output_quantities()]
    assert "axial_length_um" not in names, names
    _eyeshell._register_output_for_tests()
    names = [q["name"] for q in _eyeshell.output_quantities()]
    assert names[-2:] == ["defocus_D", "axial_length_um"], names

    scene = eyeshell.Scene(solver__nodes=41, growth__eta0=70, growth__t_end=0.2,
                           output__times=[0.1, 0.2], output__history_points=2)
    g = eyeshell.grow(scene, frames=False)
    for table in (g.series, g.history):
        assert list(table)[-1] == "axial_length_um", list(table)
        assert len(table["t"]) >= 3
        for length, um in zip(table["axial_length"], table["axial_length_um"]):
            assert um == length * 1000.0, (length, um)

    # The sweep's frame from runs of this process (a sweep's own runs are in worker
    # processes, which have the production table alone), an elastic one among them.
    e = eyeshell.solve(solver__nodes=41)
    runs = [eyeshell.RunResult(f"Gamma={G}", {"growth.Gamma": G}, "ok",
                               eyeshell.grow(scene.copy(growth__Gamma=G), frames=False), None, 0.0, i)
            for i, G in enumerate([6.0, 8.0])]
    runs.append(eyeshell.RunResult("elastic", {}, "ok", e, None, 0.0, 2))
    df = eyeshell.SweepResults(runs).to_frame(frames=False)
    columns = list(df)
    assert columns.index("axial_length_um") == columns.index("defocus_D") + 1, columns
    for length, um in zip(df["axial_length"], df["axial_length_um"]):
        assert um == length * 1000.0, (length, um)
    assert len(df["t"]) == 2 * 3 + 1
    # An elastic run's row: what its solve measures (the column too), refraction_D NaN.
    assert e.eye["axial_length_um"] == e.eye["axial_length"] * 1000.0
    assert df["axial_length_um"][-1] == e.eye["axial_length_um"] and math.isnan(df["refraction_D"][-1])
    print("ok")
    """
)


def test_a_column_added_to_the_table_reaches_the_frames():
    r = subprocess.run([sys.executable, "-c", CHECK], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0 and r.stdout.strip() == "ok", r.stdout + r.stderr


def test_the_frames_columns_are_the_tables():
    names = [q["name"] for q in eyeshell._eyeshell.output_quantities()]
    assert names == ["axial_length", "equatorial_radius", "retina_minus_blue", "retina_minus_red", "class",
                     "refraction_D", "drive", "defocus_D"]
    assert {q["kind"] for q in eyeshell._eyeshell.output_quantities()} == {"number", "class"}
