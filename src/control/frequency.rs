//! Frequency response G(jω) = C (jωI − A)⁻¹ B + D, the small-signal check against the
//! nonlinear simulation, and step responses of the linear and the nonlinear model.
//!
//! G(jω) is evaluated with a complex LU on the scaled matrices: x = S x̃ with S the state
//! scales (charges of 1e-9 C beside angles of 1e-2 rad), then a Parlett–Reinsch balancing, so
//! that the pivots of jωI − Ã are of comparable size across the nine decades of eigenvalues.

use nalgebra::{Complex, DMatrix, DVector};

use super::linearize::{Linearization, StateSpace};
use super::{ControlError, linalg};
use crate::model::Platform;
use crate::simulation::Sample;
use crate::simulation::{Input, SimError, Simulator, Tone};
use crate::solver::{OdeSystem, Radau5, RhsError, SolverError, Tolerances};

/// Steps a check's nonlinear simulation may take: a few thousand suffice at any sensible
/// voltage; extreme voltages (1e12 V) make the electrical transients so stiff that a run
/// would grind on for minutes, and the check is reported as failed instead.
const STEP_BUDGET: usize = 200_000;

/// An eigenvalue of the minimal model on or right of the imaginary axis, if there is one:
/// then there is no steady state to compare, and the runs would only chase the instability.
fn unstable(lin: &Linearization) -> Option<Complex<f64>> {
    lin.minimal_eigenvalues
        .iter()
        .copied()
        .find(|e| e.re >= 0.0)
}

/// `sim.run_at(input, times, …)` in chunks, giving up past [`STEP_BUDGET`] steps.
fn run_budgeted(
    sim: &mut Simulator,
    input: &Input,
    times: &[f64],
    mut on_sample: impl FnMut(&Sample),
) -> Result<(), SimError> {
    for chunk in times.chunks(4) {
        sim.run_at(input, chunk, &mut on_sample)?;
        let st = sim.stats();
        if st.accepted + st.rejected > STEP_BUDGET {
            return Err(SimError::Solver(SolverError::TooManySteps {
                t: sim.t(),
                limit: STEP_BUDGET,
            }));
        }
    }
    Ok(())
}

/// A state-space model prepared for evaluating G(jω): scaled and balanced.
#[derive(Clone, Debug)]
pub struct Evaluator {
    a: DMatrix<f64>,
    b: DMatrix<f64>,
    c: DMatrix<f64>,
    d: DMatrix<f64>,
    /// x = back · x̂ (diagonal: the state scales times the balancing).
    back: Vec<f64>,
}

impl Evaluator {
    pub fn new(sys: &StateSpace) -> Evaluator {
        let mut a = linalg::scale_similar(&sys.a, &sys.scales);
        let bal = if a.nrows() > 0 && linalg::finite(&a) {
            nalgebra::linalg::balancing::balance_parlett_reinsch(&mut a)
        } else {
            DVector::from_element(a.nrows(), 1.0)
        };
        let back: Vec<f64> = sys
            .scales
            .iter()
            .zip(bal.iter())
            .map(|(s, d)| s * d)
            .collect();
        Evaluator {
            a,
            b: linalg::scale_rows(&sys.b, &back),
            c: linalg::scale_columns(&sys.c, &back),
            d: sys.d.clone(),
            back,
        }
    }

    /// (jωI − Â)⁻¹ B̂ (scaled and balanced states).
    fn resolvent_b(&self, omega: f64) -> Result<DMatrix<Complex<f64>>, ControlError> {
        let n = self.a.nrows();
        let m = DMatrix::from_fn(n, n, |r, c| {
            Complex::new(-self.a[(r, c)], if r == c { omega } else { 0.0 })
        });
        let rhs = self.b.map(|v| Complex::new(v, 0.0));
        m.lu().solve(&rhs).ok_or(ControlError::Numerics {
            what: "frequency response",
            why: "jωI − A is singular (an eigenvalue on the imaginary axis)",
        })
    }

    /// G(jω) [output units per V].
    pub fn at(&self, omega: f64) -> Result<DMatrix<Complex<f64>>, ControlError> {
        let x = self.resolvent_b(omega)?;
        let c = self.c.map(|v| Complex::new(v, 0.0));
        Ok(c * x + self.d.map(|v| Complex::new(v, 0.0)))
    }

