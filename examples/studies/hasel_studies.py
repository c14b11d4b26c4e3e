"""Uncertainty and parameter studies of HaselPlatform.fmu on a Dask cluster.

Runs a list of parameter sets through the FMU with fmpy, each run the same co-simulation: the
parameters set after fmi2Instantiate (or fmi2Reset), the inputs U1..U3 held over each step of
`dt` (the communication point of step k is exactly k*dt), the outputs h1..h3, tip_x/y/z read
after each step. Where the runs go:

- ``serial``: a plain loop in this process, a fresh FMU instance for every run (the reference);
- ``local``: this process, through the cache a worker uses (one instance, fmi2Reset between runs);
- ``dask``: a Dask cluster: a LocalCluster by default, or ``--scheduler ADDRESS``. Each worker
  process unpacks the FMU once (a module-level cache keyed by the FMU's path and content hash)
  and keeps its instances, resetting them with fmi2Reset between runs.

The three give the same outputs bit for bit: the same shared library computes every run from
the same parameters and inputs, a reset instance starts exactly as a fresh one, and floats travel
between processes as their 8 bytes (pickle) and into CSV as 17 significant digits.

Studies (``python examples/studies/hasel_studies.py STUDY --help``):

- ``montecarlo``: parameter sets drawn from an identification's covariance, in the coordinates
  the fit used (``ln p`` for parameters that must be positive, ``p`` otherwise:
  ``covariance.coordinates`` of identification.json), held combinations held (the covariance is
  zero along them; from older files without the full covariance they are projected out). The
  draw is ``x = x_hat + F xi`` with ``F F^T`` the covariance (eigen-decomposition, eigenvalues
  below 1e-12 of the largest dropped) and ``xi`` standard normal from numpy's
  ``default_rng(seed)``: the same distribution as ``hasel simulate --samples``, not the same
  numbers (that command seeds each sample with SplitMix64). To run exactly the sets the Rust
  command drew, give its ``--draws FILE.csv`` to ``run``. Writes bands.csv (the columns of the
  Rust command's), outputs.csv, runs.csv and bands.png.
- ``grid``: a full-factorial sweep of named parameters (``--param Kb_1=0.2:0.4:3``,
  ``--param b_1=0.1,0.13``). Writes outputs.csv, runs.csv, grid.png.
- ``run``: the parameter sets of a CSV (one row per set, columns named as FMU parameters;
  ``sample`` and ``failed`` columns are ignored). Writes outputs.csv, runs.csv.

A run that fails (an invalid parameter, a step the FMU discards) is reported in runs.csv with
its parameters and the FMU's message; the other runs complete.
"""
from __future__ import annotations

import argparse
import atexit
import ctypes
import hashlib
import itertools
import json
import math
import os
import pathlib
import shutil
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, field

import numpy as np

OUTPUTS = ("h1", "h2", "h3", "tip_x", "tip_y", "tip_z")
INPUTS = ("U1", "U2", "U3")
PHASES = (0.0, 2.0 * math.pi / 3.0, 4.0 * math.pi / 3.0)


# --------------------------------------------------------------------------------------------
# inputs


@dataclass
class Inputs:
    """Voltages U1..U3 at the communication points t_k = k*dt, k = 0..n, each held over
    [t_k, t_k + dt); the run ends at n*dt."""

    dt: float
    u: np.ndarray  # (n + 1, 3)

    @property
    def steps(self) -> int:
        return len(self.u) - 1

    @property
    def t(self) -> np.ndarray:
        return np.arange(len(self.u)) * self.dt


def steps_of(t_end: float, dt: float) -> int:
    if not (dt > 0 and t_end > 0):
        raise ValueError(f"t_end = {t_end}, dt = {dt}: both must be > 0")
    return int(math.floor(t_end / dt * (1 + 1e-12)))


def sine(u0: float = 60.0, omega: float = 3 * math.pi, t_end: float = 10.0, dt: float = 1e-3) -> Inputs:
    """The paper's excitation U0 sin(omega t + phi_i), phi = 0, 120, 240 degrees."""
    t = np.arange(steps_of(t_end, dt) + 1) * dt
    return Inputs(dt, np.stack([u0 * np.sin(omega * t + p) for p in PHASES], axis=1))


