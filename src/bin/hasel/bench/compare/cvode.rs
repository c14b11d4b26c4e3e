//! SUNDIALS CVODE (the system's libsundials 6.x through `sundials-sys`), called natively on the
//! two runs of the table: variable-order BDF with Newton iterations on the analytic Jacobian,
//! through SUNDIALS' dense LU or its band LU. The Jacobian of the paper's model is
//! block-diagonal (one 5 × 5 block per actuator, book/src/model.md), so a band of half-width
//! 4 holds it exactly and the band LU is CVODE's block-diagonal solver here; with a coupling
//! effect the blocks join and only the dense solver applies.
//!
//! The sine run asks CVODE for the outputs every 1 ms (its own interpolation, `CV_NORMAL`,
//! stop time 10 s); the held run re-initializes CVODE at each 1 ms step (`CVodeReInit`, the
//! documented restart at a discontinuity) with the stop time at the step's end.

use std::cell::Cell;
use std::ffi::{CStr, c_int, c_long, c_void};
use std::ptr::null_mut;

use hasel_fmu::model::Platform;
use hasel_fmu::simulation::{Input, Sample, SimError, tolerances};
use sundials_sys as sun;

use super::{Case, Work};
use crate::error::Error;

/// CVODE's linear solver for the Newton iterations.
#[derive(Clone, Copy)]
pub enum Linear {
    Dense,
    /// SUNDIALS' band LU with the half-widths of the Jacobian's blocks
    Band,
}

impl Linear {
    pub const ALL: [Linear; 2] = [Linear::Dense, Linear::Band];

    pub fn name(self) -> &'static str {
        match self {
            Linear::Dense => "CVODE BDF, dense LU",
            Linear::Band => "CVODE BDF, band LU",
        }
    }
}

/// The SUNDIALS version linked.
pub fn version() -> &'static str {
    CStr::from_bytes_until_nul(sun::SUNDIALS_VERSION)
        .ok()
        .and_then(|v| v.to_str().ok())
        .unwrap_or("?")
}

/// What the callbacks see, through CVODE's user-data pointer.
struct Problem<'m> {
    model: &'m Platform,
    input: Input,
    case: Case,
    /// the input held over the current step (held run)
    held: Cell<[f64; 3]>,
    f: Cell<usize>,
    jac: Cell<usize>,
    /// the model's column-major Jacobian, copied into the band storage
    scratch: std::cell::RefCell<Vec<f64>>,
    band: Option<usize>,
}

impl Problem<'_> {
    fn u(&self, t: f64) -> [f64; 3] {
        match self.case {
            Case::Sine => self.input.value(t),
            Case::Held => self.held.get(),
        }
    }
}

fn slice<'a>(v: sun::N_Vector, n: usize) -> &'a mut [f64] {
    // SAFETY: a serial N_Vector of length n, alive for the call it was handed to
    unsafe { std::slice::from_raw_parts_mut(sun::N_VGetArrayPointer(v), n) }
}

/// f(t, x); a state outside the model's domain is a recoverable failure (CVODE retries with a
/// smaller step), as the model's errors are for Radau5.
unsafe extern "C" fn rhs(t: f64, y: sun::N_Vector, dy: sun::N_Vector, data: *mut c_void) -> c_int {
    // SAFETY: `data` is the `Problem` given to CVodeSetUserData, alive during CVode
    let p = unsafe { &*(data as *const Problem) };
    let n = p.model.n_states();
    p.f.set(p.f.get() + 1);
    match p.model.rhs(slice(y, n), p.u(t), slice(dy, n)) {
        Ok(()) => 0,
        Err(_) => 1,
    }
}

/// The analytic Jacobian into CVODE's dense or band matrix.
unsafe extern "C" fn jacobian(
    t: f64,
    y: sun::N_Vector,
    _fy: sun::N_Vector,
    jac: sun::SUNMatrix,
    data: *mut c_void,
    _t1: sun::N_Vector,
    _t2: sun::N_Vector,
    _t3: sun::N_Vector,
) -> c_int {
    // SAFETY: as in `rhs`
    let p = unsafe { &*(data as *const Problem) };
    let n = p.model.n_states();
    p.jac.set(p.jac.get() + 1);
    let x = slice(y, n);
    match p.band {
        None => {
            // SAFETY: an n × n dense matrix, column-major like the model's Jacobian
            let dense =
                unsafe { std::slice::from_raw_parts_mut(sun::SUNDenseMatrix_Data(jac), n * n) };
            if p.model.jacobian(x, p.u(t), dense).is_err() {
                return 1;
            }
        }
        Some(w) => {
            let mut full = p.scratch.borrow_mut();
            if p.model.jacobian(x, p.u(t), &mut full).is_err() {
                return 1;
            }
            for j in 0..n {
                // SAFETY: the column pointer addresses rows j-w..=j+w of column j (band storage)
                let col = unsafe { sun::SUNBandMatrix_Column(jac, j as i64) };
                for i in j.saturating_sub(w)..(j + w + 1).min(n) {
                    unsafe { *col.offset(i as isize - j as isize) = full[j * n + i] };
                }
            }
        }
    }
    0
}