    /// The state phasor X = (jωI − A)⁻¹ B û for the input phasor û, in SI units.
    fn state_phasor(&self, omega: f64, u: [f64; 3]) -> Result<Vec<Complex<f64>>, ControlError> {
        let x = self.resolvent_b(omega)?;
        Ok((0..x.nrows())
            .map(|r| (0..3).map(|j| x[(r, j)] * u[j]).sum::<Complex<f64>>() * self.back[r])
            .collect())
    }
}

/// `per_decade` logarithmically spaced frequencies from `f_lo` to `f_hi` \[Hz\], both included.
pub fn log_grid(f_lo: f64, f_hi: f64, per_decade: usize) -> Vec<f64> {
    let decades = (f_hi / f_lo).log10();
    let n = ((decades * per_decade as f64).round() as usize).max(1);
    (0..=n)
        .map(|k| f_lo * 10f64.powf(decades * k as f64 / n as f64))
        .collect()
}

/// G(j 2π f) on a grid of frequencies f \[Hz\].
pub fn response(
    sys: &StateSpace,
    freqs: &[f64],
) -> Result<Vec<DMatrix<Complex<f64>>>, ControlError> {
    let ev = Evaluator::new(sys);
    freqs
        .iter()
        .map(|f| ev.at(2.0 * std::f64::consts::PI * f))
        .collect()
}

/// The nonlinear model's response to a small sine around an equilibrium, against the
/// linearization's prediction, for one output at one frequency.
#[derive(Clone, Debug, PartialEq)]
pub struct SineCheck {
    /// \[Hz\]
    pub frequency: f64,
    /// Index into the outputs (h1..h3, tip_x, tip_y, tip_z).
    pub output: usize,
    /// The predicted and the measured phasor of δy per volt of amplitude (gain and phase).
    pub linear: Complex<f64>,
    pub nonlinear: Complex<f64>,
}

impl SineCheck {
    /// |nonlinear/linear| − 1.
    pub fn gain_error(&self) -> f64 {
        self.nonlinear.norm() / self.linear.norm() - 1.0
    }
    /// arg(nonlinear) − arg(linear) \[rad\], in (−π, π].
    pub fn phase_error(&self) -> f64 {
        (self.nonlinear / self.linear).arg()
    }
}