def from_csv(path: str, t_end: float | None = None, dt: float = 1e-3) -> Inputs:
    """Sampled voltages (CSV with t,U1,U2,U3; other columns ignored), held from each sample to
    the next, read at the communication points."""
    table = read_csv(path)
    for c in ("t",) + INPUTS:
        if c not in table:
            raise ValueError(f"{path}: missing column {c}")
    t = table["t"]
    end = t[-1] if t_end is None else t_end
    grid = np.arange(steps_of(end, dt) + 1) * dt
    k = np.clip(np.searchsorted(t, grid * (1 + 1e-12), side="right") - 1, 0, len(t) - 1)
    return Inputs(dt, np.stack([table[c][k] for c in INPUTS], axis=1))


def read_csv(path: str) -> dict[str, np.ndarray]:
    """A numeric CSV with a header row ('#' lines skipped) as columns."""
    lines = [ln for ln in pathlib.Path(path).read_text().splitlines() if ln.strip() and not ln.startswith("#")]
    if not lines:
        raise ValueError(f"{path}: empty file")
    header = [h.strip() for h in lines[0].split(",")]
    rows = []
    for no, ln in enumerate(lines[1:], start=2):
        fields = ln.split(",")
        if len(fields) != len(header):
            raise ValueError(f"{path}:{no}: {len(fields)} fields, the header has {len(header)}")
        try:
            rows.append([float(f) for f in fields])
        except ValueError as e:
            raise ValueError(f"{path}:{no}: {e}") from None
    data = np.array(rows, dtype=float).reshape(len(rows), len(header))
    return {h: data[:, i] for i, h in enumerate(header)}


# --------------------------------------------------------------------------------------------
# one run on an FMU instance, and the per-process cache of unpacked FMUs and instances


@dataclass(frozen=True)
class FmuRef:
    """An FMU by path and content: workers that do not share the file system get the bytes."""

    path: str
    digest: str

    @staticmethod
    def of(path: str) -> "FmuRef":
        data = pathlib.Path(path).read_bytes()
        return FmuRef(str(pathlib.Path(path).resolve()), hashlib.sha256(data).hexdigest())


class _Instance:
    """One FMU2Slave with its own logger, which keeps the FMU's messages for error reports."""

    def __init__(self, unit: "_Unit", number: int):
        from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                               fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)
        from fmpy import calloc, free

        self.number = number
        self.messages: list[str] = []
        self.runs = 0

        def logger(component, instance, status, category, message):
            self.messages.append(message.decode("utf-8", "replace"))

        callbacks = fmi2CallbackFunctions()
        callbacks.logger = fmi2CallbackLoggerTYPE(logger)
        callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        try:
            from fmpy.logging import addLoggerProxy

            addLoggerProxy(ctypes.byref(callbacks))
        except Exception:  # the messages are lost, the statuses are not
            pass
        self._callbacks = callbacks  # kept alive as long as the instance
        md = unit.model_description
        self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=unit.unzipdir,
                             modelIdentifier=md.coSimulation.modelIdentifier,
                             instanceName=f"study{number}")
        self.fmu.instantiate(callbacks=callbacks)

    def free(self):
        # fmi2FreeInstance only: the shared library stays loaded for the other instances
        try:
            self.fmu.fmi2FreeInstance(self.fmu.component)
        except Exception:
            pass


class _Unit:
    """An FMU unpacked once in this process, with its instances ready for reuse."""

    def __init__(self, ref: FmuRef, data: bytes | None):
        from fmpy import extract, read_model_description

        self.dir = tempfile.mkdtemp(prefix="hasel_study_")
        atexit.register(shutil.rmtree, self.dir, True)  # when the worker process ends
        source = ref.path
        if data is not None or not os.path.exists(source):
            if data is None:
                raise FileNotFoundError(f"{ref.path} is not on this worker and no copy was sent")
            source = os.path.join(self.dir, "model.fmu")
            pathlib.Path(source).write_bytes(data)
        self.model_description = read_model_description(source)
        self.unzipdir = extract(source, os.path.join(self.dir, "unzipped"))
        self.vr = {v.name: v.valueReference for v in self.model_description.modelVariables}
        self.parameters = {v.name for v in self.model_description.modelVariables if v.causality == "parameter"}
        self.lock = threading.Lock()
        self.idle: list[_Instance] = []
        self.created = 0

    def acquire(self) -> _Instance:
        with self.lock:
            if self.idle:
                return self.idle.pop()
            self.created += 1
            number = self.created
        return _Instance(self, number)

    def release(self, inst: _Instance):
        with self.lock:
            self.idle.append(inst)


