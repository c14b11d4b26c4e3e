"""The FMU's C API under misuse, called through ctypes exactly as a C importer would.

Every test drives the shared library extracted from the packed FMU and checks three things: the
returned status, that the reason was logged through the importer's logger (with a non-NULL
category and, where it applies, the variable's name and value), and - implicitly - that the
pytest process survives. Value references and the GUID come from the packed modelDescription.xml.
"""
import ctypes as C
import math
import os
import pathlib
import shutil
import urllib.parse
import zipfile

import pytest
from fmpy import read_model_description

OK, WARNING, DISCARD, ERROR, FATAL = 0, 1, 2, 3, 4
MODEL_EXCHANGE, CO_SIMULATION = 0, 1
LAST_SUCCESSFUL_TIME = 2
OUTPUTS = ["h1", "h2", "h3", "tip_x", "tip_y", "tip_z"]

# fmi2CallbackLogger is variadic: (env, instanceName, status, category, message, ...). The FMU
# always calls it with the format "%s" and exactly one char* argument, so we declare the callback
# with that argument as a sixth fixed parameter. On x86-64 (System V ABI) a variadic call passes
# its arguments in the same registers as a call to a fixed-argument prototype (the caller only
# adds %al = number of vector registers used, which a fixed-argument callee ignores), so the
# string arrives in the sixth integer register where this prototype reads it.
LOGGER = C.CFUNCTYPE(None, C.c_void_p, C.c_char_p, C.c_int, C.c_char_p, C.c_char_p, C.c_char_p)


class CallbackFunctions(C.Structure):
    _fields_ = [
        ("logger", LOGGER),
        ("allocateMemory", C.c_void_p),
        ("freeMemory", C.c_void_p),
        ("stepFinished", C.c_void_p),
        ("componentEnvironment", C.c_void_p),
    ]


class EventInfo(C.Structure):
    _fields_ = [
        ("newDiscreteStatesNeeded", C.c_int),
        ("terminateSimulation", C.c_int),
        ("nominalsOfContinuousStatesChanged", C.c_int),
        ("valuesOfContinuousStatesChanged", C.c_int),
        ("nextEventTimeDefined", C.c_int),
        ("nextEventTime", C.c_double),
    ]


class Log:
    """The logger callback and what it received: (env, instanceName, status, category, format, text)."""

    def __init__(self):
        self.records = []
        self.callback = LOGGER(self._log)

    def _log(self, env, name, status, category, fmt, arg):
        self.records.append((env, name, status, category, fmt, arg.decode() if arg is not None else None))

    def clear(self):
        self.records.clear()

    def expect(self, status, *needles):
        """Asserts that a message of `status` containing all `needles` was logged; returns its text."""
        for env, name, st, category, fmt, text in self.records:
            if st == status and text is not None and all(n in text for n in needles):
                assert category is not None and category.startswith(b"log"), category
                assert fmt == b"%s"
                return text
        raise AssertionError(f"no status-{status} message containing {needles}; got {self.records}")


class Api:
    """ctypes prototypes of the fmi2 functions used here."""

    def __init__(self, so_path):
        self.lib = lib = C.CDLL(str(so_path))
        vp, d, i, sz = C.c_void_p, C.c_double, C.c_int, C.c_size_t
        uintp, dblp = C.POINTER(C.c_uint), C.POINTER(C.c_double)
        sig = {
            "fmi2Instantiate": (vp, [C.c_char_p, i, C.c_char_p, C.c_char_p, C.POINTER(CallbackFunctions), i, i]),
            "fmi2FreeInstance": (None, [vp]),
            "fmi2SetupExperiment": (i, [vp, i, d, d, i, d]),
            "fmi2EnterInitializationMode": (i, [vp]),
            "fmi2ExitInitializationMode": (i, [vp]),
            "fmi2Terminate": (i, [vp]),
            "fmi2GetReal": (i, [vp, uintp, sz, dblp]),
            "fmi2SetReal": (i, [vp, uintp, sz, dblp]),
            "fmi2GetInteger": (i, [vp, uintp, sz, C.POINTER(C.c_int)]),
            "fmi2DoStep": (i, [vp, d, d, i]),
            "fmi2GetRealStatus": (i, [vp, i, dblp]),
            "fmi2GetFMUstate": (i, [vp, C.POINTER(vp)]),
            "fmi2SetFMUstate": (i, [vp, vp]),
            "fmi2FreeFMUstate": (i, [vp, C.POINTER(vp)]),
            "fmi2SerializedFMUstateSize": (i, [vp, vp, C.POINTER(sz)]),
            "fmi2SerializeFMUstate": (i, [vp, vp, C.c_char_p, sz]),
            "fmi2DeSerializeFMUstate": (i, [vp, C.c_char_p, sz, C.POINTER(vp)]),
            "fmi2SetTime": (i, [vp, d]),
            "fmi2SetContinuousStates": (i, [vp, dblp, sz]),
            "fmi2GetContinuousStates": (i, [vp, dblp, sz]),
            "fmi2GetDerivatives": (i, [vp, dblp, sz]),
            "fmi2GetNominalsOfContinuousStates": (i, [vp, dblp, sz]),
            "fmi2GetEventIndicators": (i, [vp, dblp, sz]),
            "fmi2EnterEventMode": (i, [vp]),
            "fmi2EnterContinuousTimeMode": (i, [vp]),
            "fmi2NewDiscreteStates": (i, [vp, C.POINTER(EventInfo)]),
            "fmi2CompletedIntegratorStep": (i, [vp, i, C.POINTER(i), C.POINTER(i)]),
            "fmi2GetDirectionalDerivative": (i, [vp, uintp, sz, uintp, sz, dblp, dblp]),
        }
        for name, (restype, argtypes) in sig.items():
            f = getattr(lib, name)
            f.restype, f.argtypes = restype, argtypes
            setattr(self, name[4:], f)


