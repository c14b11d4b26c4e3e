//! A co-simulation step makes no heap allocation: fmi2SetReal of the three inputs, fmi2DoStep
//! of 1 ms and fmi2GetReal of the six outputs, through the FMU's C functions (made by the
//! library's macro as the fuzz targets make them, tests/fuzz/fuzz_targets/fmi2_sequence.rs), counted by a global allocator that counts every allocation made
//! on the calling thread (the FMU steps on its caller's thread; the test harness's own
//! threads allocate at times of their own, which made a process-wide count fail under load).
//! Allocations before the loop (instantiation, initialization, the first steps while buffers
//! settle) are not counted. The slow model's FMU (feature reduced-fmu, a build of its own) steps
//! through the same simulator, whose held step is counted here on the slow model.

// the FMU's C functions as the fuzz targets make them, with the library's macro
#[allow(dead_code)]
#[path = "fuzz/fuzz_targets/common.rs"]
mod common;
#[allow(dead_code)]
#[path = "fuzz/fuzz_targets/fmi2_sequence.rs"]
mod fmi2_sequence;

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::ffi::c_void;
use std::ptr::{null, null_mut};

use fmi2_sequence::Fmu;
use hasel_fmu::fmi2::types::{FMI2_CO_SIMULATION, Fmi2Status, fmi2CallbackFunctions};
use hasel_fmu::fmu::variables::rows;
use hasel_fmu::model::{Params, Platform, Reduction};
use hasel_fmu::simulation::{DEFAULT_RTOL, Input, Simulator};

struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

fn count_one() {
    ALLOCATIONS.with(|n| n.set(n.get() + 1));
}

fn allocations() -> usize {
    ALLOCATIONS.with(Cell::get)
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count_one();
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, size: usize) -> *mut u8 {
        count_one();
        unsafe { System.realloc(ptr, layout, size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

unsafe extern "C" {
    fn calloc(n: usize, size: usize) -> *mut c_void;
    fn free(p: *mut c_void);
}

const OK: Fmi2Status = Fmi2Status::Ok;

fn vrs<const N: usize>(names: [&str; N]) -> [u32; N] {
    names.map(|name| rows().iter().position(|r| r.name == name).unwrap() as u32)
}

#[test]
fn set_real_do_step_and_get_real_allocate_nothing() {
    let inputs = vrs(["U1", "U2", "U3"]);
    let outputs = vrs(["h1", "h2", "h3", "tip_x", "tip_y", "tip_z"]);
    let fmu = Fmu::platform();
    let f = fmu.functions;
    let callbacks = fmi2CallbackFunctions {
        logger: None,
        allocate_memory: Some(calloc),
        free_memory: Some(free),
        step_finished: None,
        component_environment: null_mut(),
    };
    let c = unsafe {
        (f.fmi2Instantiate)(
            c"alloc".as_ptr(),
            FMI2_CO_SIMULATION,
            fmu.token.as_ptr(),
            null(),
            &callbacks,
            0,
            0,
        )
    };
    assert!(!c.is_null());
    unsafe {
        assert_eq!((f.fmi2SetupExperiment)(c, 0, 0.0, 0.0, 0, 0.0), OK);
        assert_eq!((f.fmi2EnterInitializationMode)(c), OK);
        assert_eq!((f.fmi2ExitInitializationMode)(c), OK);
    }
    let input = Input::sine(60.0, 3.0 * std::f64::consts::PI);
    let dt = 1e-3;
    let mut y = [0.0; 6];
    let mut step = |k: usize| unsafe {
        let t = k as f64 * dt;
        assert_eq!(
            (f.fmi2SetReal)(c, inputs.as_ptr(), 3, input.value(t).as_ptr()),
            OK
        );
        assert_eq!((f.fmi2DoStep)(c, t, dt, 1), OK, "step {k}");
        assert_eq!((f.fmi2GetReal)(c, outputs.as_ptr(), 6, y.as_mut_ptr()), OK);
    };
    let made = allocations_in_steps(&mut step);
    unsafe { (f.fmi2FreeInstance)(c) };
    assert!(y.iter().all(|v| v.is_finite()));
    assert_eq!(made, 0, "{made} heap allocations in 2,000 steps");
}

#[test]
fn a_held_step_of_the_slow_model_allocates_nothing() {
    let model = Platform::reduced(Params::default(), Reduction::Slow).unwrap();
    let mut sim = Simulator::new(model, 0.0, DEFAULT_RTOL).unwrap();
    let input = Input::sine(60.0, 3.0 * std::f64::consts::PI);
    let mut step = |k: usize| {
        sim.step_held(input.value(k as f64 * 1e-3), (k + 1) as f64 * 1e-3)
            .unwrap();
    };
    let made = allocations_in_steps(&mut step);
    assert_eq!(made, 0, "{made} heap allocations in 2,000 steps");
}

/// The heap allocations of 2,000 steps, after 100 steps that warm up.
fn allocations_in_steps(step: &mut impl FnMut(usize)) -> usize {
    for k in 0..100 {
        step(k);
    }
    let before = allocations();
    for k in 100..2100 {
        step(k);
    }
    allocations() - before
}