_UNITS: dict[tuple[str, str], _Unit] = {}
_UNITS_LOCK = threading.Lock()
EXTRACTIONS = {"count": 0}


def unit_for(ref: FmuRef, data: bytes | None = None) -> _Unit:
    """This process's unpacked copy of the FMU (made on first use)."""
    key = (ref.path, ref.digest)
    with _UNITS_LOCK:
        unit = _UNITS.get(key)
        if unit is None:
            unit = _UNITS[key] = _Unit(ref, data)
            EXTRACTIONS["count"] += 1
        return unit


def simulate(inst: _Instance, unit: _Unit, params: dict, inputs: Inputs) -> np.ndarray:
    """One co-simulation on an instance in the instantiated state; returns (n + 1, 6) outputs."""
    fmu = inst.fmu
    unknown = [k for k in params if k not in unit.parameters]
    if unknown:
        raise ValueError(f"not a parameter of the FMU: {', '.join(unknown)}")
    fmu.setupExperiment(startTime=0.0)  # no tolerance: the FMU's rtol parameter decides
    if params:
        fmu.setReal([unit.vr[k] for k in params], [float(v) for v in params.values()])
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    c = fmu.component
    u_vr = (ctypes.c_uint * 3)(*[unit.vr[u] for u in INPUTS])
    u_val = (ctypes.c_double * 3)()
    y_vr = (ctypes.c_uint * 6)(*[unit.vr[y] for y in OUTPUTS])
    y_val = (ctypes.c_double * 6)()
    y_view = np.ctypeslib.as_array(y_val)
    out = np.empty((inputs.steps + 1, 6))
    set_real, do_step, get_real = fmu.fmi2SetReal, fmu.fmi2DoStep, fmu.fmi2GetReal
    get_real(c, y_vr, 6, y_val)
    out[0] = y_view
    u, dt = inputs.u.tolist(), inputs.dt
    for k in range(inputs.steps):
        u_val[0], u_val[1], u_val[2] = u[k]
        set_real(c, u_vr, 3, u_val)
        do_step(c, k * dt, dt, 1)
        get_real(c, y_vr, 6, y_val)
        out[k + 1] = y_view
    fmu.terminate()
    return out


def _failure(index, params, error, inst=None):
    reason = f"{type(error).__name__}: {error}"
    if inst is not None and inst.messages:
        reason += " (FMU: " + inst.messages[-1] + ")"
    return {"index": index, "params": params, "ok": False, "error": reason, "outputs": None,
            "pid": os.getpid(), "instance": None if inst is None else inst.number}


def run_batch(ref: FmuRef, batch: list, inputs: Inputs, data: bytes | None = None) -> list[dict]:
    """Runs (index, params) pairs on this process's cached instances: the task of a worker."""
    unit = unit_for(ref, data)
    results = []
    for index, params in batch:
        inst = unit.acquire()
        inst.messages.clear()
        started, cpu = time.perf_counter(), time.thread_time()
        try:
            if inst.runs:
                inst.fmu.reset()  # fmi2Reset: back to the start values, not a reload
            inst.runs += 1
            out = simulate(inst, unit, params, inputs)
        except Exception as e:  # reported with its parameters; the study goes on
            results.append(_failure(index, params, e, inst))
            try:
                inst.fmu.reset()
                unit.release(inst)
            except Exception:
                inst.free()
            continue
        unit.release(inst)
        results.append({"index": index, "params": params, "ok": True, "error": "", "outputs": out,
                        "seconds": time.perf_counter() - started, "cpu": time.thread_time() - cpu,
                        "pid": os.getpid(),
                        "instance": inst.number, "extractions": EXTRACTIONS["count"]})
    return results


