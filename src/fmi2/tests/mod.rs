//! Tests of the FMI shell through the real `extern "C"` functions, generated for a toy core
//! (a first-order lag) by the same macro the FMU uses, minus the exported symbol names.

mod fmu_state;
mod lifecycle;
mod logging;
mod model_description;
mod threads;
mod values;

use std::ffi::{CStr, CString, c_char};
use std::path::Path;
use std::ptr::{null, null_mut};
use std::sync::Mutex;

use super::model_description::guid_for;
use super::types::*;
use crate::fmi_common::model_api::{
    FmuCore, InstanceKind, ModelStructure, OutputDependency, StateDerivative,
};
use crate::fmi_common::variables::{
    Causality, DefaultExperiment, Initial, ModelInfo, Variability, Variable,
};

/// y' = (u - y) / tau, solved exactly over each step with u held.
#[derive(Clone, Debug)]
pub struct LagCore {
    kind: InstanceKind,
    tau: f64,
    y_start: f64,
    max_step: f64,
    explode: f64,
    u: f64,
    y: f64,
    t: f64,
    initialized: bool,
    /// start value of tau, from `resources/tau.txt` when present
    tau_start: f64,
}

pub const TAU: u32 = 0;
pub const Y_START: u32 = 1;
pub const MAX_STEP: u32 = 2;
pub const EXPLODE: u32 = 3;
pub const U: u32 = 4;
pub const Y: u32 = 5;
pub const RATE: u32 = 6;
pub const DER_Y: u32 = 7;

fn var(
    name: &str,
    vr: u32,
    causality: Causality,
    variability: Variability,
    unit: &str,
    start: Option<f64>,
) -> Variable {
    Variable {
        name: name.into(),
        value_reference: vr,
        causality,
        variability,
        initial: None,
        unit: Some(unit.into()),
        description: format!("the {name}"),
        start,
        derivative: None,
    }
}

impl FmuCore for LagCore {
    fn model_info() -> ModelInfo {
        ModelInfo {
            model_name: "Lag".into(),
            model_identifier: "Lag".into(),
            description: "first-order lag <test> & \"quotes\"".into(),
            author: "tests".into(),
            version: "1".into(),
            generation_tool: "hasel-fmu tests".into(),
            default_experiment: DefaultExperiment {
                start_time: 0.0,
                stop_time: 10.0,
                step_size: 0.01,
                tolerance: 1e-6,
            },
            log_categories: vec![("logModel".into(), "model messages".into())],
        }
    }

    fn model_structure() -> ModelStructure {
        ModelStructure {
            derivatives: vec![StateDerivative {
                state: Y,
                derivative: DER_Y,
                dependencies: vec![U, Y],
            }],
            outputs: vec![OutputDependency {
                output: Y,
                dependencies: vec![Y],
            }],
        }
    }

    fn instantiate(kind: InstanceKind, resource_dir: Option<&Path>) -> Result<Self, String> {
        let tau_start = match resource_dir.map(|d| std::fs::read_to_string(d.join("tau.txt"))) {
            Some(Ok(text)) => text
                .trim()
                .parse()
                .map_err(|e| format!("resources/tau.txt: {e}"))?,
            _ => 1.0,
        };
        Ok(LagCore {
            kind,
            tau: tau_start,
            y_start: 0.0,
            max_step: 1.0,
            explode: 0.0,
            u: 0.0,
            y: 0.0,
            t: 0.0,
            initialized: false,
            tau_start,
        })
    }

    fn variables(&self) -> Vec<Variable> {
        use Causality::*;
        use Variability::*;
        let mut rate = var("rate", RATE, CalculatedParameter, Fixed, "Hz", None);
        rate.initial = Some(Initial::Calculated);
        let mut der_y = var("der(y)", DER_Y, Local, Continuous, "Hz", None);
        der_y.derivative = Some(Y);
        vec![
            var("tau", TAU, Parameter, Fixed, "s", Some(self.tau_start)),
            var("y_start", Y_START, Parameter, Fixed, "1", Some(0.0)),
            var("max_step", MAX_STEP, Parameter, Tunable, "s", Some(1.0)),
            var("explode", EXPLODE, Parameter, Tunable, "1", Some(0.0)),
            var("u", U, Input, Continuous, "1", Some(0.0)),
            var("y", Y, Output, Continuous, "1", None),
            rate,
            der_y,
        ]
    }