@pytest.fixture(scope="module", params=["fmu_path", "reduced_fmu_path"])
def fmu(request, tmp_path_factory):
    """The FMU extracted once, the platform's and its slow model's: its directory, ctypes API,
    GUID and value references by name."""
    path = request.getfixturevalue(request.param)
    root = tmp_path_factory.mktemp("fmu")
    with zipfile.ZipFile(path) as z:
        z.extractall(root)
    md = read_model_description(path)
    so = root / "binaries" / "linux64" / f"{md.coSimulation.modelIdentifier}.so"

    class F:
        pass

    f = F()
    f.dir, f.api, f.guid = root, Api(so), md.guid.encode()
    f.vr = {v.name: v.valueReference for v in md.modelVariables}
    f.nx = len(md.derivatives)
    f.states = [d.variable.derivative.name for d in md.derivatives]
    # the slow model (HaselPlatformReduced) has no charges a command can drive out of reach
    f.reduced = md.coSimulation.modelIdentifier == "HaselPlatformReduced"
    f.uri = (root / "resources").as_uri().encode()
    return f


class Slave:
    """One instance with its own logger, plus small helpers."""

    def __init__(self, fmu, name=b"misuse", guid=None, uri=None, fmu_type=CO_SIMULATION, env=None,
                 with_logger=True, visible=0, logging_on=0, resource_location=...):
        self.fmu, self.api, self.log = fmu, fmu.api, Log()
        self.callbacks = CallbackFunctions(self.log.callback if with_logger else LOGGER(), None, None, None, env)
        location = fmu.uri if resource_location is ... else resource_location
        self.c = self.api.Instantiate(name, fmu_type, fmu.guid if guid is None else guid, location,
                                      C.byref(self.callbacks), visible, logging_on)

    def free(self):
        self.api.FreeInstance(self.c)
        self.c = None

    def set(self, name, value):
        return self.api.SetReal(self.c, (C.c_uint * 1)(self.fmu.vr[name]), 1, (C.c_double * 1)(value))

    def get(self, *names):
        vrs = (C.c_uint * len(names))(*(self.fmu.vr[n] for n in names))
        out = (C.c_double * len(names))()
        status = self.api.GetReal(self.c, vrs, len(names), out)
        return status, list(out)

    def init(self, start=0.0):
        assert self.api.SetupExperiment(self.c, 0, 0.0, start, 0, 0.0) == OK
        assert self.api.EnterInitializationMode(self.c) == OK
        assert self.api.ExitInitializationMode(self.c) == OK
        self.t = start

    def step(self, h=1e-3):
        status = self.api.DoStep(self.c, self.t, h, 1)
        if status == OK:
            self.t += h
        return status

    def outputs(self):
        status, y = self.get(*OUTPUTS)
        assert status == OK
        return y


@pytest.fixture
def slave(fmu):
    s = Slave(fmu)
    assert s.c, s.log.records
    yield s
    s.free()


def sine(t):
    return 250.0 + 150.0 * math.sin(2 * math.pi * 3 * t)


# --- the state machine ---------------------------------------------------------------------------

def test_do_step_before_initialization_is_an_error(slave):
    """fmi2DoStep in state instantiated: fmi2Error naming the function and the state."""
    assert slave.api.DoStep(slave.c, 0.0, 1e-3, 1) == ERROR
    slave.log.expect(ERROR, "fmi2DoStep", "instantiated")
    slave.init()  # nothing was changed: the instance still initializes and steps
    assert slave.step() == OK