/// CVODE's objects for one run, freed on drop whatever happens.
struct Cvode {
    ctx: sun::SUNContext,
    mem: *mut c_void,
    y: sun::N_Vector,
    atol: sun::N_Vector,
    matrix: sun::SUNMatrix,
    solver: sun::SUNLinearSolver,
}

impl Drop for Cvode {
    fn drop(&mut self) {
        // SAFETY: each pointer is NULL or was created for this run and is freed once
        unsafe {
            if !self.mem.is_null() {
                sun::CVodeFree(&mut self.mem);
            }
            if !self.solver.is_null() {
                sun::SUNLinSolFree(self.solver);
            }
            if !self.matrix.is_null() {
                sun::SUNMatDestroy(self.matrix);
            }
            for v in [self.y, self.atol] {
                if !v.is_null() {
                    sun::N_VDestroy(v);
                }
            }
            if !self.ctx.is_null() {
                sun::SUNContext_Free(&mut self.ctx);
            }
        }
    }
}

/// A CVODE return flag as an error naming the call.
fn check(call: &'static str, flag: c_int) -> Result<c_int, Error> {
    if flag < 0 {
        // SAFETY: CVodeGetReturnFlagName returns a static string for any flag
        let name = unsafe { CStr::from_ptr(sun::CVodeGetReturnFlagName(flag as c_long)) };
        Err(Error::Cvode {
            call,
            flag: name.to_string_lossy().into_owned(),
        })
    } else {
        Ok(flag)
    }
}

fn created<T>(call: &'static str, p: *mut T) -> Result<*mut T, Error> {
    if p.is_null() {
        Err(Error::Cvode {
            call,
            flag: "returned NULL".into(),
        })
    } else {
        Ok(p)
    }
}

/// Adds CVODE's step, rejection and LU counters since its last (re-)initialization to `work`.
fn counters(mem: *mut c_void, work: &mut Work) -> Result<(), Error> {
    type Getter = unsafe extern "C" fn(*mut c_void, *mut c_long) -> c_int;
    let get = |call: &'static str, getter: Getter| {
        let mut v: c_long = 0;
        // SAFETY: `mem` is a live CVODE memory block
        check(call, unsafe { getter(mem, &mut v) }).map(|_| v as usize)
    };
    work.steps += get("CVodeGetNumSteps", sun::CVodeGetNumSteps)?;
    work.rejected += get("CVodeGetNumErrTestFails", sun::CVodeGetNumErrTestFails)?
        + get(
            "CVodeGetNumNonlinSolvConvFails",
            sun::CVodeGetNumNonlinSolvConvFails,
        )?;
    work.lu += get("CVodeGetNumLinSolvSetups", sun::CVodeGetNumLinSolvSetups)?;
    Ok(())
}

