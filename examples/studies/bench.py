"""Throughput of uncertainty studies, 10 s simulations of the paper's sine at 1 ms steps, drawn
from a small synthetic identification: runs per second of

- the FMU through fmpy in a plain serial loop (one process, a new instance per run) and through
  the worker's cache in this process (one instance, fmi2Reset between runs);
- `hasel simulate --samples` (the Rust library on every core, no FMU);
- a Dask LocalCluster of 2 worker processes (the FMU through fmpy), and its start-up time;
- the per-task overhead of the cluster (tasks that do nothing) and of a run (an FMU run of no
  steps: reset, parameters, initialisation, terminate).

    python examples/studies/bench.py [--fmu fmu/HaselPlatform.fmu] [--hasel target/release/hasel]
"""
import argparse
import os
import pathlib
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import hasel_studies as hs  # noqa: E402


def noop(x):
    return x


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--fmu", default="fmu/HaselPlatform.fmu")
    ap.add_argument("--hasel", default="target/release/hasel")
    ap.add_argument("--serial-runs", type=int, default=6)
    ap.add_argument("--cluster-runs", type=int, default=24)
    ap.add_argument("--rust-runs", type=int, default=100)
    ap.add_argument("--noop-tasks", type=int, default=1000)
    a = ap.parse_args()

    work = pathlib.Path(tempfile.mkdtemp(prefix="hasel_bench_"))
    for args in (["synth", "--t-end", "2", "--dt", "1e-2", "--noise", "0.01", "--seed", "3", "--out", str(work / "est.csv")],
                 ["identify", str(work / "est.csv"), "--out", str(work / "fit")]):
        subprocess.run([a.hasel] + args, check=True, capture_output=True)
    identification = work / "fit" / "identification.json"
    posterior = hs.read_posterior(str(identification))
    inputs = hs.sine(t_end=10.0, dt=1e-3)
    print(f"10 s of the paper's sine at 1 ms ({inputs.steps} steps), parameter sets drawn from a synthetic "
          f"identification of {len(posterior.names)} parameters; {os.cpu_count()} cores, load average "
          f"{os.getloadavg()[0]:.1f} (other processes share the cores)")

    def report(label, runs, seconds, extra=""):
        print(f"  {label:<52} {runs:>5} runs in {seconds:7.2f} s: {runs / seconds:7.2f} runs/s{extra}")

    sets = posterior.draw(max(a.serial_runs, a.cluster_runs), seed=1)
    cpu = time.process_time()
    r = hs.run_study(a.fmu, sets[:a.serial_runs], inputs, "serial")
    cpu = (time.process_time() - cpu) / a.serial_runs
    assert r.ok.all()
    report("FMU, fmpy, serial loop (new instance per run)", a.serial_runs, r.seconds, f" ({cpu * 1e3:.0f} ms CPU per run)")
    hs.run_study(a.fmu, sets[:1], inputs, "local")  # unpack once, as a worker does
    cpu = time.process_time()
    r = hs.run_study(a.fmu, sets[:a.serial_runs], inputs, "local")
    cpu = (time.process_time() - cpu) / a.serial_runs
    report("FMU, fmpy, one process, instance reused (fmi2Reset)", a.serial_runs, r.seconds, f" ({cpu * 1e3:.0f} ms CPU per run)")

    for threads in (1, 2):
        started, cpu = time.perf_counter(), resource.getrusage(resource.RUSAGE_CHILDREN)
        subprocess.run([a.hasel, "simulate", "--samples", str(a.rust_runs), "--uncertainty", str(identification),
                        "--threads", str(threads), "--t-end", "10"], check=True, capture_output=True, text=True)
        seconds = time.perf_counter() - started
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = (after.ru_utime + after.ru_stime - cpu.ru_utime - cpu.ru_stime) / a.rust_runs
        report(f"hasel simulate --samples (Rust, no FMU), {threads} thread{'s' if threads > 1 else ''}",
               a.rust_runs, seconds, f" ({cpu * 1e3:.1f} ms CPU per run, process included)")

    from distributed import Client, LocalCluster

    started = time.perf_counter()
    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    client = Client(cluster)
    print(f"  LocalCluster of 2 worker processes started in {time.perf_counter() - started:.2f} s")
    try:
        hs.run_study(a.fmu, sets[:2], hs.sine(t_end=0.01, dt=1e-3), "dask", client)  # each worker unpacks
        r = hs.run_study(a.fmu, sets[:a.cluster_runs], inputs, "dask", client, progress=False)
        assert r.ok.all()
        report("FMU, fmpy, LocalCluster of 2 workers, 1 run per task", a.cluster_runs, r.seconds)
        per_run = np.mean([d["seconds"] for d in r.details])
        cpu_run = np.mean([d["cpu"] for d in r.details])
        print(f"  one run inside a worker: {per_run * 1e3:.0f} ms wall, {cpu_run * 1e3:.0f} ms CPU")

        def cpu_of(times):
            return times.user + times.system

        here, workers = cpu_of(os.times()), client.run(os.times)
        started = time.perf_counter()
        client.gather(client.map(noop, range(a.noop_tasks), pure=False))
        seconds = time.perf_counter() - started
        here = cpu_of(os.times()) - here
        worker_cpu = sum(cpu_of(os.times_result(t)) - cpu_of(os.times_result(workers[w]))
                         for w, t in client.run(os.times).items())
        print(f"  per-task overhead of the cluster: {a.noop_tasks} tasks that do nothing in {seconds:.2f} s: "
              f"{seconds / a.noop_tasks * 1e3:.2f} ms per task ({a.noop_tasks / seconds:.0f} tasks/s); CPU per task "
              f"{here / a.noop_tasks * 1e3:.2f} ms in the client and scheduler, "
              f"{worker_cpu / a.noop_tasks * 1e3:.2f} ms in the workers")
        empty = hs.sine(t_end=1e-3, dt=1e-3)
        r = hs.run_study(a.fmu, sets[:40], empty, "dask", client)
        per_run = np.mean([d["seconds"] for d in r.details])
        cpu_run = np.mean([d["cpu"] for d in r.details])
        print(f"  per-run overhead in a worker (reset, parameters, initialisation, one step, terminate): "
              f"{per_run * 1e3:.2f} ms wall, {cpu_run * 1e3:.2f} ms CPU")
    finally:
        client.close()
        cluster.close()
    print(f"  load average at the end: {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