def test_enter_initialization_twice_is_an_error(slave):
    """A second fmi2EnterInitializationMode, and Exit before Enter, are fmi2Error with a log."""
    assert slave.api.ExitInitializationMode(slave.c) == ERROR
    slave.log.expect(ERROR, "fmi2ExitInitializationMode", "instantiated")
    assert slave.api.SetupExperiment(slave.c, 0, 0.0, 0.0, 0, 0.0) == OK
    assert slave.api.EnterInitializationMode(slave.c) == OK
    slave.log.clear()
    assert slave.api.EnterInitializationMode(slave.c) == ERROR
    slave.log.expect(ERROR, "fmi2EnterInitializationMode", "initializationMode")
    assert slave.api.ExitInitializationMode(slave.c) == OK


def test_enter_initialization_without_setup_experiment_is_an_error(slave):
    """fmi2EnterInitializationMode needs fmi2SetupExperiment first (FMI 2.0 section 2.1.6)."""
    assert slave.api.EnterInitializationMode(slave.c) == ERROR
    slave.log.expect(ERROR, "fmi2EnterInitializationMode", "fmi2SetupExperiment")


def test_fixed_parameter_cannot_be_set_after_initialization(slave):
    """Kb_1 (fixed) set in stepComplete: fmi2Error naming Kb_1 and the state; the value stays."""
    slave.init()
    assert slave.set("Kb_1", 0.6) == ERROR
    slave.log.expect(ERROR, "Kb_1", "stepComplete")
    assert slave.get("Kb_1") == (OK, [0.305])


def test_do_step_at_the_wrong_time_is_an_error(slave):
    """A currentCommunicationPoint that skips ahead is rejected with both times in the message."""
    slave.init()
    assert slave.api.DoStep(slave.c, 0.5, 1e-3, 1) == ERROR
    slave.log.expect(ERROR, "fmi2DoStep", "0.5")
    assert slave.step() == OK


def test_terminate_twice_and_get_after_terminate(slave):
    """Terminate twice is fmi2Error with a log; Get after Terminate returns the last values; DoStep is refused."""
    slave.init()
    for _ in range(5):
        assert slave.step() == OK
    before = slave.outputs()
    assert slave.api.Terminate(slave.c) == OK
    assert slave.api.Terminate(slave.c) == ERROR
    slave.log.expect(ERROR, "fmi2Terminate", "terminated")
    assert slave.outputs() == before
    assert slave.api.DoStep(slave.c, slave.t, 1e-3, 1) == ERROR
    slave.log.expect(ERROR, "fmi2DoStep", "terminated")


# --- NULL pointers and unknown references --------------------------------------------------------

def test_null_arrays_are_errors(slave):
    """NULL vr or value arrays with nvr > 0 are fmi2Error naming the argument; nvr = 0 with NULLs is fine."""
    slave.init()
    vals = (C.c_double * 2)(1.0, 2.0)
    vrs = (C.c_uint * 2)(slave.fmu.vr["U1"], slave.fmu.vr["U2"])
    assert slave.api.SetReal(slave.c, None, 2, vals) == ERROR
    slave.log.expect(ERROR, "fmi2SetReal", "vr", "NULL")
    assert slave.api.SetReal(slave.c, vrs, 2, None) == ERROR
    slave.log.expect(ERROR, "fmi2SetReal", "value", "NULL")
    assert slave.api.GetReal(slave.c, None, 2, vals) == ERROR
    slave.log.expect(ERROR, "fmi2GetReal", "vr", "NULL")
    assert slave.api.GetReal(slave.c, vrs, 2, None) == ERROR
    slave.log.expect(ERROR, "fmi2GetReal", "value", "NULL")
    n_errors = len(slave.log.records)
    assert slave.api.GetReal(slave.c, None, 0, None) == OK
    assert slave.api.SetReal(slave.c, None, 0, None) == OK
    assert len(slave.log.records) == n_errors
    assert slave.get("U1", "U2") == (OK, [0.0, 0.0])  # the rejected SetReal changed nothing


def test_null_component_and_free_null(fmu):
    """Calls on a NULL component return fmi2Error (no logger to tell); fmi2FreeInstance(NULL) is a no-op."""
    api = fmu.api
    fmu.api.FreeInstance(None)
    assert api.DoStep(None, 0.0, 1e-3, 1) == ERROR
    assert api.Terminate(None) == ERROR
    assert api.EnterInitializationMode(None) == ERROR
    out = (C.c_double * 1)()
    assert api.GetReal(None, (C.c_uint * 1)(0), 1, out) == ERROR
    state = C.c_void_p()
    assert api.GetFMUstate(None, C.byref(state)) == ERROR and not state.value