    fn get_real(&mut self, vr: u32) -> Result<f64, String> {
        Ok(match vr {
            TAU => self.tau,
            Y_START => self.y_start,
            MAX_STEP => self.max_step,
            EXPLODE => self.explode,
            U => self.u,
            Y if self.initialized => self.y,
            Y => self.y_start,
            RATE => 1.0 / self.tau,
            DER_Y => (self.u - self.get_real(Y)?) / self.tau,
            _ => return Err(format!("no variable {vr}")),
        })
    }

    fn set_real(&mut self, vr: u32, value: f64) -> Result<(), String> {
        match vr {
            TAU if !(value > 0.0 && value.is_finite()) => {
                return Err(format!("tau must be > 0, got {value}"));
            }
            TAU => self.tau = value,
            Y_START => self.y_start = value,
            MAX_STEP => self.max_step = value,
            EXPLODE => self.explode = value,
            U if !value.is_finite() => return Err(format!("u must be finite, got {value}")),
            U => self.u = value,
            _ => return Err(format!("variable {vr} cannot be set")),
        }
        Ok(())
    }

    fn enter_initialization(
        &mut self,
        start_time: f64,
        _stop_time: Option<f64>,
        _tolerance: Option<f64>,
    ) -> Result<(), String> {
        self.t = start_time;
        Ok(())
    }

    fn exit_initialization(&mut self) -> Result<(), String> {
        self.y = self.y_start;
        self.initialized = true;
        Ok(())
    }

    fn do_step(&mut self, step: f64) -> Result<(), String> {
        assert!(self.explode == 0.0, "explode = {} set", self.explode);
        if step > self.max_step {
            return Err(format!("step {step} exceeds max_step {}", self.max_step));
        }
        self.y = self.u + (self.y - self.u) * (-step / self.tau).exp();
        self.t += step;
        Ok(())
    }

    fn time(&self) -> f64 {
        self.t
    }

    fn set_time(&mut self, time: f64) -> Result<(), String> {
        self.t = time;
        Ok(())
    }

    fn continuous_states(&mut self, x: &mut [f64]) -> Result<(), String> {
        x[0] = self.get_real(Y)?;
        Ok(())
    }

    fn set_continuous_states(&mut self, x: &[f64]) -> Result<(), String> {
        if !x[0].is_finite() {
            return Err(format!("y = {} must be finite", x[0]));
        }
        self.y = x[0];
        Ok(())
    }

    fn derivatives(&mut self, dx: &mut [f64]) -> Result<(), String> {
        dx[0] = self.get_real(DER_Y)?;
        Ok(())
    }

    fn nominals(&self, nominal: &mut [f64]) -> Result<(), String> {
        nominal[0] = 1.0;
        Ok(())
    }

    fn directional_derivative(
        &mut self,
        unknowns: &[u32],
        knowns: &[u32],
        seed: &[f64],
        result: &mut [f64],
    ) -> Result<(), String> {
        for (r, &unknown) in result.iter_mut().zip(unknowns) {
            *r = 0.0;
            for (&known, &s) in knowns.iter().zip(seed) {
                *r += s * match (unknown, known) {
                    (DER_Y, Y) => -1.0 / self.tau,
                    (DER_Y, U) => 1.0 / self.tau,
                    (Y, Y) => 1.0,
                    (Y, U) => 0.0,
                    _ => return Err(format!("no partial derivative d{unknown}/d{known}")),
                };
            }
        }
        Ok(())
    }

    fn serialize_state(&self) -> Vec<u8> {
        [
            self.tau,
            self.y_start,
            self.max_step,
            self.explode,
            self.u,
            self.y,
            self.t,
            f64::from(u8::from(self.initialized)),
        ]
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect()
    }

