"""The FMI 3.0 FMU's C API under misuse, called through ctypes exactly as a C importer would:
wrong states, NULL pointers, unknown references, sizes that do not match, NaN, the types the FMU
has no variables of, corrupted serialized states, in Co-Simulation and Model Exchange. Each call must return the right status and
log the reason through the importer's callback (with a non-NULL category); the pytest process
surviving is the check that nothing crashes. References and the token come from the packed
modelDescription.xml."""
import ctypes as C
import math
import zipfile

import pytest
from fmpy import read_model_description

OK, WARNING, DISCARD, ERROR, FATAL = 0, 1, 2, 3, 4

# fmi3LogMessageCallback(instanceEnvironment, status, category, message): not variadic
LOG = C.CFUNCTYPE(None, C.c_void_p, C.c_int, C.c_char_p, C.c_char_p)
vp, d, sz, b = C.c_void_p, C.c_double, C.c_size_t, C.c_bool
uintp, dblp, boolp = C.POINTER(C.c_uint), C.POINTER(C.c_double), C.POINTER(C.c_bool)


class Log:
    def __init__(self):
        self.records = []
        self.callback = LOG(lambda env, status, category, message: self.records.append(
            (status, category, message.decode() if message is not None else None)))

    def expect(self, status, *needles):
        for st, category, text in self.records:
            if st == status and text is not None and all(n in text for n in needles):
                assert category is not None and category.startswith(b"log"), category
                return text
        raise AssertionError(f"no status-{status} message containing {needles}; got {self.records}")


SIGNATURES = {
    "InstantiateCoSimulation": (vp, [C.c_char_p, C.c_char_p, C.c_char_p, b, b, b, b, uintp, sz, vp, LOG, vp]),
    "InstantiateModelExchange": (vp, [C.c_char_p, C.c_char_p, C.c_char_p, b, b, vp, LOG]),
    "FreeInstance": (None, [vp]),
    "EnterInitializationMode": (C.c_int, [vp, b, d, d, b, d]),
    "ExitInitializationMode": (C.c_int, [vp]),
    "EnterStepMode": (C.c_int, [vp]),
    "Terminate": (C.c_int, [vp]),
    "Reset": (C.c_int, [vp]),
    "GetFloat64": (C.c_int, [vp, uintp, sz, dblp, sz]),
    "SetFloat64": (C.c_int, [vp, uintp, sz, dblp, sz]),
    "GetInt32": (C.c_int, [vp, uintp, sz, C.POINTER(C.c_int32), sz]),
    "SetBoolean": (C.c_int, [vp, uintp, sz, boolp, sz]),
    "GetFloat32": (C.c_int, [vp, uintp, sz, C.POINTER(C.c_float), sz]),
    "DoStep": (C.c_int, [vp, d, d, b, boolp, boolp, boolp, dblp]),
    "GetContinuousStates": (C.c_int, [vp, dblp, sz]),
    "GetFMUState": (C.c_int, [vp, C.POINTER(vp)]),
    "SetFMUState": (C.c_int, [vp, vp]),
    "FreeFMUState": (C.c_int, [vp, C.POINTER(vp)]),
    "SerializedFMUStateSize": (C.c_int, [vp, vp, C.POINTER(sz)]),
    "SerializeFMUState": (C.c_int, [vp, vp, C.c_char_p, sz]),
    "DeserializeFMUState": (C.c_int, [vp, C.c_char_p, sz, C.POINTER(vp)]),
    "GetAdjointDerivative": (C.c_int, [vp, uintp, sz, uintp, sz, dblp, sz, dblp, sz]),
    "GetDirectionalDerivative": (C.c_int, [vp, uintp, sz, uintp, sz, dblp, sz, dblp, sz]),
    "GetNumberOfContinuousStates": (C.c_int, [vp, C.POINTER(sz)]),
    "EnterContinuousTimeMode": (C.c_int, [vp]),
    "SetContinuousStates": (C.c_int, [vp, dblp, sz]),
    "GetContinuousStateDerivatives": (C.c_int, [vp, dblp, sz]),
    "SetTime": (C.c_int, [vp, d]),
}