def test_unknown_value_references(slave):
    """An unknown value reference is fmi2Error naming it, for Get and Set, and for the absent Integer type."""
    vrs = (C.c_uint * 2)(slave.fmu.vr["U1"], 9999)
    vals = (C.c_double * 2)(7.0, 8.0)
    assert slave.api.SetReal(slave.c, vrs, 2, vals) == ERROR
    slave.log.expect(ERROR, "fmi2SetReal", "9999")
    slave.init()
    assert slave.get("U1") == (OK, [0.0])  # checked before anything was set
    assert slave.api.GetReal(slave.c, vrs, 2, vals) == ERROR
    slave.log.expect(ERROR, "fmi2GetReal", "9999")
    ints = (C.c_int * 1)()
    assert slave.api.GetInteger(slave.c, (C.c_uint * 1)(0), 1, ints) == ERROR
    slave.log.expect(ERROR, "fmi2GetInteger", "Integer")


# --- bad values ----------------------------------------------------------------------------------

def test_negative_capacitance_is_rejected(slave):
    """C1_2 = -1e-9 F: fmi2Error naming C1_2 and the value; the start value is kept, not clamped."""
    assert slave.set("C1_2", -1e-9) == ERROR
    slave.log.expect(ERROR, "C1_2", "-1e-9")
    assert slave.api.SetupExperiment(slave.c, 0, 0.0, 0.0, 0, 0.0) == OK
    assert slave.api.EnterInitializationMode(slave.c) == OK
    assert slave.get("C1_2") == (OK, [2e-10])


def test_lp_below_lv_fails_at_exit_initialization(slave):
    """Lp = 1 mm < Lv = 12 mm leaves the asin domain: Exit is fmi2Error naming Lp, its value and Lv."""
    assert slave.set("Lp", 1e-3) == OK  # a single value is fine; the relation is checked at Exit
    assert slave.api.SetupExperiment(slave.c, 0, 0.0, 0.0, 0, 0.0) == OK
    assert slave.api.EnterInitializationMode(slave.c) == OK
    assert slave.api.ExitInitializationMode(slave.c) == ERROR
    text = slave.log.expect(ERROR, "fmi2ExitInitializationMode", "Lp", "1e-3")
    assert "Lv" in text
    assert slave.api.DoStep(slave.c, 0.0, 1e-3, 1) == ERROR  # never got to stepComplete


@pytest.mark.parametrize("value, shown", [(math.nan, "NaN"), (math.inf, "inf"), (-math.inf, "-inf")])
def test_non_finite_input_is_rejected(slave, value, shown):
    """A NaN or infinite U1 is fmi2Error naming U1 and the value; U1 keeps its last value and stepping goes on."""
    slave.init()
    assert slave.set("U1", 100.0) == OK
    assert slave.set("U1", value) == ERROR
    slave.log.expect(ERROR, "U1", shown)
    assert slave.get("U1") == (OK, [100.0])
    assert slave.step() == OK
    assert all(math.isfinite(y) for y in slave.outputs())


# --- a failing solver, FMU states ----------------------------------------------------------------

def run_clean(fmu, n_steps, u_of_t):
    """Outputs after each of n_steps 1 ms steps of a fresh instance with U1 = U2 = U3 = u_of_t(t)."""
    s = Slave(fmu)
    s.init()
    rows = []
    for k in range(n_steps):
        for u in ("U1", "U2", "U3"):
            assert s.set(u, u_of_t(k * 1e-3)) == OK
        assert s.step() == OK
        rows.append(s.outputs())
    s.free()
    return rows


