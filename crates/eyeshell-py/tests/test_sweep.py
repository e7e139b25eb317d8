"""eyeshell.sweep: the command line's sweep, run on threads, in processes and on Dask."""

import concurrent.futures
import json

import numpy as np
import pytest

import eyeshell
from conftest import SCENES, optional, read_csv

# Four short growth runs (the fibre stiffness D), each as the command line would run it.
FIBRES = {"fibres.D": [0, 100, 200, 400]}


def small():
    return eyeshell.Scene.from_file(SCENES / "const.toml", solver__nodes=101, output__history_points=0)


def axial(results):
    return {r.name: r.result.series["axial_length"] for r in results}


def test_a_sweep_file_matches_the_command_lines_sweep(cli, tmp_path):
    cli("sweep", SCENES / "grow.toml", "--set", "solver.nodes=101", "--out", tmp_path / "s",
        "--quiet")
    results = eyeshell.sweep(SCENES / "grow.toml", jobs=2, **{"solver.nodes": 101})
    table = read_csv(tmp_path / "s" / "sweep.csv")
    assert [r.name for r in results] == table["run"]
    for i, r in enumerate(results):
        assert r.ok and list(r.values) == ["growth.Gamma", "growth.delta"]
        for key, value in r.values.items():
            assert float(value) == table[key][i]
        assert r.result.series["axial_length"][-1] == table["axial_length"][i]
        series = read_csv(tmp_path / "s" / "runs" / r.name / "series.csv")
        for column, values in series.items():
            assert list(np.asarray(r.result.series[column])) == values, (r.name, column)


def test_grid_and_runs_on_a_scene():
    results = eyeshell.sweep(small(), grid=FIBRES, runs=[{"name": "thin", "material.H0": 0.5}])
    assert [r.name for r in results] == ["thin_D=0", "thin_D=100", "thin_D=200", "thin_D=400"]
    for r, d in zip(results, FIBRES["fibres.D"]):
        alone = eyeshell.grow(small(), frames=False, material__H0=0.5, fibres__D=d)
        assert np.array_equal(r.result.series["axial_length"], alone.series["axial_length"])
    assert all(r.result.scene["material.H0"] == 0.5 for r in results)


def test_results_come_as_they_finish():
    finished = [r.name for r in eyeshell.iter_sweep(small(), grid=FIBRES, jobs=2)]
    assert sorted(finished) == ["D=0", "D=100", "D=200", "D=400"]


def test_a_process_pool_gives_the_local_results():
    local = eyeshell.sweep(small(), grid=FIBRES, jobs=2)
    with concurrent.futures.ProcessPoolExecutor(max_workers=2) as pool:
        remote = eyeshell.sweep(small(), grid=FIBRES, executor=pool)
    assert [r.name for r in remote] == [r.name for r in local]
    for a, b in zip(local, remote):
        for column in ["t", "axial_length", "equatorial_radius"]:
            assert np.array_equal(a.result.series[column], b.result.series[column])


def test_dask_gives_the_local_results():
    distributed = optional("distributed")
    local = eyeshell.sweep(SCENES / "grow.toml", jobs=2, solver__nodes=101)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None, host="127.0.0.1") as cluster, \
            distributed.Client(cluster) as client:
        remote = eyeshell.sweep(SCENES / "grow.toml", executor=client, solver__nodes=101)
    assert [r.name for r in remote] == [r.name for r in local]
    for a, b in zip(local, remote):
        assert a.values == b.values and b.ok
        assert json.dumps(a.result.summary["final"]) == json.dumps(b.result.summary["final"])
        for column in ["t", "axial_length", "equatorial_radius", "retina_minus_blue"]:
            assert np.array_equal(a.result.series[column], b.result.series[column])
        for t, fields in a.result.snapshots.items():
            assert np.array_equal(fields["r"], b.result.snapshots[t]["r"])