def run_serial(path: str, params_list: list[dict], inputs: Inputs) -> list[dict]:
    """The reference: a plain loop, a new instance for every run, nothing reused but the file."""
    from fmpy import extract, read_model_description

    md = read_model_description(path)
    unzipdir = extract(path)
    try:
        return _serial_loop(md, unzipdir, params_list, inputs)
    finally:
        shutil.rmtree(unzipdir, ignore_errors=True)


def _serial_loop(md, unzipdir, params_list, inputs):
    from fmpy.fmi2 import FMU2Slave

    vr = {v.name: v.valueReference for v in md.modelVariables}
    names = {v.name for v in md.modelVariables if v.causality == "parameter"}
    results = []
    for index, params in enumerate(params_list):
        fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipdir,
                        modelIdentifier=md.coSimulation.modelIdentifier, instanceName=f"serial{index}")
        try:
            unknown = [k for k in params if k not in names]
            if unknown:
                raise ValueError(f"not a parameter of the FMU: {', '.join(unknown)}")
            fmu.instantiate()
            fmu.setupExperiment(startTime=0.0)
            if params:
                fmu.setReal([vr[k] for k in params], [float(v) for v in params.values()])
            fmu.enterInitializationMode()
            fmu.exitInitializationMode()
            out = np.empty((inputs.steps + 1, 6))
            out[0] = fmu.getReal([vr[y] for y in OUTPUTS])
            for k in range(inputs.steps):
                fmu.setReal([vr[u] for u in INPUTS], list(inputs.u[k]))
                fmu.doStep(currentCommunicationPoint=k * inputs.dt, communicationStepSize=inputs.dt)
                out[k + 1] = fmu.getReal([vr[y] for y in OUTPUTS])
            fmu.terminate()
            results.append({"index": index, "params": params, "ok": True, "error": "", "outputs": out})
        except Exception as e:
            results.append(_failure(index, params, e))
        finally:
            if fmu.component is not None:
                fmu.fmi2FreeInstance(fmu.component)
    return results


# --------------------------------------------------------------------------------------------
# a study: many runs, on a cluster or here, back as one table


@dataclass
class StudyResult:
    t: np.ndarray
    inputs: Inputs
    params: list[dict]
    outputs: np.ndarray  # (runs, n + 1, 6), NaN for failed runs
    ok: np.ndarray  # (runs,) bool
    errors: list[str]
    seconds: float
    details: list[dict] = field(default_factory=list)

    @property
    def failures(self) -> list[dict]:
        return [{"index": i, "params": self.params[i], "error": self.errors[i]}
                for i in range(len(self.params)) if not self.ok[i]]

    def table(self) -> np.ndarray:
        """One long table of every successful run: run, t, h1..tip_z."""
        good = np.flatnonzero(self.ok)
        n = len(self.t)
        dtype = [("run", "i8"), ("t", "f8")] + [(o, "f8") for o in OUTPUTS]
        tab = np.empty(len(good) * n, dtype=dtype)
        tab["run"] = np.repeat(good, n)
        tab["t"] = np.tile(self.t, len(good))
        for j, o in enumerate(OUTPUTS):
            tab[o] = self.outputs[good, :, j].reshape(-1)
        return tab

    def write(self, out: pathlib.Path):
        out.mkdir(parents=True, exist_ok=True)
        tab = self.table()
        write_csv(out / "outputs.csv", list(tab.dtype.names), [tab[c] for c in tab.dtype.names])
        names = sorted({k for p in self.params for k in p})
        rows = ["run,ok,error," + ",".join(names)]
        for i, p in enumerate(self.params):
            error = self.errors[i].replace('"', "'")
            rows.append(f'{i},{int(self.ok[i])},"{error}",' + ",".join(fmt(p[k]) if k in p else "" for k in names))
        atomic_text(out / "runs.csv", "\n".join(rows) + "\n")


def fmt(v: float) -> str:
    """17 significant digits: reads back to the same bits."""
    return repr(float(v))


def atomic_text(path: pathlib.Path, text: str):
    tmp = path.with_name(f".{path.name}.tmp{os.getpid()}")
    tmp.write_text(text)
    os.replace(tmp, path)


def write_csv(path: pathlib.Path, header: list[str], columns: list[np.ndarray]):
    lines = [",".join(header)]
    for row in zip(*[np.asarray(c).tolist() for c in columns]):
        lines.append(",".join(repr(v) for v in row))
    atomic_text(path, "\n".join(lines) + "\n")