def test_failing_solver_discards_and_a_restored_state_replays(fmu, slave):
    """U1 = 1e7 V over 10 ms makes the solver give up: fmi2Discard with the reason logged,
    fmi2LastSuccessfulTime is the step's start, further steps are refused, and after
    fmi2SetFMUstate of a state saved before, the run equals a clean run bit for bit."""
    if fmu.reduced:
        pytest.skip("the slow model follows U1 = 1e7 V (its angle settles where the input gain "
                    "vanishes): no command makes its solver give up")
    slave.init()
    for k in range(50):
        for u in ("U1", "U2", "U3"):
            assert slave.set(u, sine(k * 1e-3)) == OK
        assert slave.step() == OK
    saved = C.c_void_p()
    assert slave.api.GetFMUstate(slave.c, C.byref(saved)) == OK and saved.value
    t_saved = slave.t

    assert slave.set("U1", 1e7) == OK
    status = slave.api.DoStep(slave.c, slave.t, 0.01, 1)
    assert status in (DISCARD, ERROR)
    text = slave.log.expect(status, "fmi2DoStep", "solver")
    print("solver failure logged as:", text)
    last = C.c_double(-1.0)
    assert slave.api.GetRealStatus(slave.c, LAST_SUCCESSFUL_TIME, C.byref(last)) == OK
    assert last.value == t_saved
    assert slave.api.DoStep(slave.c, t_saved, 1e-3, 1) == ERROR  # stepFailed: no more steps
    slave.log.expect(ERROR, "fmi2DoStep", "stepFailed")

    assert slave.api.SetFMUstate(slave.c, saved) == OK
    rows = []
    for k in range(50, 100):
        for u in ("U1", "U2", "U3"):
            assert slave.set(u, sine(k * 1e-3)) == OK
        assert slave.step() == OK
        rows.append(slave.outputs())
    assert slave.api.FreeFMUstate(slave.c, C.byref(saved)) == OK and not saved.value
    assert rows == run_clean(fmu, 100, sine)[50:]