@pytest.fixture(scope="module", params=["fmu3_path", "reduced_fmu3_path"])
def fmu(request, tmp_path_factory):
    """The platform's FMI 3.0 FMU and its slow model's, extracted once."""
    path = request.getfixturevalue(request.param)
    root = tmp_path_factory.mktemp("fmu3")
    with zipfile.ZipFile(path) as z:
        z.extractall(root)
    md = read_model_description(path)
    identifier = md.coSimulation.modelIdentifier
    lib = C.CDLL(str(root / "binaries" / "x86_64-linux" / f"{identifier}.so"))

    class F:
        pass

    f = F()
    for name, (restype, argtypes) in SIGNATURES.items():
        fn = getattr(lib, "fmi3" + name)
        fn.restype, fn.argtypes = restype, argtypes
        setattr(f, name, fn)
    f.token = md.instantiationToken.encode()
    f.resources = str(root / "resources") + "/"
    f.vr = {v.name: v.valueReference for v in md.modelVariables}
    f.nx = len(md.derivatives)
    return f


class Instance:
    def __init__(self, fmu, token=None, event_mode_used=False):
        self.fmu, self.log, self.t = fmu, Log(), 0.0
        self.c = fmu.InstantiateCoSimulation(b"misuse", token or fmu.token, fmu.resources.encode(), False, False,
                                             event_mode_used, False, None, 0, None, self.log.callback, None)

    def init(self):
        assert self.fmu.EnterInitializationMode(self.c, False, 0.0, 0.0, False, 0.0) == OK
        assert self.fmu.ExitInitializationMode(self.c) == OK

    def vrs(self, *names):
        return (C.c_uint * len(names))(*(self.fmu.vr[n] for n in names))

    def get(self, *names):
        out = (C.c_double * len(names))()
        return self.fmu.GetFloat64(self.c, self.vrs(*names), len(names), out, len(names)), list(out)

    def set(self, name, value):
        return self.fmu.SetFloat64(self.c, self.vrs(name), 1, (C.c_double * 1)(value), 1)

    def step(self, h=1e-3, tc=None):
        flags, last = [C.c_bool(True) for _ in range(3)], C.c_double(math.nan)
        status = self.fmu.DoStep(self.c, self.t if tc is None else tc, h, True, *map(C.byref, flags), C.byref(last))
        if status == OK:
            self.t += h
            assert not any(f.value for f in flags) and last.value == pytest.approx(self.t, abs=1e-15)
        return status


@pytest.fixture
def inst(fmu):
    i = Instance(fmu)
    assert i.c, i.log.records
    yield i
    fmu.FreeInstance(i.c)


def test_a_wrong_token_gives_no_instance(fmu):
    bad = Instance(fmu, token=b"{0}")
    assert not bad.c
    bad.log.expect(ERROR, "instantiationToken {0}", "does not match")
    log = Log()
    assert not fmu.InstantiateModelExchange(b"me", b"{1}", None, False, False, None, log.callback)
    log.expect(ERROR, "fmi3InstantiateModelExchange", "instantiationToken {1}")


def test_model_exchange_misuse(fmu):
    log = Log()
    me = fmu.InstantiateModelExchange(b"me", fmu.token, fmu.resources.encode(), False, False, None, log.callback)
    assert me
    n = C.c_size_t()
    assert fmu.GetNumberOfContinuousStates(me, C.byref(n)) == OK and n.value == fmu.nx
    x = (C.c_double * n.value)()
    assert fmu.SetContinuousStates(me, x, n.value) == ERROR  # still Instantiated
    log.expect(ERROR, "fmi3SetContinuousStates", "Instantiated")
    assert fmu.EnterInitializationMode(me, False, 0.0, 0.0, False, 0.0) == OK
    assert fmu.ExitInitializationMode(me) == OK
    assert fmu.SetContinuousStates(me, x, n.value) == ERROR  # Event Mode
    log.expect(ERROR, "fmi3SetContinuousStates", "Event Mode")
    assert fmu.EnterContinuousTimeMode(me) == OK
    assert fmu.GetContinuousStates(me, x, n.value) == OK
    assert fmu.SetContinuousStates(me, x, n.value - 1) == ERROR
    log.expect(ERROR, "fmi3SetContinuousStates", f"nContinuousStates = {n.value - 1}")
    assert fmu.SetContinuousStates(me, None, n.value) == ERROR
    log.expect(ERROR, "fmi3SetContinuousStates", "NULL")
    saved = list(x)
    x[3] = math.nan
    assert fmu.SetContinuousStates(me, x, n.value) == ERROR
    log.expect(ERROR, "continuousStates[3]", "NaN")
    assert fmu.SetTime(me, math.nan) == ERROR
    log.expect(ERROR, "fmi3SetTime", "not finite")
    dx = (C.c_double * n.value)()
    assert fmu.GetContinuousStateDerivatives(me, dx, n.value + 1) == ERROR
    log.expect(ERROR, "fmi3GetContinuousStateDerivatives", f"{n.value} continuous states")
    assert fmu.GetContinuousStateDerivatives(me, dx, n.value) == OK
    assert all(math.isfinite(v) for v in dx)
    assert fmu.GetContinuousStates(me, x, n.value) == OK and list(x) == saved
    flags = [C.c_bool() for _ in range(3)]
    assert fmu.DoStep(me, 0.0, 1e-3, True, *map(C.byref, flags), C.byref(C.c_double())) == ERROR
    log.expect(ERROR, "fmi3DoStep", "Continuous-Time Mode")
    vr = {k: v for k, v in fmu.vr.items()}
    unknowns, knowns = (C.c_uint * 1)(vr["der(theta_1)"]), (C.c_uint * 2)(vr["theta_1"], vr["U1"])
    out = (C.c_double * 1)()
    assert fmu.GetDirectionalDerivative(me, unknowns, 1, knowns, 2, (C.c_double * 1)(1.0), 1, out, 1) == ERROR
    log.expect(ERROR, "fmi3GetDirectionalDerivative", "nSeed = 1 must equal nKnowns = 2")
    assert fmu.GetDirectionalDerivative(me, unknowns, 1, knowns, 2, (C.c_double * 2)(math.nan, 0), 2, out, 1) == ERROR
    log.expect(ERROR, "fmi3GetDirectionalDerivative", "seed[0] = NaN")
    assert fmu.GetDirectionalDerivative(me, knowns, 1, knowns, 2, (C.c_double * 2)(1, 0), 2, out, 1) == ERROR
    log.expect(ERROR, "theta_1", "neither a state derivative nor an output")
    assert fmu.GetDirectionalDerivative(me, unknowns, 1, knowns, 2, (C.c_double * 2)(1, 0), 2, out, 1) == OK
    fmu.FreeInstance(me)