def run_study(fmu_path: str, params_list: list[dict], inputs: Inputs, backend: str = "dask", client=None,
              batch: int = 1, progress: bool | None = None) -> StudyResult:
    """Runs every parameter set of `params_list` with `inputs`: on `client`'s cluster
    (backend "dask"), in this process with a reused instance ("local"), or in a plain loop with
    a new instance per run ("serial")."""
    started = time.perf_counter()
    ref = FmuRef.of(fmu_path)
    pairs = list(enumerate(params_list))
    if backend == "serial":
        results = run_serial(fmu_path, params_list, inputs)
    elif backend == "local":
        results = run_batch(ref, pairs, inputs)
    elif backend == "dask":
        if client is None:
            raise ValueError("backend 'dask' needs a client")
        batches = [pairs[i:i + batch] for i in range(0, len(pairs), max(1, batch))]
        # the inputs and the FMU's bytes travel once to every worker, not with every task; under
        # keys of their own (hash=False): a content key would be shared with an earlier study's
        # data, which the scheduler may be releasing just then
        shared_inputs = client.scatter(inputs, broadcast=True, hash=False)
        data = pathlib.Path(fmu_path).read_bytes()
        shared_data = client.scatter(data, broadcast=True, hash=False)
        futures = [client.submit(run_batch, ref, b, shared_inputs, shared_data, pure=False) for b in batches]
        if progress if progress is not None else (sys.stderr.isatty() and len(futures) > 1):
            from distributed import progress as show

            show(futures)
            print(file=sys.stderr)
        results = [r for rs in client.gather(futures) for r in rs]
    else:
        raise ValueError(f"backend {backend!r}: expected dask, local or serial")
    results.sort(key=lambda r: r["index"])
    n = inputs.steps + 1
    outputs = np.full((len(params_list), n, 6), np.nan)
    ok = np.zeros(len(params_list), bool)
    errors = [""] * len(params_list)
    for r in results:
        if r["ok"]:
            outputs[r["index"]] = r["outputs"]
            ok[r["index"]] = True
        else:
            errors[r["index"]] = r["error"]
    details = [{k: v for k, v in r.items() if k != "outputs"} for r in results]
    return StudyResult(inputs.t, inputs, params_list, outputs, ok, errors, time.perf_counter() - started, details)


# --------------------------------------------------------------------------------------------
# Monte Carlo from an identification's covariance


@dataclass
class Posterior:
    center: dict  # every parameter of the identification at its value
    names: list  # the estimated parameters, which the draw moves
    log: np.ndarray  # per estimated parameter: drawn in ln p
    mean: np.ndarray  # identified values in those coordinates
    factor: np.ndarray  # x = mean + factor @ xi

    def draw(self, samples: int, seed: int) -> list[dict]:
        rng = np.random.default_rng(seed)
        xi = rng.standard_normal((samples, self.factor.shape[1]))
        x = self.mean + xi @ self.factor.T
        sets = []
        for row in x:
            p = dict(self.center)
            for name, is_log, v in zip(self.names, self.log, row):
                p[name] = math.exp(v) if is_log else float(v)
            sets.append(p)
        return sets


def read_posterior(path: str) -> Posterior:
    """The distribution `hasel identify` reports in identification.json (see the module doc)."""
    def fail(msg):
        return ValueError(f"{path}: {msg}")

    try:
        doc = json.loads(pathlib.Path(path).read_text())
    except (OSError, ValueError) as e:
        raise fail(f"cannot read the identification: {e}") from None
    params = doc.get("parameters") if isinstance(doc, dict) else None
    if not isinstance(params, dict):
        raise fail('no "parameters" object: expected the identification.json of `hasel identify`')
    center = {}
    for name, entry in params.items():
        v = entry.get("value") if isinstance(entry, dict) else None
        center[name] = float(v)
    try:
        return _posterior(doc, params, center)
    except (KeyError, TypeError, ValueError, IndexError) as e:
        raise fail(f"not the identification.json of `hasel identify`: {type(e).__name__} {e}") from None