def test_serialized_state_replays_in_a_second_instance(fmu):
    """A state serialized after 200 sine-driven 1 ms steps, deserialized into a fresh instance,
    makes both instances produce bit-identical h1..tip_z over the next 200 steps."""
    a, b = Slave(fmu, name=b"a"), Slave(fmu, name=b"b")
    a.init()
    for k in range(200):
        for u in ("U1", "U2", "U3"):
            assert a.set(u, sine(k * 1e-3)) == OK
        assert a.step() == OK
    state = C.c_void_p()
    assert a.api.GetFMUstate(a.c, C.byref(state)) == OK
    size = C.c_size_t()
    assert a.api.SerializedFMUstateSize(a.c, state, C.byref(size)) == OK and size.value > 0
    buf = C.create_string_buffer(size.value)
    assert a.api.SerializeFMUstate(a.c, state, buf, size.value) == OK
    assert a.api.SerializeFMUstate(a.c, state, buf, size.value - 1) == ERROR  # too small: refused
    a.log.expect(ERROR, "fmi2SerializeFMUstate", "too small")

    restored = C.c_void_p()
    assert b.api.DeSerializeFMUstate(b.c, buf.raw, size.value, C.byref(restored)) == OK
    assert b.api.SetFMUstate(b.c, restored) == OK
    b.t = a.t
    assert b.outputs() == a.outputs()
    runs = {a: [], b: []}
    for k in range(200, 400):
        for s in (a, b):
            for u in ("U1", "U2", "U3"):
                assert s.set(u, sine(k * 1e-3)) == OK
            assert s.step() == OK
            runs[s].append(s.outputs())
    assert runs[a] == runs[b]
    assert runs[a] == run_clean(fmu, 400, sine)[200:]

    corrupted = bytearray(buf.raw)
    corrupted[len(corrupted) // 2] ^= 0xFF
    other = C.c_void_p()
    assert b.api.DeSerializeFMUstate(b.c, bytes(corrupted), size.value, C.byref(other)) == ERROR
    b.log.expect(ERROR, "fmi2DeSerializeFMUstate")
    for s, st in ((a, state), (b, restored)):
        assert s.api.FreeFMUstate(s.c, C.byref(st)) == OK
        s.free()


# --- fmi2Instantiate arguments -------------------------------------------------------------------

def test_guid_mismatch_gives_null_with_a_log(fmu):
    """A wrong GUID: NULL, and the message names both GUIDs."""
    s = Slave(fmu, guid=b"{00000000-0000-0000-0000-000000000000}")
    assert not s.c
    s.log.expect(ERROR, "fmi2Instantiate", "GUID", "{00000000-0000-0000-0000-000000000000}", fmu.guid.decode())


def test_unknown_fmu_type_gives_null_with_a_log(fmu):
    """fmuType neither fmi2ModelExchange nor fmi2CoSimulation: NULL, and the log says so."""
    s = Slave(fmu, fmu_type=2)
    assert not s.c
    s.log.expect(ERROR, "fmi2Instantiate", "fmuType = 2 is neither")


def test_null_instance_name_gives_null_with_a_log(fmu):
    """instanceName = NULL: NULL, with a log message."""
    s = Slave(fmu, name=None)
    assert not s.c
    s.log.expect(ERROR, "fmi2Instantiate", "instanceName")


@pytest.fixture(scope="module")
def spaced_copy(fmu, tmp_path_factory):
    """The extracted FMU copied to a directory whose name holds a space and a non-ASCII letter."""
    target = tmp_path_factory.mktemp("uri") / "Hasel platform é"
    shutil.copytree(fmu.dir, target)
    return target


@pytest.mark.parametrize("form", ["file:///", "file:/", "file://localhost/"])
def test_resource_uri_forms_with_percent_encoding(fmu, spaced_copy, form):
    """file:///abs, file:/abs and file://localhost/abs with %20 and UTF-8 escapes name the copied
    resources folder: the debug trace shows the decoded path, and a tampered parameters.toml there
    is really read (the GUID, computed from the start values, no longer matches)."""
    resources = spaced_copy / "resources"
    uri = (form + urllib.parse.quote(str(resources).lstrip("/"))).encode()
    assert b"%20" in uri and b"%C3%A9" in uri
    s = Slave(fmu, resource_location=uri, logging_on=1)
    assert s.c, s.log.records
    s.log.expect(OK, "resources: " + str(resources))
    s.init()
    assert s.step() == OK
    s.free()

    tampered = spaced_copy.parent / "tampered copy"
    if not tampered.exists():
        shutil.copytree(spaced_copy, tampered)
        toml = tampered / "resources" / "parameters.toml"
        toml.write_text(toml.read_text().replace("Kb_2 = 0.3 ", "Kb_2 = 0.6 "))
        assert "Kb_2 = 0.6 " in toml.read_text()
    uri = (form + urllib.parse.quote(str(tampered / "resources").lstrip("/"))).encode()
    s = Slave(fmu, resource_location=uri)
    assert not s.c
    s.log.expect(ERROR, "fmi2Instantiate", "GUID")


def test_null_resource_location_uses_the_built_in_defaults(fmu):
    """fmuResourceLocation = NULL: the instance works with the default parameters."""
    s = Slave(fmu, resource_location=None)
    assert s.c, s.log.records
    s.init()
    assert s.step() == OK
    assert s.get("Kb_1") == (OK, [0.305])
    s.free()


def test_visible_and_logging_on(fmu):
    """visible = 1, loggingOn = 1 is accepted and turns on OK-level call traces (category logCalls);
    with loggingOn = 0 no OK-level message is sent."""
    for logging_on in (1, 0):
        s = Slave(fmu, visible=1, logging_on=logging_on)
        assert s.c, s.log.records
        s.init()
        assert s.step() == OK
        traces = [r for r in s.log.records if r[2] == OK]
        if logging_on:
            assert any(r[3] == b"logCalls" and "fmi2DoStep" in r[5] for r in traces), s.log.records
        else:
            assert traces == []
        s.free()


def test_component_environment_is_passed_back(fmu):
    """The logger gets componentEnvironment unchanged: NULL stays NULL, a pointer stays that pointer."""
    for env in (None, 0x5EED1234):
        s = Slave(fmu, env=env)
        assert s.c
        assert s.api.DoStep(s.c, 0.0, 1e-3, 1) == ERROR
        s.log.expect(ERROR, "fmi2DoStep")
        assert [r[0] for r in s.log.records] == [env] * len(s.log.records)
        assert all(r[1] == b"misuse" for r in s.log.records)
        s.free()


def test_null_logger_is_tolerated(fmu):
    """With logger = NULL the FMU instantiates, refuses bad calls with fmi2Error and fails a
    GUID mismatch with NULL, without calling through the NULL pointer."""
    s = Slave(fmu, with_logger=False)
    assert s.c
    assert s.api.DoStep(s.c, 0.0, 1e-3, 1) == ERROR
    assert s.set("U1", math.nan) == ERROR
    s.init()
    assert s.set("U1", 1e7) == OK
    # a failing step (see test_failing_solver_discards_and_a_restored_state_replays)
    assert s.api.DoStep(s.c, 0.0, 0.01, 1) in ((OK,) if fmu.reduced else (DISCARD, ERROR))
    s.free()
    assert not Slave(fmu, with_logger=False, guid=b"{wrong}").c


# --- resources over many instances ---------------------------------------------------------------

def rss_bytes():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def test_many_instance_cycles_do_not_grow_memory(fmu):
    """1000 instantiate/setup/enter/exit/10 steps/terminate/free cycles: RSS grows < 4 MB from cycle 100 to 1000."""
    rss = {}
    for cycle in range(1, 1001):
        s = Slave(fmu)
        assert s.c
        s.init()
        assert s.set("U1", 300.0) == OK
        for _ in range(10):
            assert s.step() == OK
        assert s.api.Terminate(s.c) == OK
        s.free()
        if cycle in (100, 1000):
            rss[cycle] = rss_bytes()
    growth = rss[1000] - rss[100]
    print(f"RSS after 100 cycles {rss[100] / 2**20:.1f} MiB, after 1000 {rss[1000] / 2**20:.1f} MiB, "
          f"growth {growth / 2**10:.0f} KiB")
    assert growth < 4 * 2**20


# --- Model Exchange ------------------------------------------------------------------------------

def doubles(n, value=0.0):
    return (C.c_double * n)(*([value] * n))


@pytest.fixture
def model(fmu):
    """A Model Exchange instance, initialized, in Event Mode."""
    s = Slave(fmu, fmu_type=MODEL_EXCHANGE)
    assert s.c, s.log.records
    s.init()
    yield s
    s.free()


def test_model_exchange_state_machine(model):
    """Each Model Exchange call outside its states is fmi2Error naming function and state; Event
    Mode after initialization, Continuous-Time Mode after fmi2EnterContinuousTimeMode."""
    api, c, nx = model.api, model.c, model.fmu.nx
    x = doubles(nx)
    assert api.SetContinuousStates(c, x, nx) == ERROR
    model.log.expect(ERROR, "fmi2SetContinuousStates", "not allowed in state eventMode")
    assert api.DoStep(c, 0.0, 1e-3, 1) == ERROR
    model.log.expect(ERROR, "fmi2DoStep", "is a Co-Simulation function")
    info = EventInfo(1, 1, 1, 1, 1, 1.0)
    assert api.NewDiscreteStates(c, C.byref(info)) == OK
    assert (info.newDiscreteStatesNeeded, info.terminateSimulation, info.nextEventTimeDefined) == (0, 0, 0)
    assert api.EnterContinuousTimeMode(c) == OK
    assert api.NewDiscreteStates(c, C.byref(info)) == ERROR
    model.log.expect(ERROR, "fmi2NewDiscreteStates", "not allowed in state continuousTimeMode")
    assert api.GetContinuousStates(c, x, nx) == OK and api.SetContinuousStates(c, x, nx) == OK
    assert model.set("Kb_1", 0.4) == ERROR
    model.log.expect(ERROR, "Kb_1", "cannot be set in state continuousTimeMode")
    assert api.EnterEventMode(c) == OK and api.Terminate(c) == OK
    assert api.SetTime(c, 0.1) == ERROR
    model.log.expect(ERROR, "fmi2SetTime", "not allowed in state terminated")


def test_model_exchange_calls_on_a_co_simulation_instance(slave):
    """fmi2SetTime, fmi2GetDerivatives, ... on a Co-Simulation instance: fmi2Error."""
    slave.init()
    nx = slave.fmu.nx
    assert slave.api.SetTime(slave.c, 0.0) == ERROR
    assert slave.api.GetDerivatives(slave.c, doubles(nx), nx) == ERROR
    slave.log.expect(ERROR, "fmi2GetDerivatives", "is a Model Exchange function", "Co-Simulation")
    assert slave.step() == OK, "still usable"


def test_model_exchange_arguments(model):
    """Wrong nx, NULL arrays, event indicators that do not exist, a NaN time, non-finite states."""
    api, c, nx = model.api, model.c, model.fmu.nx
    assert api.EnterContinuousTimeMode(c) == OK
    assert api.GetDerivatives(c, doubles(nx + 1), nx + 1) == ERROR
    model.log.expect(ERROR, "fmi2GetDerivatives", f"nx = {nx + 1}", f"has {nx} continuous states")
    assert api.GetNominalsOfContinuousStates(c, None, nx) == ERROR
    model.log.expect(ERROR, "fmi2GetNominalsOfContinuousStates", "argument x_nominal is NULL")
    assert api.GetEventIndicators(c, None, 0) == OK
    assert api.GetEventIndicators(c, doubles(1), 1) == ERROR
    model.log.expect(ERROR, "fmi2GetEventIndicators", "no event indicators")
    assert api.SetTime(c, math.nan) == ERROR
    model.log.expect(ERROR, "fmi2SetTime", "not finite")
    assert api.CompletedIntegratorStep(c, 1, None, None) == ERROR
    model.log.expect(ERROR, "fmi2CompletedIntegratorStep", "argument enterEventMode is NULL")
    x = doubles(nx)
    assert api.GetContinuousStates(c, x, nx) == OK
    x[3] = math.inf
    assert api.SetContinuousStates(c, x, nx) == ERROR
    model.log.expect(ERROR, "fmi2SetContinuousStates", model.fmu.states[3], "must be finite")


def test_model_exchange_refuses_the_transport_delay(fmu):
    """tau_d > 0 needs the command history: refused at fmi2ExitInitializationMode in Model
    Exchange, with the reason; Co-Simulation runs it."""
    for fmu_type, status in ((MODEL_EXCHANGE, ERROR), (CO_SIMULATION, OK)):
        s = Slave(fmu, fmu_type=fmu_type)
        assert s.set("tau_d", 1e-3) == OK
        assert s.api.SetupExperiment(s.c, 0, 0.0, 0.0, 0, 0.0) == OK
        assert s.api.EnterInitializationMode(s.c) == OK
        assert s.api.ExitInitializationMode(s.c) == status
        if status == ERROR:
            s.log.expect(ERROR, "fmi2ExitInitializationMode", "tau_d", "history", "Co-Simulation")
        s.free()


def test_directional_derivative_arguments(model):
    """Knowns must be states or inputs, unknowns state derivatives or outputs; NULL arrays, unknown
    references and NaN seeds are errors naming what is wrong."""
    vr = model.fmu.vr
    api, c = model.api, model.c

    def dd(unknowns, knowns, seed, out=True):
        u = (C.c_uint * len(unknowns))(*unknowns)
        k = (C.c_uint * len(knowns))(*knowns)
        result = doubles(len(unknowns)) if out else None
        return api.GetDirectionalDerivative(c, u, len(unknowns), k, len(knowns), doubles(len(knowns), seed), result)

    assert dd([vr["der(theta_1)"], vr["h1"]], [vr["theta_1"], vr["U1"]], 1.0) == OK
    assert dd([vr["der(theta_1)"]], [vr["Kb_1"]], 1.0) == ERROR
    model.log.expect(ERROR, "fmi2GetDirectionalDerivative", "known Kb_1", "is not a continuous state or an input")
    assert dd([vr["theta_1"]], [vr["U1"]], 1.0) == ERROR
    model.log.expect(ERROR, "unknown theta_1", "neither a state derivative nor an output")
    assert dd([vr["h1"]], [123456], 1.0) == ERROR
    model.log.expect(ERROR, "unknown value reference 123456")
    assert dd([vr["h1"]], [vr["U1"]], math.nan) == ERROR
    model.log.expect(ERROR, "dvKnown for U1 is NaN")
    assert dd([vr["h1"]], [vr["U1"]], 1.0, out=False) == ERROR
    model.log.expect(ERROR, "argument dvUnknown is NULL")


def test_model_exchange_state_replays_through_bytes(fmu, model):
    """An FMU state taken in Continuous-Time Mode, serialized, restored in a second Model Exchange
    instance: the same states and derivatives; a Co-Simulation instance refuses the bytes."""
    api, c, nx = model.api, model.c, model.fmu.nx
    assert api.EnterContinuousTimeMode(c) == OK
    assert model.set("U2", 80.0) == OK
    x = doubles(nx)
    assert api.GetContinuousStates(c, x, nx) == OK
    x[9] *= 1.01  # theta_2 away from rest
    assert api.SetContinuousStates(c, x, nx) == OK and api.SetTime(c, 0.25) == OK
    state = C.c_void_p()
    assert api.GetFMUstate(c, C.byref(state)) == OK
    size = C.c_size_t()
    assert api.SerializedFMUstateSize(c, state, C.byref(size)) == OK
    buf = C.create_string_buffer(size.value)
    assert api.SerializeFMUstate(c, state, buf, size) == OK
    dx = doubles(nx)
    assert api.GetDerivatives(c, dx, nx) == OK
    other = Slave(fmu, fmu_type=MODEL_EXCHANGE)
    restored = C.c_void_p()
    assert api.DeSerializeFMUstate(other.c, buf, size, C.byref(restored)) == OK
    assert api.SetFMUstate(other.c, restored) == OK
    y, dy = doubles(nx), doubles(nx)
    assert api.GetContinuousStates(other.c, y, nx) == OK and api.GetDerivatives(other.c, dy, nx) == OK
    assert list(y) == list(x) and list(dy) == list(dx) and other.get("U2") == (OK, [80.0])
    cs = Slave(fmu)
    into_cs = C.c_void_p()
    assert api.DeSerializeFMUstate(cs.c, buf, size, C.byref(into_cs)) == ERROR
    cs.log.expect(ERROR, "fmi2DeSerializeFMUstate", "ModelExchange")
    for s, st in ((model, state), (other, restored)):
        assert api.FreeFMUstate(s.c, C.byref(st)) == OK
    other.free()
    cs.free()