    fn deserialize_state(&self, bytes: &[u8]) -> Result<Self, String> {
        if bytes.len() != 64 {
            return Err(format!("core state has {} bytes, expected 64", bytes.len()));
        }
        let x: Vec<f64> = bytes
            .chunks(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
            .collect();
        Ok(LagCore {
            kind: self.kind,
            tau: x[0],
            y_start: x[1],
            max_step: x[2],
            explode: x[3],
            u: x[4],
            y: x[5],
            t: x[6],
            initialized: x[7] != 0.0,
            tau_start: self.tau_start,
        })
    }
}

/// The C functions for the toy core, as the FMU's macro generates them.
pub mod toy {
    use super::LagCore;
    crate::__fmi2_functions!([] LagCore);
}

/// One logger call.
#[derive(Debug, Clone)]
pub struct Record {
    pub instance: String,
    pub status: Fmi2Status,
    pub category: String,
    pub message: String,
}

/// What the test logger saw; passed as `componentEnvironment`.
#[derive(Default)]
pub struct Log {
    records: Mutex<Vec<Record>>,
}

impl Log {
    pub fn records(&self) -> Vec<Record> {
        self.records.lock().unwrap().clone()
    }
    pub fn clear(&self) {
        self.records.lock().unwrap().clear();
    }
    /// All messages with status `status`, joined by newlines.
    pub fn text(&self, status: Fmi2Status) -> String {
        self.records()
            .iter()
            .filter(|r| r.status == status)
            .map(|r| r.message.clone())
            .collect::<Vec<_>>()
            .join("\n")
    }
    /// Asserts that an error message was logged containing all `parts`.
    #[track_caller]
    pub fn assert_error(&self, parts: &[&str]) {
        let errors = self.text(Fmi2Status::Error);
        for part in parts {
            assert!(
                errors.contains(part),
                "no error message containing {part:?} in:\n{errors}"
            );
        }
    }
}

/// The logger, non-variadic: it is called only with the format "%s" and one string argument.
unsafe extern "C" fn test_logger(
    env: fmi2ComponentEnvironment,
    instance: fmi2String,
    status: fmi2Status,
    category: fmi2String,
    format: fmi2String,
    arg: *const c_char,
) {
    let text = |p: *const c_char| unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned();
    assert!(!env.is_null(), "componentEnvironment not passed back");
    assert!(!category.is_null(), "NULL category");
    assert_eq!(text(format), "%s", "format other than %s");
    let log = unsafe { &*(env as *const Log) };
    log.records.lock().unwrap().push(Record {
        instance: text(instance),
        status,
        category: text(category),
        message: text(arg),
    });
}

/// The test logger as `fmi2CallbackLogger`.
pub fn logger() -> fmi2CallbackLogger {
    type Fixed = unsafe extern "C" fn(
        fmi2ComponentEnvironment,
        fmi2String,
        fmi2Status,
        fmi2String,
        fmi2String,
        *const c_char,
    );
    // SAFETY: on the platforms these tests run on (x86-64 System V, AArch64 Linux) a variadic
    // call passes its pointer arguments exactly like a non-variadic call, and the FMU always
    // passes exactly one variadic argument, the string for "%s". (Stable Rust cannot define
    // a C-variadic function.)
    Some(unsafe {
        std::mem::transmute::<
            Fixed,
            unsafe extern "C" fn(
                fmi2ComponentEnvironment,
                fmi2String,
                fmi2Status,
                fmi2String,
                fmi2String,
                ...
            ),
        >(test_logger as Fixed)
    })
}

/// The GUID of the toy FMU without resources.
pub fn toy_guid() -> String {
    guid_for(
        &LagCore::model_info(),
        &LagCore::instantiate(InstanceKind::CoSimulation, None)
            .unwrap()
            .variables(),
    )
    .unwrap()
}

/// A live toy instance with its log.
pub struct Fmu {
    pub c: fmi2Component,
    pub log: Box<Log>,
}

/// Calls `fmi2Instantiate`; returns the component (maybe NULL) and the log.
pub fn instantiate_raw(
    name: &str,
    fmu_type: fmi2Type,
    guid: &str,
    resources: Option<&str>,
    logging_on: bool,
) -> (fmi2Component, Box<Log>) {
    let log = Box::<Log>::default();
    let functions = fmi2CallbackFunctions {
        logger: logger(),
        allocate_memory: None,
        free_memory: None,
        step_finished: None,
        component_environment: &*log as *const Log as *mut _,
    };
    let name = CString::new(name).unwrap();
    let guid = CString::new(guid).unwrap();
    let resources = resources.map(|r| CString::new(r).unwrap());
    let c = unsafe {
        toy::fmi2Instantiate(
            name.as_ptr(),
            fmu_type,
            guid.as_ptr(),
            resources.as_ref().map_or(null(), |r| r.as_ptr()),
            &functions,
            FMI2_FALSE,
            fmi2Boolean::from(logging_on),
        )
    };
    (c, log)
}

impl Fmu {
    pub fn new() -> Fmu {
        Fmu::with_guid(&toy_guid(), None)
    }