def test_calls_in_the_wrong_state(inst):
    assert inst.step() == ERROR
    inst.log.expect(ERROR, "fmi3DoStep", "Instantiated")
    assert inst.get("h1")[0] == ERROR
    assert inst.fmu.EnterStepMode(inst.c) == ERROR
    inst.log.expect(ERROR, "fmi3EnterStepMode", "Instantiated")
    inst.init()
    assert inst.set("Kb_1", 0.6) == ERROR
    inst.log.expect(ERROR, "Kb_1", "Step Mode")
    assert inst.get("Kb_1") == (OK, [0.305])
    assert inst.fmu.GetContinuousStates(inst.c, (C.c_double * 15)(), 15) == ERROR
    inst.log.expect(ERROR, "fmi3GetContinuousStates", "Model Exchange")
    assert inst.step() == OK
    assert inst.fmu.Terminate(inst.c) == OK
    assert inst.fmu.Terminate(inst.c) == ERROR
    inst.log.expect(ERROR, "fmi3Terminate", "Terminated")
    assert inst.step() == ERROR
    assert inst.fmu.Reset(inst.c) == OK
    inst.t = 0.0
    inst.init()
    assert inst.step() == OK


def test_nulls_unknown_references_and_sizes(inst, fmu):
    inst.init()
    out = (C.c_double * 2)()
    assert fmu.GetFloat64(inst.c, None, 2, out, 2) == ERROR
    inst.log.expect(ERROR, "fmi3GetFloat64", "valueReferences is NULL")
    assert fmu.GetFloat64(inst.c, inst.vrs("h1", "h2"), 2, None, 2) == ERROR
    inst.log.expect(ERROR, "fmi3GetFloat64", "values is NULL")
    assert fmu.GetFloat64(inst.c, inst.vrs("h1", "h2"), 2, out, 1) == ERROR
    inst.log.expect(ERROR, "fmi3GetFloat64", "nValues = 1", "need 2 values")
    assert fmu.SetFloat64(inst.c, inst.vrs("U1"), 1, (C.c_double * 3)(1, 2, 3), 3) == ERROR
    inst.log.expect(ERROR, "fmi3SetFloat64", "nValues = 3")
    assert fmu.GetFloat64(inst.c, (C.c_uint * 1)(999999), 1, out, 1) == ERROR
    inst.log.expect(ERROR, "fmi3GetFloat64", "unknown value reference 999999")
    assert fmu.GetFloat64(inst.c, None, 0, None, 0) == OK
    flags = [C.c_bool() for _ in range(3)]
    assert fmu.DoStep(inst.c, 0.0, 1e-3, True, *map(C.byref, flags), None) == ERROR
    inst.log.expect(ERROR, "fmi3DoStep", "lastSuccessfulTime is NULL")
    assert fmu.DoStep(inst.c, 0.0, 1e-3, True, None, *map(C.byref, flags[1:]), C.byref(C.c_double())) == ERROR
    inst.log.expect(ERROR, "fmi3DoStep", "eventHandlingNeeded is NULL")
    assert fmu.DoStep(None, 0.0, 1e-3, True, *map(C.byref, flags), C.byref(C.c_double())) == ERROR
    fmu.FreeInstance(None)
    assert inst.step() == OK


