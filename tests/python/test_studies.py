"""Parameter studies on a Dask cluster (examples/studies/hasel_studies.py): a LocalCluster of two
worker processes gives the same outputs, bit for bit, as a plain serial loop over the FMU; the
95 % band of a synthetic identification covers the true trajectory; a failing run is reported
with its parameters and the others complete."""
import json
import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "examples" / "studies"))
import hasel_studies as hs  # noqa: E402

# short runs: 1 s at 1 ms steps
INPUTS = hs.sine(60.0, 3 * np.pi, t_end=1.0, dt=1e-3)


def bits(a):
    return np.ascontiguousarray(a).view(np.uint64)


def same_bits(a, b):
    return a.shape == b.shape and np.array_equal(bits(a), bits(b))


@pytest.fixture(scope="module")
def client():
    from distributed import Client, LocalCluster

    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    c = Client(cluster)
    yield c
    c.close()
    cluster.close()


@pytest.fixture(scope="module")
def identification(tmp_path_factory, hasel_path):
    """A small synthetic identification: 2 s of the paper's sine at 10 ms, 1 % noise, the twelve
    default parameters estimated (two combinations held) from the true (default) values."""
    hasel = hasel_path
    d = tmp_path_factory.mktemp("identification")
    for args in (["synth", "--t-end", "2", "--dt", "1e-2", "--noise", "0.01", "--seed", "3", "--out", str(d / "est.csv")],
                 ["identify", str(d / "est.csv"), "--out", str(d / "fit")]):
        r = subprocess.run([str(hasel)] + args, capture_output=True, text=True, timeout=120)
        assert r.returncode == 0, r.stdout + r.stderr
    return d / "fit" / "identification.json"


def test_montecarlo_on_the_cluster_equals_the_serial_loop_bit_for_bit(fmu_path, client, identification, tmp_path):
    posterior = hs.read_posterior(str(identification))
    assert len(posterior.names) == 12 and posterior.factor.shape[1] == 10  # two combinations held
    sets = posterior.draw(16, seed=1)
    cluster = hs.run_study(fmu_path, sets, INPUTS, "dask", client)
    serial = hs.run_study(fmu_path, sets, INPUTS, "serial")
    local = hs.run_study(fmu_path, sets, INPUTS, "local")
    assert cluster.ok.all() and serial.ok.all() and local.ok.all()
    assert same_bits(cluster.outputs, serial.outputs)
    assert same_bits(local.outputs, serial.outputs)
    # the draws differ, so the runs do
    assert not np.array_equal(cluster.outputs[0], cluster.outputs[1])
    # each worker process unpacked the FMU once and ran every task on one reused instance
    by_pid = {}
    for d in cluster.details:
        by_pid.setdefault(d["pid"], set()).add(d["instance"])
        assert d["extractions"] == 1
    assert all(len(instances) == 1 for instances in by_pid.values()), by_pid
    assert os.getpid() not in by_pid
    # the one table, and its CSV, keep every bit
    cluster.write(tmp_path)
    table = cluster.table()
    assert len(table) == 16 * len(INPUTS.t)
    back = hs.read_csv(str(tmp_path / "outputs.csv"))
    for o in hs.OUTPUTS:
        assert same_bits(back[o], table[o])


def test_held_combinations_stay_held_in_the_draw(identification):
    posterior = hs.read_posterior(str(identification))
    doc = json.loads(identification.read_text())
    x = np.array([[np.log(p[n]) for n in posterior.names] for p in posterior.draw(50, seed=2)])
    for held in doc["held_combinations"]:
        w = np.array([held.get(n, 0.0) for n in posterior.names])
        along = (x - posterior.mean) @ w
        spread = np.abs(x - posterior.mean).max()
        # zero up to the 4 digits the file gives the weights with
        assert np.abs(along).max() < 1e-3 * spread, (along, spread)


def test_grid_on_the_cluster_equals_the_serial_loop_bit_for_bit(fmu_path, client):
    axes = {"Kb_1": [0.25, 0.3, 0.35], "b_2": [0.008, 0.01, 0.012]}
    sets = hs.grid_sets(axes)
    assert len(sets) == 9
    cluster = hs.run_study(fmu_path, sets, INPUTS, "dask", client, batch=2)
    serial = hs.run_study(fmu_path, sets, INPUTS, "serial")
    assert cluster.ok.all()
    assert same_bits(cluster.outputs, serial.outputs)
    # a slower actuator 2 (more damping) strokes less
    half = INPUTS.t >= 0.5
    stroke = [np.ptp(cluster.outputs[i, half, 1]) for i in range(9)]
    assert stroke[0] > stroke[1] > stroke[2]


