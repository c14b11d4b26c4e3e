//! diffsol 0.18 (BDF, ESDIRK34 and TR-BDF2, dense nalgebra LU) on the two runs of the table.
//!
//! The model enters diffsol through `OdeBuilder::rhs_implicit`: f(x, t) and the action J·v of
//! the analytic Jacobian. diffsol builds its dense Newton matrix from 15 such products (one per
//! unit vector), so the J·v closure keeps the last `Platform::jacobian` and re-evaluates it only
//! when the state or the input changes: one model Jacobian per diffsol Jacobian, as in Radau5.
//! The counters are taken in the closures (f and model-Jacobian calls) and from diffsol's
//! `OdeSolverStatistics` (steps, rejections, LU set-ups).

use std::cell::{Cell, RefCell};

use diffsol::{
    NalgebraContext, NalgebraLU, NalgebraMat, NalgebraVec, OdeBuilder, OdeEquationsImplicit,
    OdeSolverMethod, OdeSolverStopReason, ode_solver::OdeSolverStatistics,
};
use hasel_fmu::model::Platform;
use hasel_fmu::simulation::{Input, Sample, SimError, tolerances};

use super::{Case, Work};
use crate::error::Error;

type M = NalgebraMat<f64>;
type LS = NalgebraLU<f64>;

/// Library methods compared.
#[derive(Clone, Copy)]
pub enum Method {
    Bdf,
    Esdirk34,
    TrBdf2,
}

impl Method {
    pub const ALL: [Method; 3] = [Method::Bdf, Method::Esdirk34, Method::TrBdf2];

    pub fn name(self) -> &'static str {
        match self {
            Method::Bdf => "diffsol BDF",
            Method::Esdirk34 => "diffsol ESDIRK34",
            Method::TrBdf2 => "diffsol TR-BDF2",
        }
    }
}

/// Evaluation counters and the cached model Jacobian shared by the closures of one run.
struct Evals<'m> {
    model: &'m Platform,
    n: usize,
    f: Cell<usize>,
    jac: Cell<usize>,
    /// (x, u) of the cached Jacobian, and the Jacobian (column-major n × n)
    at: RefCell<(Vec<f64>, [f64; 3], Vec<f64>)>,
}