def test_types_without_variables_name_the_reference_and_type(inst, fmu):
    inst.init()
    assert fmu.GetInt32(inst.c, inst.vrs("U1"), 1, (C.c_int32 * 1)(), 1) == ERROR
    inst.log.expect(ERROR, "fmi3GetInt32", "is U1, a Float64", "no Int32 variables")
    assert fmu.GetFloat32(inst.c, (C.c_uint * 1)(4242), 1, (C.c_float * 1)(), 1) == ERROR
    inst.log.expect(ERROR, "fmi3GetFloat32", "unknown value reference 4242", "no Float32 variables")
    assert fmu.SetBoolean(inst.c, inst.vrs("h1"), 1, (C.c_bool * 1)(True), 1) == ERROR
    inst.log.expect(ERROR, "fmi3SetBoolean", "no Boolean variables")
    n = 1
    assert fmu.GetAdjointDerivative(inst.c, inst.vrs("h1"), n, inst.vrs("U1"), n, (C.c_double * 1)(1), n,
                                    (C.c_double * 1)(), n) == ERROR
    inst.log.expect(ERROR, "fmi3GetAdjointDerivative", "providesAdjointDerivatives", "not offered")


@pytest.mark.parametrize("value, shown", [(math.nan, "NaN"), (math.inf, "inf")])
def test_non_finite_values_and_steps(inst, value, shown):
    inst.init()
    assert inst.set("U1", 100.0) == OK
    assert inst.set("U1", value) == ERROR
    inst.log.expect(ERROR, "U1", shown)
    assert inst.get("U1") == (OK, [100.0])
    assert inst.step(h=value) == ERROR
    inst.log.expect(ERROR, "fmi3DoStep", "communicationStepSize")
    assert inst.step(tc=0.5) == ERROR
    inst.log.expect(ERROR, "fmi3DoStep", "currentCommunicationPoint = 0.5")
    assert inst.step() == OK


def serialized(inst, state):
    size = C.c_size_t()
    assert inst.fmu.SerializedFMUStateSize(inst.c, state, C.byref(size)) == OK
    buf = C.create_string_buffer(size.value)
    assert inst.fmu.SerializeFMUState(inst.c, state, buf, size.value) == OK
    return buf.raw


def test_state_round_trip_and_corrupted_bytes(inst, fmu):
    inst.init()
    assert inst.set("U2", 80.0) == OK
    for _ in range(10):
        assert inst.step() == OK
    state = C.c_void_p()
    assert fmu.GetFMUState(inst.c, C.byref(state)) == OK
    data = serialized(inst, state)
    t0, ahead = inst.t, []
    for _ in range(10):
        assert inst.step() == OK
        ahead.append(inst.get("h2")[1][0])
    restored = C.c_void_p()
    assert fmu.DeserializeFMUState(inst.c, data, len(data), C.byref(restored)) == OK
    assert fmu.SetFMUState(inst.c, restored) == OK
    inst.t, again = t0, []
    for _ in range(10):
        assert inst.step() == OK
        again.append(inst.get("h2")[1][0])
    assert again == ahead  # bit for bit
    corrupted = bytearray(data)
    corrupted[len(data) // 2] ^= 0x01
    for bad, why in [(bytes(corrupted), "corrupted"), (data[:-5], "truncated"), (b"\x00" * 40, "bad magic")]:
        out = C.c_void_p()
        assert fmu.DeserializeFMUState(inst.c, bad, len(bad), C.byref(out)) == ERROR
        inst.log.expect(ERROR, "fmi3DeserializeFMUState", why)
        assert not out.value
    assert fmu.SerializeFMUState(inst.c, state, C.create_string_buffer(3), 3) == ERROR
    inst.log.expect(ERROR, "fmi3SerializeFMUState", "too small")
    assert fmu.SetFMUState(inst.c, None) == ERROR
    inst.log.expect(ERROR, "fmi3SetFMUState", "NULL")
    for s in (state, restored):
        assert fmu.FreeFMUState(inst.c, C.byref(s)) == OK and not s.value