/// Drives the nonlinear model from its equilibrium with U = u0 + a sin(2π f t) on every
/// actuator (the same phase) at each frequency, and measures each output's first harmonic
/// over two periods after one period of settling (least squares on sin, cos, a mean and a
/// drift). The run starts from the linear model's
/// periodic state x0 + Im X̂, so what remains of a transient is of second order. Outputs
/// whose predicted response is below 1e-6 of the largest are left out (an actuator at 0 V
/// does not respond to first order: its force goes with U²).
pub fn sine_check(
    model: &Platform,
    lin: &Linearization,
    amplitude: f64,
    freqs: &[f64],
    rtol: f64,
) -> Result<Vec<SineCheck>, ControlError> {
    if let Some(e) = unstable(lin) {
        return Err(ControlError::NotStable {
            eigenvalue: (e.re, e.im),
        });
    }
    let minimal = lin.minimal();
    let full = Evaluator::new(&lin.system);
    let ev = Evaluator::new(&minimal);
    let mut out = Vec::new();
    for &f in freqs {
        let omega = 2.0 * std::f64::consts::PI * f;
        let g = ev.at(omega)?;
        let predicted: Vec<Complex<f64>> = (0..6)
            .map(|r| (0..3).map(|j| g[(r, j)]).sum::<Complex<f64>>())
            .collect();
        let largest = predicted.iter().map(|p| p.norm()).fold(0.0, f64::max);
        // start on the periodic solution of the linear model: δx(0) = Im X̂ for a sin(ωt)
        let phasor = full.state_phasor(omega, [amplitude; 3])?;
        let x_start: Vec<f64> = lin.x0.iter().zip(&phasor).map(|(x, p)| x + p.im).collect();
        let input = Input::Tones {
            offset: lin.u0,
            tones: [0, 1, 2].map(|_| {
                vec![Tone {
                    amplitude,
                    omega,
                    phase: 0.0,
                }]
            }),
        };
        let period = 1.0 / f;
        let per_period = 256;
        let times: Vec<f64> = (0..2 * per_period)
            .map(|k| period * (1.0 + k as f64 / per_period as f64))
            .collect();
        let mut sim = Simulator::from_state(model.clone(), 0.0, &x_start, rtol)?;
        let mut samples: Vec<(f64, [f64; 6])> = Vec::with_capacity(times.len());
        run_budgeted(&mut sim, &input, &times, |s| {
            let y = [s.h[0], s.h[1], s.h[2], s.tip[0], s.tip[1], s.tip[2]];
            samples.push((s.t, [0, 1, 2, 3, 4, 5].map(|r| y[r] - lin.y0[r])));
        })?;
        // least squares δy ≈ s sin ωt + c cos ωt + d0 + d1 (t − t_mid): the mean and the drift
        // take up the second-order shift of the mean (U² in the force), which settles with the
        // slow modes and would otherwise leak into the first harmonic
        let t_mid = 0.5 * (times[0] + times[times.len() - 1]);
        let basis = |t: f64| {
            let (sin, cos) = (omega * t).sin_cos();
            [sin, cos, 1.0, (t - t_mid) / period]
        };
        let mut normal = nalgebra::Matrix4::<f64>::zeros();
        for &(t, _) in &samples {
            let b = nalgebra::Vector4::from(basis(t));
            normal += b * b.transpose();
        }
        let Some(inverse) = normal.try_inverse() else {
            return Err(ControlError::Numerics {
                what: "small-signal check",
                why: "singular least-squares problem",
            });
        };
        for r in 0..6 {
            if predicted[r].norm() <= 1e-6 * largest {
                continue;
            }
            let mut rhs = nalgebra::Vector4::<f64>::zeros();
            for (t, dy) in &samples {
                rhs += nalgebra::Vector4::from(basis(*t)) * dy[r];
            }
            let coef = inverse * rhs;
            // δy = s sin ωt + c cos ωt = Im((s + j c) e^{jωt}): the phasor is s + j c
            out.push(SineCheck {
                frequency: f,
                output: r,
                linear: predicted[r],
                nonlinear: Complex::new(coef[0], coef[1]) / amplitude,
            });
        }
    }
    Ok(out)
}

/// The linear ODE δẋ = A δx + B δU (scaled), for the step response by the same Radau IIA
/// integrator as the model.
struct LinearOde<'a> {
    a: &'a DMatrix<f64>,
    forcing: DVector<f64>,
}

impl OdeSystem for LinearOde<'_> {
    fn dim(&self) -> usize {
        self.a.nrows()
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), RhsError> {
        let n = self.dim();
        for (r, d) in dy.iter_mut().enumerate().take(n) {
            *d = self.forcing[r] + (0..n).map(|c| self.a[(r, c)] * y[c]).sum::<f64>();
        }
        Ok(())
    }
    fn jacobian(&self, _t: f64, _y: &[f64], jac: &mut [f64]) -> Result<(), RhsError> {
        jac.copy_from_slice(self.a.as_slice());
        Ok(())
    }
}

/// The response of the outputs to a voltage step δU at t = 0, linear beside nonlinear.
#[derive(Clone, Debug, PartialEq)]
pub struct StepComparison {
    pub du: [f64; 3],
    pub t: Vec<f64>,
    /// δy(t) of the linear model \[m\] (the integration fails only if the linearization is
    /// unstable enough to overflow).
    pub linear: Result<Vec<[f64; 6]>, SimError>,
    /// δy(t) of the nonlinear model: the run with the step minus the run without it \[m\]; or
    /// why the simulation failed (the linear model is reported all the same).
    pub nonlinear: Result<Vec<[f64; 6]>, SimError>,
}