impl<'m> Evals<'m> {
    fn new(model: &'m Platform) -> Evals<'m> {
        let n = model.n_states();
        Evals {
            model,
            n,
            f: Cell::new(0),
            jac: Cell::new(0),
            at: RefCell::new((vec![f64::NAN; n], [f64::NAN; 3], vec![0.0; n * n])),
        }
    }

    /// f(x, u); NaN where the model is out of its domain, so that diffsol rejects the step.
    fn rhs(&self, x: &[f64], u: [f64; 3], dx: &mut [f64]) {
        self.f.set(self.f.get() + 1);
        if self.model.rhs(x, u, dx).is_err() {
            dx.fill(f64::NAN);
        }
    }

    /// J(x, u) v, from the cached Jacobian when (x, u) is the one it was evaluated at.
    fn jac_mul(&self, x: &[f64], u: [f64; 3], v: &[f64], y: &mut [f64]) {
        let mut at = self.at.borrow_mut();
        let (ax, au, jac) = &mut *at;
        if ax.as_slice() != x || *au != u {
            self.jac.set(self.jac.get() + 1);
            if self.model.jacobian(x, u, jac).is_err() {
                jac.fill(f64::NAN);
            }
            ax.copy_from_slice(x);
            *au = u;
        }
        y.fill(0.0);
        for (c, &vc) in v.iter().enumerate() {
            if vc != 0.0 {
                for (yr, &j) in y.iter_mut().zip(&jac[c * self.n..(c + 1) * self.n]) {
                    *yr += j * vc;
                }
            }
        }
    }
}

/// Runs `case` once with `method`; returns the samples (every 1 ms) and diffsol's statistics.
pub fn run(
    model: &Platform,
    method: Method,
    case: Case,
    rtol: f64,
) -> Result<(Vec<Sample>, Work), Error> {
    let input = Input::sine(60.0, 3.0 * std::f64::consts::PI);
    // the input the closures see: the sine itself, or the value held over the current step
    let held = Cell::new([0.0; 3]);
    let u_at = |t: f64| match case {
        Case::Sine => input.value(t),
        Case::Held => held.get(),
    };
    let evals = Evals::new(model);
    let x0 = model.rest_state().map_err(SimError::from)?;
    let tol = tolerances(rtol, &model.state_scales())?;
    // diffsol's own errors, before a method runs and while it does
    let library = |source| Error::Diffsol {
        method: None,
        source,
    };
    let mut problem = OdeBuilder::<M>::new()
        .t0(0.0)
        .rtol(tol.rtol)
        .atol(tol.atol)
        .rhs_implicit(
            |x: &[f64], _p: &[f64], t: f64, y: &mut [f64]| evals.rhs(x, u_at(t), y),
            |x: &[f64], _p: &[f64], t: f64, v: &[f64], y: &mut [f64]| {
                evals.jac_mul(x, u_at(t), v, y)
            },
        )
        .init(
            |_p: &[f64], _t: f64, y: &mut [f64]| y.copy_from_slice(&x0),
            x0.len(),
        )
        .build()
        .map_err(library)?;
    // diffsol stops a solve after 50 Newton failures in all (not in a row). With that default
    // every method stops on this model (the sine between 3.5 and 8.1 s, the held input within
    // 25 ms): Newton iterates from a reused Jacobian leave the shell's domain (f is NaN there)
    // and the step is retried smaller. The cap is lifted; each failure is still paid for and
    // counted among the rejections.
    problem.ode_options.max_nonlinear_solver_failures = usize::MAX;
    let drive = Drive {
        model,
        case,
        input: &input,
        held: &held,
        evals: &evals,
    };
    let (samples, stats) = match method {
        Method::Bdf => drive.run(problem.bdf::<LS>().map_err(library)?),
        Method::Esdirk34 => drive.run(problem.esdirk34::<LS>().map_err(library)?),
        Method::TrBdf2 => drive.run(problem.tr_bdf2::<LS>().map_err(library)?),
    }
    .map_err(|source| Error::Diffsol {
        method: Some(method.name()),
        source,
    })?;
    Ok((
        samples,
        Work {
            steps: stats.number_of_steps,
            rejected: stats.number_of_error_test_failures + stats.number_of_nonlinear_solver_fails,
            f: evals.f.get(),
            jac: evals.jac.get(),
            lu: stats.number_of_linear_solver_setups,
        },
    ))
}

struct Drive<'r, 'm> {
    model: &'m Platform,
    case: Case,
    input: &'r Input,
    held: &'r Cell<[f64; 3]>,
    evals: &'r Evals<'m>,
}

impl Drive<'_, '_> {
    fn run<'a, Eqn, S>(
        &self,
        mut solver: S,
    ) -> Result<(Vec<Sample>, OdeSolverStatistics), diffsol::DiffsolError>
    where
        Eqn: OdeEquationsImplicit<T = f64, V = NalgebraVec<f64>, C = NalgebraContext> + 'a,
        S: OdeSolverMethod<'a, Eqn>,
    {
        let (dt, n_out) = (1e-3, 10_000usize);
        let mut samples = Vec::with_capacity(n_out + 1);
        let y = solver.state().y.batch_as_slice(0).to_vec();
        samples.push(Sample::of(self.model, 0.0, self.input.value(0.0), &y));
        match self.case {
            Case::Sine => {
                // adaptive steps to 10 s (stopping exactly there), outputs from the interpolant
                let t_end = n_out as f64 * dt;
                solver.set_stop_time(t_end)?;
                let mut k = 1;
                loop {
                    let reason = solver.step()?;
                    let t = solver.state().t;
                    while k <= n_out && (k as f64 * dt).min(t_end) <= t {
                        let ts = (k as f64 * dt).min(t_end);
                        let x = solver.interpolate(ts)?;
                        samples.push(Sample::of(
                            self.model,
                            ts,
                            self.input.value(ts),
                            x.batch_as_slice(0),
                        ));
                        k += 1;
                    }
                    if matches!(reason, OdeSolverStopReason::TstopReached) {
                        break;
                    }
                }
            }
            Case::Held => {
                for k in 0..n_out {
                    // restart at the input jump with diffsol's own means: hold the new value,
                    // give the state its derivative under it (ESDIRK's first stage and BDF's
                    // order-1 history start from dy) and let diffsol pick the first step by its
                    // initial step-size rule (Hairer-Norsett-Wanner II.4). Touching state_mut
                    // makes BDF drop its history and the Runge-Kutta methods re-arm the stop
                    // time. (Keeping the last step size instead is correct too but ~15% slower:
                    // twice the rejections, while the error control shrinks h to the ns scale of
                    // the source-resistor transient.)
                    let u = self.input.value(k as f64 * dt);
                    self.held.set(u);
                    {
                        let problem = solver.problem();
                        let order = solver.order();
                        let mut s = solver.state_mut();
                        self.evals
                            .rhs(s.y.batch_as_slice(0), u, s.dy.batch_as_mut_slice(0));
                        s.set_step_size(dt, &problem.atol, problem.rtol, &problem.eqn, order);
                    }
                    solver.set_stop_time((k + 1) as f64 * dt)?;
                    while !matches!(solver.step()?, OdeSolverStopReason::TstopReached) {}
                    let st = solver.state();
                    let t = st.t;
                    samples.push(Sample::of(
                        self.model,
                        t,
                        self.input.value(t),
                        st.y.batch_as_slice(0),
                    ));
                }
            }
        }
        Ok((samples, solver.get_statistics().clone()))
    }
}