def _posterior(doc: dict, params: dict, center: dict) -> Posterior:
    held = doc.get("held_combinations") or []
    if "covariance" in doc:
        c = doc["covariance"]
        names, log = list(c["parameters"]), np.array([k == "ln" for k in c["coordinates"]])
        cov = np.array(c["matrix"], dtype=float).reshape(len(names), len(names))
        exact = True
    else:  # older files: standard errors and the rounded correlations
        names = list(doc["correlation"]["parameters"])
        r = np.array(doc["correlation"]["matrix"], dtype=float).reshape(len(names), len(names))
        log = np.array([params[n]["prior"] > 0 for n in names])
        se = np.array([params[n]["std_error"] / (params[n]["value"] if lg else 1.0) for n, lg in zip(names, log)])
        cov = r * np.outer(se, se)
        exact = False
    for n in names:
        if n not in center:
            raise ValueError(f"covariance: {n} is not among the parameters")
    mean = np.array([math.log(center[n]) if lg else center[n] for n, lg in zip(names, log)])
    lam, vec = np.linalg.eigh((cov + cov.T) / 2)
    keep = lam > 1e-12 * lam.max()
    factor = vec[:, keep] * np.sqrt(lam[keep])
    if not exact and held:
        q, _ = np.linalg.qr(np.array([[h.get(n, 0.0) for n in names] for h in held]).T)
        factor = factor - q @ (q.T @ factor)
    return Posterior(center, names, log, mean, factor)


def quantile_bands(result: StudyResult) -> dict[str, np.ndarray]:
    """Per output: 2.5 %, median and 97.5 % over the successful runs at every time."""
    good = result.outputs[result.ok]
    q = np.quantile(good, [0.025, 0.5, 0.975], axis=0)  # (3, n, 6), linear: as the Rust command
    return {o: q[:, :, j] for j, o in enumerate(OUTPUTS)}


def write_bands(result: StudyResult, path: pathlib.Path):
    bands = quantile_bands(result)
    header = ["t"] + list(INPUTS)
    cols = [result.t] + [result.inputs.u[:, i] for i in range(3)]
    for o in OUTPUTS:
        header += [f"{o}_p2.5", f"{o}_median", f"{o}_p97.5"]
        cols += [bands[o][0], bands[o][1], bands[o][2]]
    write_csv(path, header, cols)


# --------------------------------------------------------------------------------------------
# figures


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_bands(result: StudyResult, path: pathlib.Path, data: dict | None = None, title: str = ""):
    """Per output the median and its 95 % band over the measured data (top), and the same less
    the median (bottom), where a band narrower than the signal shows."""
    plt = _plt()
    bands = quantile_bands(result)
    shown = [o for o in OUTPUTS if data and o in data] or list(OUTPUTS)
    fig, axes = plt.subplots(2, len(shown), figsize=(4.2 * len(shown), 7), squeeze=False)
    um = 1e6
    for j, o in enumerate(shown):
        lo, med, hi = bands[o]
        top, bottom = axes[0, j], axes[1, j]
        top.fill_between(result.t, lo * um, hi * um, alpha=0.3, label="95 % band")
        top.plot(result.t, med * um, lw=1, label="median")
        bottom.fill_between(result.t, (lo - med) * um, (hi - med) * um, alpha=0.3, label="95 % band")
        bottom.axhline(0, lw=1)
        if data and o in data:
            top.plot(data["t"], data[o] * um, ".", ms=2, color="0.3", label="measured")
            k = np.clip(np.round(data["t"] / result.inputs.dt).astype(int), 0, len(result.t) - 1)
            bottom.plot(data["t"], (data[o] - med[k]) * um, ".", ms=2, color="0.3", label="measured - median")
        top.set(title=f"{o}: median and 95 % band", xlabel="t [s]", ylabel=f"{o} [um]")
        bottom.set(title=f"{o} less the median", xlabel="t [s]", ylabel=f"{o} - median [um]")
        top.legend(fontsize=7, loc="upper right")
        bottom.legend(fontsize=7, loc="upper right")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


def uniform_value(values: np.ndarray, rtol: float = 1e-6) -> float | None:
    """The value of `values` (NaN left out) when they all agree within `rtol` of it, the FMU's
    default relative tolerance: an output the swept parameters do not reach differs between runs
    only by what the integrator's step sequence leaves (4e-9 of h2's stroke when actuator 1's
    parameters are swept); None when they vary."""
    finite = values[np.isfinite(values)]
    if finite.size == 0:
        return None
    middle = float(np.median(finite))
    return middle if np.ptp(finite) <= rtol * max(abs(middle), np.finfo(float).tiny) else None


