//! A co-simulation step makes no heap allocation: fmi2SetReal of the three inputs, fmi2DoStep
//! of 1 ms and fmi2GetReal of the six outputs, through the C functions the FMU exports (linked
//! here from the library), counted by a global allocator that counts every allocation made
//! on the calling thread (the FMU steps on its caller's thread; the test harness's own
//! threads allocate at times of their own, which made a process-wide count fail under load).
//! Allocations before the loop (instantiation, initialization, the first steps while buffers
//! settle) are not counted. The slow model's FMU (feature reduced-fmu, a build of its own) steps
//! through the same simulator, whose held step is counted here on the slow model.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::ffi::{CString, c_char, c_int, c_void};
use std::ptr::null;

use hasel_fmu::fmu::pack::{guid, platform};
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

type Component = *mut c_void;

/// `fmi2CallbackFunctions` without a logger: what a quiet importer passes.
#[repr(C)]
struct Callbacks {
    logger: *const c_void,
    allocate: Option<unsafe extern "C" fn(usize, usize) -> *mut c_void>,
    free: Option<unsafe extern "C" fn(*mut c_void)>,
    step_finished: *const c_void,
    environment: *mut c_void,
}

unsafe extern "C" {
    fn fmi2Instantiate(
        name: *const c_char,
        kind: c_int,
        guid: *const c_char,
        resources: *const c_char,
        callbacks: *const Callbacks,
        visible: i32,
        logging_on: i32,
    ) -> Component;
    fn fmi2FreeInstance(c: Component);
    fn fmi2SetupExperiment(
        c: Component,
        tol_on: i32,
        tol: f64,
        t0: f64,
        stop_on: i32,
        stop: f64,
    ) -> c_int;
    fn fmi2EnterInitializationMode(c: Component) -> c_int;
    fn fmi2ExitInitializationMode(c: Component) -> c_int;
    fn fmi2SetReal(c: Component, vr: *const u32, n: usize, v: *const f64) -> c_int;
    fn fmi2GetReal(c: Component, vr: *const u32, n: usize, v: *mut f64) -> c_int;
    fn fmi2DoStep(c: Component, t: f64, h: f64, no_prior: i32) -> c_int;
    fn calloc(n: usize, size: usize) -> *mut c_void;
    fn free(p: *mut c_void);
}

fn vrs<const N: usize>(names: [&str; N]) -> [u32; N] {
    names.map(|name| rows().iter().position(|r| r.name == name).unwrap() as u32)
}

#[test]
fn set_real_do_step_and_get_real_allocate_nothing() {
    let inputs = vrs(["U1", "U2", "U3"]);
    let outputs = vrs(["h1", "h2", "h3", "tip_x", "tip_y", "tip_z"]);
    let guid = CString::new(guid(&platform(&Params::default()))).unwrap();
    let callbacks = Callbacks {
        logger: null(),
        allocate: Some(calloc),
        free: Some(free),
        step_finished: null(),
        environment: std::ptr::null_mut(),
    };
    let c = unsafe {
        fmi2Instantiate(
            c"alloc".as_ptr(),
            1,
            guid.as_ptr(),
            null(),
            &callbacks,
            0,
            0,
        )
    };
    assert!(!c.is_null());
    unsafe {
        assert_eq!(fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0), 0);
        assert_eq!(fmi2EnterInitializationMode(c), 0);
        assert_eq!(fmi2ExitInitializationMode(c), 0);
    }
    let input = Input::sine(60.0, 3.0 * std::f64::consts::PI);
    let dt = 1e-3;
    let mut y = [0.0; 6];
    let mut step = |k: usize| unsafe {
        let t = k as f64 * dt;
        assert_eq!(
            fmi2SetReal(c, inputs.as_ptr(), 3, input.value(t).as_ptr()),
            0
        );
        assert_eq!(fmi2DoStep(c, t, dt, 1), 0, "step {k}");
        assert_eq!(fmi2GetReal(c, outputs.as_ptr(), 6, y.as_mut_ptr()), 0);
    };
    let made = allocations_in_steps(&mut step);
    unsafe { fmi2FreeInstance(c) };
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