def test_the_95_percent_band_covers_the_true_trajectory(fmu_path, client, identification):
    posterior = hs.read_posterior(str(identification))
    study = hs.run_study(fmu_path, posterior.draw(100, seed=1), INPUTS, "dask", client, batch=5)
    assert study.ok.all()
    truth = hs.run_study(fmu_path, [{}], INPUTS, "local").outputs[0]  # the synthetic data's parameters
    bands = hs.quantile_bands(study)
    inside = np.stack([(bands[o][0] <= truth[:, j]) & (truth[:, j] <= bands[o][2])
                       for j, o in enumerate(hs.OUTPUTS)])
    assert inside.mean() >= 0.9, inside.mean(axis=1)
    # and the band is no wider than it needs to be: well inside +-10 um everywhere
    assert max(np.max(bands[o][2] - bands[o][0]) for o in hs.OUTPUTS) < 10e-6


def test_an_invalid_parameter_set_is_reported_and_the_rest_complete(fmu_path, client):
    sets = [{"Kb_1": 0.3}, {"b_1": -1.0}, {"Kb_2": 0.31}, {"nonsense": 1.0}, {"Kb_3": 0.29}]
    study = hs.run_study(fmu_path, sets, INPUTS, "dask", client)
    assert list(study.ok) == [True, False, True, False, True]
    failures = {f["index"]: f for f in study.failures}
    assert failures[1]["params"] == {"b_1": -1.0}
    assert "fmi2SetReal" in failures[1]["error"] and "b_1" in failures[1]["error"], failures[1]
    assert "not a parameter of the FMU: nonsense" in failures[3]["error"]
    serial = hs.run_study(fmu_path, sets, INPUTS, "serial")
    assert list(serial.ok) == list(study.ok)
    assert same_bits(study.outputs[study.ok], serial.outputs[serial.ok])
    # the instance that failed is reused: a run after it on the same worker is unchanged
    again = hs.run_study(fmu_path, sets[:1], INPUTS, "dask", client)
    assert same_bits(again.outputs[0], serial.outputs[0])


def test_the_command_writes_tables_and_figures(fmu_path, identification, tmp_path):
    out = tmp_path / "grid"
    hs.main(["grid", "--fmu", fmu_path, "--backend", "local", "--t-end", "0.5", "--param", "Kb_1=0.25:0.35:2",
             "--param", "b_2=0.008,0.012", "--out", str(out)])
    assert (out / "grid.png").read_bytes().startswith(b"\x89PNG")
    runs = (out / "runs.csv").read_text().splitlines()
    assert runs[0].startswith("run,ok,error,") and len(runs) == 5
    out = tmp_path / "mc"
    hs.main(["montecarlo", "--fmu", fmu_path, "--backend", "local", "--t-end", "0.5", "--identification",
             str(identification), "--samples", "4", "--out", str(out)])
    bands = hs.read_csv(str(out / "bands.csv"))
    assert len(bands["t"]) == 501 and (bands["h2_p2.5"] <= bands["h2_p97.5"]).all()
    assert (out / "bands.png").read_bytes().startswith(b"\x89PNG")


def test_an_output_the_grid_does_not_move_is_said_to_have_no_variation():
    # h2 when only actuator 1's parameters are swept: equal up to the integrator's noise
    still = np.array([[95.5814085, 95.5814081], [95.5814080, np.nan]])
    assert hs.uniform_value(still) == pytest.approx(95.5814081)
    assert hs.uniform_value(np.array([[95.5, 96.0], [95.7, 95.9]])) is None
    assert hs.uniform_value(np.full((2, 2), np.nan)) is None


def test_a_bad_identification_file_is_named(tmp_path):
    bad = tmp_path / "identification.json"
    bad.write_text("{")
    with pytest.raises(ValueError, match=f"{bad}: cannot read the identification"):
        hs.read_posterior(str(bad))
    bad.write_text("{}")
    with pytest.raises(ValueError, match='no "parameters" object'):
        hs.read_posterior(str(bad))
    bad.write_text('{"parameters": {"Kb_1": {"value": 0.3}}, "covariance": {"parameters": ["Kb_1"]}}')
    with pytest.raises(ValueError, match=f"{bad}: not the identification.json"):
        hs.read_posterior(str(bad))


def test_the_command_runs_on_an_existing_scheduler(fmu_path, client, tmp_path):
    out = tmp_path / "remote"
    result = hs.main(["grid", "--fmu", fmu_path, "--scheduler", client.scheduler.address, "--t-end", "0.2",
                      "--param", "Kb_1=0.25,0.35", "--out", str(out)])
    assert result.ok.all() and {d["pid"] for d in result.details}.isdisjoint({os.getpid()})
    serial = hs.run_study(fmu_path, result.params, hs.sine(t_end=0.2, dt=1e-3), "serial")
    assert same_bits(result.outputs, serial.outputs)
    assert (out / "grid.png").exists()


def test_studies_in_a_row_on_one_client(fmu_path, client):
    # each study scatters the FMU and the inputs anew while the previous one's are released
    sets = [{"Kb_1": 0.3}, {"Kb_1": 0.31}]
    first = hs.run_study(fmu_path, sets, INPUTS, "dask", client)
    for _ in range(5):
        again = hs.run_study(fmu_path, sets, INPUTS, "dask", client)
        assert again.ok.all() and same_bits(again.outputs, first.outputs)
