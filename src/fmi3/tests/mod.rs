//! Tests of the FMI 3.0 shell through its `extern "C"` functions, generated for the FMU's own
//! core by the same macro the FMU uses (minus the exported symbol names), beside the FMI 2.0
//! shell's functions for the same core.

mod cosimulation;
mod fmu_state;
mod model_exchange;

use std::ffi::{CStr, CString, c_void};
use std::ptr::null;
use std::sync::Mutex;

use super::types::*;
use crate::fmu::pack::FmiVersion;
use crate::model::Params;

/// The FMI 3.0 functions for the FMU's core (the tests call some of them; the Python tests of
/// the packed FMU call the others).
#[allow(dead_code)]
pub mod v3 {
    crate::__fmi3_functions!([] crate::fmu::HaselCore);
}

/// The FMI 2.0 functions for the same core, to compare with.
#[allow(dead_code)]
pub mod v2 {
    crate::__fmi2_functions!([] crate::fmu::HaselCore);
}

/// What the test logger saw; passed as the instance environment.
#[derive(Default)]
pub struct Log {
    records: Mutex<Vec<(Fmi3Status, String, String)>>,
}

impl Log {
    /// Asserts that an error message was logged under `logStatusError` containing all `parts`.
    #[track_caller]
    pub fn assert_error(&self, parts: &[&str]) {
        let records = self.records.lock().unwrap();
        let found = records.iter().any(|(status, category, text)| {
            *status == Fmi3Status::Error
                && category == "logStatusError"
                && parts.iter().all(|p| text.contains(p))
        });
        assert!(found, "no error message with {parts:?} in {records:#?}");
    }

    pub fn clear(&self) {
        self.records.lock().unwrap().clear();
    }
}

unsafe extern "C" fn log_message(
    env: fmi3InstanceEnvironment,
    status: fmi3Status,
    category: fmi3String,
    message: fmi3String,
) {
    assert!(!category.is_null() && !message.is_null());
    let log = unsafe { &*(env as *const Log) };
    let text = |p| unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned();
    log.records
        .lock()
        .unwrap()
        .push((status, text(category), text(message)));
}

/// The instantiationToken of the default FMU.
pub fn token() -> CString {
    CString::new(FmiVersion::V3.token(&crate::fmu::pack::platform(&Params::default()))).unwrap()
}

/// One Co-Simulation instance with its log.
pub struct Cs {
    pub c: fmi3Instance,
    pub log: Box<Log>,
    pub t: f64,
}

impl Cs {
    pub fn new(event_mode_used: bool) -> Cs {
        Cs::with_token(&token(), event_mode_used)
    }

    /// A Model Exchange instance (`t` unused), with the same helpers.
    pub fn model_exchange() -> Cs {
        let log = Box::<Log>::default();
        let c = unsafe {
            v3::fmi3InstantiateModelExchange(
                c"me".as_ptr(),
                token().as_ptr(),
                null(),
                FMI3_FALSE,
                FMI3_FALSE,
                &*log as *const Log as *mut c_void,
                Some(log_message),
            )
        };
        assert!(!c.is_null());
        Cs { c, log, t: 0.0 }
    }

    fn with_token(token: &CStr, event_mode_used: bool) -> Cs {
        let log = Box::<Log>::default();
        let c = unsafe {
            v3::fmi3InstantiateCoSimulation(
                c"test".as_ptr(),
                token.as_ptr(),
                null(),
                FMI3_FALSE,
                FMI3_FALSE,
                u8::from(event_mode_used),
                FMI3_FALSE,
                null(),
                0,
                &*log as *const Log as *mut c_void,
                Some(log_message),
                None,
            )
        };
        Cs { c, log, t: 0.0 }
    }

    pub fn init(&mut self) {
        unsafe {
            assert_eq!(
                v3::fmi3EnterInitializationMode(self.c, 0, 0.0, 0.0, 0, 0.0),
                Fmi3Status::Ok
            );
            assert_eq!(v3::fmi3ExitInitializationMode(self.c), Fmi3Status::Ok);
        }
    }

    pub fn set(&self, vrs: &[u32], values: &[f64]) -> Fmi3Status {
        unsafe {
            v3::fmi3SetFloat64(
                self.c,
                vrs.as_ptr(),
                vrs.len(),
                values.as_ptr(),
                values.len(),
            )
        }
    }

    pub fn get(&self, vrs: &[u32]) -> (Fmi3Status, Vec<f64>) {
        let mut out = vec![0.0; vrs.len()];
        let s = unsafe {
            v3::fmi3GetFloat64(self.c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr(), out.len())
        };
        (s, out)
    }

    /// `fmi3DoStep` from the instance's time; the time advances on success.
    pub fn step(&mut self, h: f64) -> (Fmi3Status, f64) {
        let (mut event, mut terminate, mut early, mut last) = (9, 9, 9, f64::NAN);
        let s = unsafe {
            v3::fmi3DoStep(
                self.c,
                self.t,
                h,
                FMI3_TRUE,
                &mut event,
                &mut terminate,
                &mut early,
                &mut last,
            )
        };
        assert_eq!((event, terminate, early), (0, 0, 0));
        if s == Fmi3Status::Ok {
            self.t += h;
        }
        (s, last)
    }
}

impl Drop for Cs {
    fn drop(&mut self) {
        unsafe { v3::fmi3FreeInstance(self.c) };
    }
}

/// The value reference of the variable `name` in the FMU's table.
pub fn vr(name: &str) -> u32 {
    crate::fmu::variables::rows()
        .iter()
        .position(|r| r.name == name)
        .unwrap_or_else(|| panic!("no variable {name}")) as u32
}

#[test]
fn the_version_is_3_0_and_the_token_guards_instantiation() {
    assert_eq!(
        unsafe { CStr::from_ptr(v3::fmi3GetVersion()) }.to_str(),
        Ok("3.0")
    );
    let wrong = Cs::with_token(c"{not the token}", false);
    assert!(wrong.c.is_null());
    wrong
        .log
        .assert_error(&["instantiationToken {not the token}", "does not match"]);
}