def plot_grid(result: StudyResult, axes_values: dict[str, list], path: pathlib.Path):
    """The heights of every run, and, for two swept parameters, the steady peak-to-peak stroke
    of each actuator over the grid."""
    plt = _plt()
    names = list(axes_values)
    two = len(names) == 2
    fig, axes = plt.subplots(2 if two else 1, 3, figsize=(14, 8 if two else 4), squeeze=False)
    um = 1e6
    half = result.t >= result.t[-1] / 2
    for j in range(3):
        ax = axes[0, j]
        for i, p in enumerate(result.params):
            if result.ok[i]:
                label = ", ".join(f"{n}={p[n]:.3g}" for n in names)
                ax.plot(result.t, result.outputs[i, :, j] * um, lw=0.8, label=label)
        ax.set(title=f"h{j + 1}, every run", xlabel="t [s]", ylabel=f"h{j + 1} [um]")
        if len(result.params) <= 12:
            ax.legend(fontsize=6, loc="upper right")
        if two:
            a, b = axes_values[names[0]], axes_values[names[1]]
            stroke = np.full((len(a), len(b)), np.nan)
            for i, p in enumerate(result.params):
                if result.ok[i]:
                    y = result.outputs[i, half, j]
                    stroke[a.index(p[names[0]]), b.index(p[names[1]])] = np.ptp(y) * um
            ax = axes[1, j]
            ax.set(xticks=range(len(a)), xticklabels=[f"{v:.3g}" for v in a], yticks=range(len(b)),
                   yticklabels=[f"{v:.3g}" for v in b], xlabel=names[0], ylabel=names[1],
                   title=f"h{j + 1}: steady stroke [um] (failed runs blank)")
            same = uniform_value(stroke)
            if same is None:
                im = ax.imshow(stroke.T, origin="lower", aspect="auto", cmap="viridis")
                fig.colorbar(im, ax=ax).ax.ticklabel_format(useOffset=False)
            else:
                # a colour scale would draw the integrator's noise on an offset axis
                ax.set(xlim=(-0.5, len(a) - 0.5), ylim=(-0.5, len(b) - 0.5))
                ax.text(0.5, 0.5, f"no variation over the grid\n(beyond the solver's tolerance):\n{same:.6g} um everywhere", ha="center",
                        va="center", transform=ax.transAxes)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


# --------------------------------------------------------------------------------------------
# the command line


def parse_values(spec: str) -> tuple[str, list[float]]:
    """NAME=LO:HI:N (N values from LO to HI) or NAME=V1,V2,..."""
    name, _, values = spec.partition("=")
    if not values:
        raise argparse.ArgumentTypeError(f"--param {spec}: expected NAME=LO:HI:N or NAME=V1,V2,...")
    try:
        if ":" in values:
            lo, hi, n = values.split(":")
            return name.strip(), [float(v) for v in np.linspace(float(lo), float(hi), int(n))]
        return name.strip(), [float(v) for v in values.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"--param {spec}: expected NAME=LO:HI:N or NAME=V1,V2,...") from None


def grid_sets(axes_values: dict[str, list], base: dict | None = None) -> list[dict]:
    names = list(axes_values)
    return [{**(base or {}), **dict(zip(names, combo))} for combo in itertools.product(*axes_values.values())]


def varied_names(params_list: list[dict]) -> list[str]:
    """The parameters whose value is not the same in every set."""
    names = sorted({k for p in params_list for k in p})
    return [k for k in names if len({repr(p.get(k)) for p in params_list}) > 1]


def make_client(scheduler: str | None, workers: int, threads: int):
    """A client of the cluster at `scheduler`, or of a new LocalCluster of `workers` processes."""
    from distributed import Client, LocalCluster

    if scheduler:
        client = Client(scheduler)
        client.upload_file(__file__)  # this module, importable on every worker
        return client, None
    cluster = LocalCluster(n_workers=workers, threads_per_worker=threads, processes=True,
                           dashboard_address=None)
    return Client(cluster), cluster