impl StepComparison {
    /// max_t |linear − nonlinear| per output, relative to max_t |nonlinear| of that output.
    pub fn relative_errors(&self) -> Option<[f64; 6]> {
        let nonlinear = self.nonlinear.as_ref().ok()?;
        let linear = self.linear.as_ref().ok()?;
        Some([0, 1, 2, 3, 4, 5].map(|r| {
            let peak = nonlinear.iter().map(|y| y[r].abs()).fold(0.0, f64::max);
            let err = linear
                .iter()
                .zip(nonlinear)
                .map(|(l, n)| (l[r] - n[r]).abs())
                .fold(0.0, f64::max);
            if peak > 0.0 { err / peak } else { err }
        }))
    }
}

/// The step response to δU from the point the simulator `start` is at (the linearization's
/// point, with the command `u0` held there; its model's delay, if any, shifts the linear
/// response), at `samples` + 1 times from 0 to `t_end`.
pub fn step_comparison(
    start: &Simulator,
    lin: &Linearization,
    u0: [f64; 3],
    du: [f64; 3],
    t_end: f64,
    samples: usize,
) -> Result<StepComparison, ControlError> {
    if !(t_end.is_finite() && t_end > 0.0) {
        return Err(ControlError::Setting {
            name: "step duration [s]",
            value: t_end,
        });
    }
    let t0 = start.t();
    let t: Vec<f64> = (0..=samples)
        .map(|k| t_end * k as f64 / samples as f64)
        .collect();
    if let Some(e) = unstable(lin) {
        let skipped = || {
            Err(SimError::Setting(format!(
                "skipped: the linearization is unstable (eigenvalue {:.4e} {:+.4e}i)",
                e.re, e.im
            )))
        };
        return Ok(StepComparison {
            du,
            t,
            linear: skipped(),
            nonlinear: skipped(),
        });
    }
    let times: Vec<f64> = t.iter().map(|s| t0 + s).collect();
    let run = |u: [f64; 3]| -> Result<Vec<[f64; 6]>, SimError> {
        let mut sim = start.clone();
        let mut y = Vec::with_capacity(times.len());
        run_budgeted(&mut sim, &Input::constant(u), &times, |s| {
            y.push([s.h[0], s.h[1], s.h[2], s.tip[0], s.tip[1], s.tip[2]]);
        })?;
        Ok(y)
    };
    let nonlinear = run([0, 1, 2].map(|i| u0[i] + du[i])).and_then(|stepped| {
        let baseline = run(u0)?;
        Ok(stepped
            .iter()
            .zip(&baseline)
            .map(|(s, b)| [0, 1, 2, 3, 4, 5].map(|r| s[r] - b[r]))
            .collect())
    });

    // the linear model in scaled states, integrated to the same times (shifted by the delay)
    let sys = &lin.system;
    let a = linalg::scale_similar(&sys.a, &sys.scales);
    let b = linalg::scale_rows(&sys.b, &sys.scales);
    let c = linalg::scale_columns(&sys.c, &sys.scales);
    let du_v = DVector::from_column_slice(&du);
    let ode = LinearOde {
        a: &a,
        forcing: &b * &du_v,
    };
    let n = a.nrows();
    let delay = start.model().params().effects.delay.tau_d;
    let lin_times: Vec<f64> = t.iter().map(|s| (s - delay).max(0.0)).collect();
    let integrate = || -> Result<Vec<[f64; 6]>, SimError> {
        let tol = Tolerances {
            rtol: 1e-9,
            atol: vec![1e-12; n],
        };
        let mut solver = Radau5::new(n, tol);
        solver.init(&ode, 0.0, &vec![0.0; n], 1e-10)?;
        let mut linear = Vec::with_capacity(t.len());
        let mut x = vec![0.0; n];
        let t_last = lin_times.last().copied().unwrap_or(0.0);
        let mut k = 0;
        loop {
            while k < lin_times.len() && lin_times[k] <= solver.t() {
                if lin_times[k] == 0.0 {
                    x.fill(0.0);
                } else {
                    solver.interpolate(lin_times[k], &mut x);
                }
                let y = &c * DVector::from_column_slice(&x) + &sys.d * &du_v;
                linear.push([0, 1, 2, 3, 4, 5].map(|r| y[r]));
                k += 1;
            }
            if k == lin_times.len() {
                return Ok(linear);
            }
            solver.step(&ode, t_last)?;
        }
    };
    let linear = integrate();
    Ok(StepComparison {
        du,
        t,
        linear,
        nonlinear,
    })
}