    pub fn with_guid(guid: &str, resources: Option<&str>) -> Fmu {
        let (c, log) = instantiate_raw("lag", FMI2_CO_SIMULATION, guid, resources, false);
        assert!(!c.is_null(), "instantiation failed: {:?}", log.records());
        Fmu { c, log }
    }

    /// Instantiated, set up from `start` without stop time, in Initialization Mode.
    pub fn in_init(start: f64) -> Fmu {
        let fmu = Fmu::new();
        assert_eq!(fmu.setup(start, None), Fmi2Status::Ok);
        assert_eq!(
            unsafe { toy::fmi2EnterInitializationMode(fmu.c) },
            Fmi2Status::Ok
        );
        fmu
    }

    /// Initialized at `start`, in stepComplete.
    pub fn running(start: f64) -> Fmu {
        let fmu = Fmu::in_init(start);
        assert_eq!(
            unsafe { toy::fmi2ExitInitializationMode(fmu.c) },
            Fmi2Status::Ok
        );
        fmu
    }

    pub fn setup(&self, start: f64, stop: Option<f64>) -> Fmi2Status {
        unsafe {
            toy::fmi2SetupExperiment(
                self.c,
                FMI2_FALSE,
                0.0,
                start,
                fmi2Boolean::from(stop.is_some()),
                stop.unwrap_or(0.0),
            )
        }
    }

    pub fn get(&self, vr: u32) -> f64 {
        let mut x = f64::NAN;
        assert_eq!(
            unsafe { toy::fmi2GetReal(self.c, &vr, 1, &mut x) },
            Fmi2Status::Ok,
            "{:?}",
            self.log.records()
        );
        x
    }

    pub fn try_get(&self, vr: u32) -> Fmi2Status {
        let mut x = 0.0;
        unsafe { toy::fmi2GetReal(self.c, &vr, 1, &mut x) }
    }

    pub fn set(&self, vr: u32, x: f64) -> Fmi2Status {
        unsafe { toy::fmi2SetReal(self.c, &vr, 1, &x) }
    }

    pub fn step(&self, tc: f64, h: f64) -> Fmi2Status {
        unsafe { toy::fmi2DoStep(self.c, tc, h, FMI2_TRUE) }
    }

    pub fn get_state(&self) -> fmi2FMUstate {
        let mut s = null_mut();
        assert_eq!(
            unsafe { toy::fmi2GetFMUstate(self.c, &mut s) },
            Fmi2Status::Ok
        );
        s
    }
}

impl Drop for Fmu {
    fn drop(&mut self) {
        unsafe { toy::fmi2FreeInstance(self.c) }
    }
}

/// Exact solution of the lag after `n` steps of `h` from `y0` with input `u`.
pub fn lag_exact(y0: f64, u: f64, tau: f64, h: f64, n: usize) -> f64 {
    (0..n).fold(y0, |y, _| u + (y - u) * (-h / tau).exp())
}