def main(argv=None):
    ap = argparse.ArgumentParser(prog="hasel_studies", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="study", required=True)
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("--fmu", default="fmu/HaselPlatform.fmu")
    common.add_argument("--out", default="out/study", help="output folder")
    common.add_argument("--t-end", type=float, default=None, help="end time [s] (default 10, or the input file's end)")
    common.add_argument("--dt", type=float, default=1e-3, help="communication step [s]")
    common.add_argument("--sine", default="60,9.42477796076938", metavar="U0,OMEGA",
                        help="the paper's excitation (default 60 V at 3 pi rad/s)")
    common.add_argument("--input", metavar="FILE.csv", help="sampled voltages t,U1,U2,U3 (held); measured "
                        "output columns are drawn under the bands")
    common.add_argument("--backend", choices=("dask", "local", "serial"), default="dask")
    common.add_argument("--scheduler", metavar="ADDRESS", help="an existing Dask scheduler (default: a LocalCluster)")
    common.add_argument("--workers", type=int, default=2, help="LocalCluster worker processes")
    common.add_argument("--threads-per-worker", type=int, default=1)
    common.add_argument("--batch", type=int, default=1, help="runs per Dask task")
    mc = sub.add_parser("montecarlo", parents=[common], help="draws from an identification's covariance")
    mc.add_argument("--identification", required=True, metavar="DIR/identification.json")
    mc.add_argument("--samples", type=int, default=100)
    mc.add_argument("--seed", type=int, default=1)
    gr = sub.add_parser("grid", parents=[common], help="full-factorial sweep of named parameters")
    gr.add_argument("--param", action="append", type=parse_values, required=True, metavar="NAME=LO:HI:N")
    rn = sub.add_parser("run", parents=[common], help="the parameter sets of a CSV")
    rn.add_argument("--params-csv", required=True, metavar="FILE.csv")
    a = ap.parse_args(argv)

    if a.input:
        inputs = from_csv(a.input, a.t_end, a.dt)
        table = read_csv(a.input)
        data = table if any(o in table for o in OUTPUTS) else None
    else:
        u0, omega = (float(v) for v in a.sine.split(","))
        inputs, data = sine(u0, omega, a.t_end or 10.0, a.dt), None
    if a.study == "montecarlo":
        params_list = read_posterior(a.identification).draw(a.samples, a.seed)
    elif a.study == "grid":
        axes_values = dict(a.param)
        params_list = grid_sets(axes_values)
    else:
        table = read_csv(a.params_csv)
        cols = [c for c in table if c not in ("sample", "failed")]
        params_list = [{c: float(table[c][i]) for c in cols} for i in range(len(table[cols[0]]))]

    client = cluster = None
    if a.backend == "dask":
        client, cluster = make_client(a.scheduler, a.workers, a.threads_per_worker)
    try:
        result = run_study(a.fmu, params_list, inputs, a.backend, client, a.batch)
    finally:
        if client is not None:
            client.close()
        if cluster is not None:
            cluster.close()
    out = pathlib.Path(a.out)
    result.write(out)
    runs = len(params_list)
    print(f"{runs} runs of {inputs.steps * inputs.dt:g} s ({inputs.steps} steps of {inputs.dt:g} s) on "
          f"{a.backend}: {result.seconds:.2f} s, {runs / result.seconds:.1f} runs/s; "
          f"{runs - int(result.ok.sum())} failed")
    varying = varied_names(params_list)
    for f in result.failures:
        shown = {k: v for k, v in f["params"].items() if k in varying}
        print(f"  run {f['index']} failed: {f['error']} (parameters {shown})")
    written = ["outputs.csv", "runs.csv"]
    if a.study == "montecarlo" and result.ok.any():
        write_bands(result, out / "bands.csv")
        plot_bands(result, out / "bands.png", data, f"{runs} draws from {a.identification}")
        written += ["bands.csv", "bands.png"]
    if a.study == "grid":
        plot_grid(result, axes_values, out / "grid.png")
        written.append("grid.png")
    print(f"wrote {', '.join(str(out / w) for w in written)}")
    return result


if __name__ == "__main__":
    # imported under its own name, so that Dask sends workers a reference to this module's
    # functions (and its per-process cache) rather than copies of __main__
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
    import hasel_studies

    hasel_studies.main()