/// Runs `case` once with CVODE and `linear`; returns the samples (every 1 ms) and its counters.
pub fn run(
    model: &Platform,
    linear: Linear,
    case: Case,
    rtol: f64,
) -> Result<(Vec<Sample>, Work), Error> {
    let n = model.n_states();
    let x0 = model.rest_state().map_err(SimError::from)?;
    let tol = tolerances(rtol, &model.state_scales())?;
    let blocks = model.jacobian_blocks();
    let problem = Problem {
        model,
        input: Input::sine(60.0, 3.0 * std::f64::consts::PI),
        case,
        held: Cell::new([0.0; 3]),
        f: Cell::new(0),
        jac: Cell::new(0),
        scratch: std::cell::RefCell::new(vec![0.0; n * n]),
        band: match linear {
            Linear::Dense => None,
            Linear::Band => Some(blocks.iter().max().copied().unwrap_or(n) - 1),
        },
    };
    let mut cv = Cvode {
        ctx: null_mut(),
        mem: null_mut(),
        y: null_mut(),
        atol: null_mut(),
        matrix: null_mut(),
        solver: null_mut(),
    };
    let (dt, n_out) = (1e-3, 10_000usize);
    let mut samples = Vec::with_capacity(n_out + 1);
    samples.push(Sample::of(model, 0.0, problem.input.value(0.0), &x0));
    // SAFETY: the SUNDIALS calls get the objects created here (freed by `cv`'s drop) and the
    // problem, which outlives every CVode call
    unsafe {
        check(
            "SUNContext_Create",
            sun::SUNContext_Create(null_mut(), &mut cv.ctx),
        )?;
        cv.y = created("N_VNew_Serial", sun::N_VNew_Serial(n as i64, cv.ctx))?;
        cv.atol = created("N_VNew_Serial", sun::N_VNew_Serial(n as i64, cv.ctx))?;
        slice(cv.y, n).copy_from_slice(&x0);
        slice(cv.atol, n).copy_from_slice(&tol.atol);
        cv.mem = created("CVodeCreate", sun::CVodeCreate(sun::CV_BDF, cv.ctx))?;
        check("CVodeInit", sun::CVodeInit(cv.mem, Some(rhs), 0.0, cv.y))?;
        check(
            "CVodeSVtolerances",
            sun::CVodeSVtolerances(cv.mem, tol.rtol, cv.atol),
        )?;
        let data = &problem as *const Problem as *mut c_void;
        check("CVodeSetUserData", sun::CVodeSetUserData(cv.mem, data))?;
        cv.matrix = match problem.band {
            None => created(
                "SUNDenseMatrix",
                sun::SUNDenseMatrix(n as i64, n as i64, cv.ctx),
            )?,
            Some(w) => created(
                "SUNBandMatrix",
                sun::SUNBandMatrix(n as i64, w as i64, w as i64, cv.ctx),
            )?,
        };
        cv.solver = match problem.band {
            None => created(
                "SUNLinSol_Dense",
                sun::SUNLinSol_Dense(cv.y, cv.matrix, cv.ctx),
            )?,
            Some(_) => created(
                "SUNLinSol_Band",
                sun::SUNLinSol_Band(cv.y, cv.matrix, cv.ctx),
            )?,
        };
        check(
            "CVodeSetLinearSolver",
            sun::CVodeSetLinearSolver(cv.mem, cv.solver, cv.matrix),
        )?;
        check("CVodeSetJacFn", sun::CVodeSetJacFn(cv.mem, Some(jacobian)))?;
        check(
            "CVodeSetMaxNumSteps",
            sun::CVodeSetMaxNumSteps(cv.mem, 1_000_000),
        )?;
        let mut t = 0.0;
        let mut work = Work::default();
        match case {
            Case::Sine => {
                let t_end = n_out as f64 * dt;
                check("CVodeSetStopTime", sun::CVodeSetStopTime(cv.mem, t_end))?;
                for k in 1..=n_out {
                    let tk = (k as f64 * dt).min(t_end);
                    check(
                        "CVode",
                        sun::CVode(cv.mem, tk, cv.y, &mut t, sun::CV_NORMAL),
                    )?;
                    samples.push(Sample::of(
                        model,
                        tk,
                        problem.input.value(tk),
                        slice(cv.y, n),
                    ));
                }
                counters(cv.mem, &mut work)?;
            }
            Case::Held => {
                for k in 0..n_out {
                    let (t0, t1) = (k as f64 * dt, (k + 1) as f64 * dt);
                    problem.held.set(problem.input.value(t0));
                    check("CVodeReInit", sun::CVodeReInit(cv.mem, t0, cv.y))?;
                    check("CVodeSetStopTime", sun::CVodeSetStopTime(cv.mem, t1))?;
                    check(
                        "CVode",
                        sun::CVode(cv.mem, t1, cv.y, &mut t, sun::CV_NORMAL),
                    )?;
                    samples.push(Sample::of(
                        model,
                        t1,
                        problem.input.value(t1),
                        slice(cv.y, n),
                    ));
                    // CVodeReInit sets CVODE's counters to zero: take them before it
                    counters(cv.mem, &mut work)?;
                }
            }
        }
        work.f = problem.f.get();
        work.jac = problem.jac.get();
        Ok((samples, work))
    }
}
