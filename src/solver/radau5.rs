//! Radau IIA of order 5 with step-size control, after Hairer & Wanner (1996), IV.8:
//! simplified Newton on the stage equations, decoupled by the eigen-transformation of A⁻¹ into
//! one real and one complex n×n system; the embedded error estimate filtered through
//! (I − γ0 h J)⁻¹; Gustafsson's predictive step-size controller; Jacobian reuse while Newton
//! converges fast; the collocation polynomial for dense output and Newton starting values.
//!
//! All work arrays are allocated in [`Radau5::new`]; stepping allocates nothing. The whole
//! integrator state is `Clone` and serde-serialisable, so a restored copy replays bit for bit.

use nalgebra::Complex;
use serde::{Deserialize, Serialize};

use super::lu::{self, BlockLu};
use super::{OdeSystem, RhsError, SolverError, Stats, Tolerances};

const SQRT6: f64 = 2.449_489_742_783_178;
/// Collocation nodes c1, c2 (c3 = 1).
pub(super) const C1: f64 = (4.0 - SQRT6) / 10.0;
pub(super) const C2: f64 = (4.0 + SQRT6) / 10.0;
pub(super) const C1M1: f64 = C1 - 1.0;
pub(super) const C2M1: f64 = C2 - 1.0;
pub(super) const C1MC2: f64 = C1 - C2;
/// The coefficients a_kl (Hairer & Wanner IV.5, Table 5.6); the iteration uses their
/// transformed inverse (T, TI and the eigenvalues below), the sensitivities the matrix itself.
pub(super) const A: [[f64; 3]; 3] = [
    [
        (88.0 - 7.0 * SQRT6) / 360.0,
        (296.0 - 169.0 * SQRT6) / 1800.0,
        (-2.0 + 3.0 * SQRT6) / 225.0,
    ],
    [
        (296.0 + 169.0 * SQRT6) / 1800.0,
        (88.0 + 7.0 * SQRT6) / 360.0,
        (-2.0 - 3.0 * SQRT6) / 225.0,
    ],
    [(16.0 - SQRT6) / 36.0, (16.0 + SQRT6) / 36.0, 1.0 / 9.0],
];
/// Error-estimate weights (Hairer & Wanner IV.8.20, scaled by 1/γ0).
const DD: [f64; 3] = [
    -(13.0 + 7.0 * SQRT6) / 3.0,
    (-13.0 + 7.0 * SQRT6) / 3.0,
    -1.0 / 3.0,
];
/// T and T⁻¹ with T⁻¹ A⁻¹ T = diag(γ, [[α, −β], [β, α]]) (verified in the tests).
#[allow(clippy::excessive_precision)] // the published 20-digit values, rounded by the compiler
const T: [[f64; 3]; 3] = [
    [
        9.123_239_487_089_294_3e-2,
        -0.141_255_295_020_954_21,
        -3.002_919_410_514_742_4e-2,
    ],
    [
        0.241_717_932_707_107_02,
        0.204_129_352_293_799_93,
        0.382_942_112_757_261_94,
    ],
    [0.966_048_182_615_092_94, 1.0, 0.0],
];
#[allow(clippy::excessive_precision)]
const TI: [[f64; 3]; 3] = [
    [
        4.325_579_890_063_155_4,
        0.339_199_251_815_809_87,
        0.541_770_539_935_874_87,
    ],
    [
        -4.178_718_591_551_904_7,
        -0.327_682_820_761_062_39,
        0.476_623_554_500_550_45,
    ],
    [
        -0.502_872_634_945_786_88,
        2.571_926_949_855_605_4,
        -0.596_039_204_828_224_92,
    ],
];
/// Newton iterations per step at most.
const NIT: usize = 7;
const UROUND: f64 = 1e-16;
const SAFE: f64 = 0.9;
/// Step-size ratio limits: h_new/h in [1/5, 8].
const FACL: f64 = 5.0;
const FACR: f64 = 0.125;
/// Reuse the Jacobian (and with it the LU factors) while the Newton contraction stays below
/// this: Hairer & Wanner's default, kept for smooth runs.
const THET: f64 = 1e-3;
/// The same after a step that began at an input jump: with the jump predicted, such a step
/// contracts by about 1.2e-3 with a fresh Jacobian, so THET would refactor at almost every held
/// co-simulation step; 1e-2 keeps Newton at 2 iterations a step with a new Jacobian every 4
/// steps at an unchanged error (book/src/solver.md, "Keeping the Jacobian after a jump").
/// Smooth runs keep THET: there the larger bound saved nothing (517 Jacobians instead of 521 on
/// the 10 s sine) and moved a fitted optimum of the identification.
const THET_AFTER_JUMP: f64 = 1e-2;
/// Keep h (and the LU factors) when the proposed ratio lies in [QUOT1, QUOT2].
const QUOT1: f64 = 1.0;
const QUOT2: f64 = 1.2;

/// Eigenvalues of A⁻¹: γ (real) and α ± iβ (the closed forms of [`eigenvalues`], as constants
/// so that no step recomputes them).
const GAMMA: f64 = 3.637_834_252_744_496;
const ALPHA: f64 = 2.681_082_873_627_752;
const BETA: f64 = 3.050_430_199_247_410_5;

/// The closed forms of GAMMA, ALPHA, BETA (checked against them in the tests).
#[cfg(test)]
fn eigenvalues() -> (f64, f64, f64) {
    let (c81, c9) = (81f64.cbrt(), 9f64.cbrt());
    let gamma = 30.0 / (6.0 + c81 - c9);
    let alpha = (12.0 - c81 + c9) / 60.0;
    let beta = (c81 + c9) * 3f64.sqrt() / 60.0;
    let cno = alpha * alpha + beta * beta;
    (gamma, alpha / cno, beta / cno)
}

/// m v for the 3 × 3 transformations T and T⁻¹ of the stage vectors.
#[inline(always)]
fn mul3(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    m.map(|r| r[0] * v[0] + r[1] * v[1] + r[2] * v[2])
}

/// x^(1/4) by two square roots (one instruction each, where `powf` is a call of a few hundred).
fn fourth_root(x: f64) -> f64 {
    x.sqrt().sqrt()
}

/// The system's failure to evaluate at time `t`, as the solver reports it.
fn at(t: f64) -> impl FnOnce(RhsError) -> SolverError {
    move |e| SolverError::Rhs { t, message: e.0 }
}

/// The three stage parts [0, n), [n, 2n) and [2n, 3n) of a stage vector.
fn stages(v: &[f64], n: usize) -> [&[f64]; 3] {
    let (first, rest) = v.split_at(n);
    let (second, third) = rest.split_at(n);
    [first, second, &third[..n]]
}

fn stages_mut(v: &mut [f64], n: usize) -> [&mut [f64]; 3] {
    let (first, rest) = v.split_at_mut(n);
    let (second, third) = rest.split_at_mut(n);
    [first, second, &mut third[..n]]
}

/// The Radau IIA(5) integrator and its whole state.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Radau5 {
    n: usize,
    tol: Tolerances,
    /// Internal tolerances (Hairer's transformation rtol' = 0.1 rtol^(2/3)).
    rtol_int: f64,
    atol_int: Vec<f64>,
    fnewt: f64,
    /// Largest step size \[s\].
    pub h_max: f64,
    /// Most steps one call to [`Radau5::advance`] may take.
    max_steps: usize,
    t: f64,
    y: Vec<f64>,
    /// f(t, y) at the current point.
    f0: Vec<f64>,
    /// The step size the next step will try.
    h: f64,
    /// The last accepted step [t_old, t_old + h_old], for dense output.
    t_old: f64,
    h_old: f64,
    /// Collocation polynomial of the last step: y(t + s h_old) = y + s (c0 + (s − c2 + 1)(c1 + (s − c1 + 1) c2)).
    cont: Vec<f64>,
    have_poly: bool,
    z: Vec<f64>,
    w: Vec<f64>,
    stage_f: Vec<f64>,
    work: Vec<f64>,
    err_vec: Vec<f64>,
    /// 1/(atol_int + rtol_int |y|): the error weights, as reciprocals so that the norms
    /// multiply (a division costs several multiplications, and the norms take hundreds a step).
    inv_scal: Vec<f64>,
    jac: Vec<f64>,
    /// The factors of E1 = (γ/h) I − J and E2 = ((α + iβ)/h) I − J, block by block.
    e1: BlockLu<f64>,
    e2: BlockLu<Complex<f64>>,
    rhs2: Vec<Complex<f64>>,
    /// The Jacobian was evaluated at the current point.
    jac_current: bool,
    /// The next step must evaluate a new Jacobian.
    need_jac: bool,
    /// The step size the LU factors belong to (NaN: none).
    lu_h: f64,
    first: bool,
    reject: bool,
    faccon: f64,
    theta: f64,
    h_acc: f64,
    err_acc: f64,
    stats: Stats,
    /// The system jumped at the current point: filter the next error estimate twice.
    after_jump: bool,
    /// How much f jumped at the current point, f(t, y) after minus before (the sum over the
    /// restarts since the last accepted step; unknown before the first step, where no f before
    /// the jump was evaluated at this state).
    jump: Vec<f64>,
    /// The last accepted step began at a jump: its polynomial's node at the step's start
    /// holds the state before the jump's transient, so Newton's starting values extrapolate
    /// only through its three stages.
    poly_jumped: bool,
    /// f0 is the last Newton iteration's f at the third stage of a step that landed on a
    /// requested time, not yet f(t, y): a restart or the next step evaluates it.
    f0_pending: bool,
}

/// What [`Radau5::last_step`] shows of the last accepted step [t_old, t_old + h].
pub(super) struct LastStep<'a> {
    pub(super) t_old: f64,
    pub(super) h: f64,
    /// The state at its end, y(t_old) + Z3.
    pub(super) y: &'a [f64],
    /// Stage increments Z_k = Y_k − y(t_old), stage k at [k n, (k + 1) n).
    pub(super) z: &'a [f64],
    /// Sizes of the diagonal blocks of J.
    pub(super) blocks: &'a [usize],
    pub(super) n: usize,
}

enum Newton {
    Converged(usize),
    /// Diverging or too slow: retry with h multiplied by this factor.
    Failed(f64, String),
}

impl Radau5 {
    /// An integrator for `n` states; call [`Radau5::init`] before stepping.
    pub fn new(n: usize, tol: Tolerances) -> Radau5 {
        assert_eq!(tol.atol.len(), n, "one absolute tolerance per state");
        let rtol_int = 0.1 * tol.rtol.powf(2.0 / 3.0);
        let atol_int = tol.atol.iter().map(|a| a * rtol_int / tol.rtol).collect();
        let zero_c = Complex::new(0.0, 0.0);
        Radau5 {
            n,
            fnewt: (10.0 * UROUND / rtol_int).max(0.03f64.min(rtol_int.sqrt())),
            rtol_int,
            atol_int,
            tol,
            h_max: f64::INFINITY,
            max_steps: super::MAX_STEPS,
            t: 0.0,
            y: vec![0.0; n],
            f0: vec![0.0; n],
            h: 1e-6,
            t_old: 0.0,
            h_old: 0.0,
            cont: vec![0.0; 3 * n],
            have_poly: false,
            z: vec![0.0; 3 * n],
            w: vec![0.0; 3 * n],
            stage_f: vec![0.0; 3 * n],
            work: vec![0.0; n],
            err_vec: vec![0.0; n],
            inv_scal: vec![0.0; n],
            jac: vec![0.0; n * n],
            e1: BlockLu::new(vec![n]),
            e2: BlockLu::new(vec![n]),
            rhs2: vec![zero_c; n],
            jac_current: false,
            need_jac: true,
            lu_h: f64::NAN,
            first: true,
            reject: false,
            faccon: 1.0,
            theta: 0.0,
            h_acc: 0.0,
            err_acc: 0.0,
            stats: Stats::default(),
            after_jump: false,
            jump: vec![0.0; n],
            poly_jumped: false,
            f0_pending: false,
        }
    }

    /// Starts at (t, y) with a first step of `h0` seconds, forgetting all history.
    pub fn init<S: OdeSystem>(
        &mut self,
        sys: &S,
        t: f64,
        y: &[f64],
        h0: f64,
    ) -> Result<(), SolverError> {
        self.t = t;
        self.y.copy_from_slice(y);
        self.h = h0;
        self.have_poly = false;
        self.need_jac = true;
        self.jac_current = false;
        self.lu_h = f64::NAN;
        self.first = true;
        self.reject = false;
        let blocks = sys.jacobian_blocks();
        assert_eq!(
            blocks.iter().sum::<usize>(),
            self.n,
            "Jacobian blocks must cover the states"
        );
        if blocks != self.e1.blocks() {
            self.e2 = BlockLu::new(blocks.clone());
            self.e1 = BlockLu::new(blocks);
        }
        self.update_scal();
        self.restart(sys)
    }

    /// Continues after a discontinuity of the system at the current point (an input jump): f is
    /// re-evaluated and the next error estimate made stiffly accurate. The step size and the
    /// Jacobian carry over (the solution is continuous, the simplified Newton iteration
    /// tolerates an approximate Jacobian, and the error control shrinks the step if the jump
    /// needs it); the next step's Newton starting values add the stages' linear response to
    /// the jump of f (`Radau5::predict_jump`).
    pub fn restart<S: OdeSystem>(&mut self, sys: &S) -> Result<(), SolverError> {
        sys.rhs(self.t, &self.y, &mut self.work)
            .map_err(at(self.t))?;
        self.stats.rhs_evals += 1;
        if !self.after_jump {
            self.jump.fill(0.0);
        }
        for ((j, f0), f) in self.jump.iter_mut().zip(self.f0.iter_mut()).zip(&self.work) {
            *j += f - *f0;
            *f0 = *f;
        }
        self.f0_pending = false;
        self.after_jump = true;
        self.faccon = 1.0;
        Ok(())
    }

    pub fn t(&self) -> f64 {
        self.t
    }

    pub fn y(&self) -> &[f64] {
        &self.y
    }

    pub fn stats(&self) -> Stats {
        self.stats
    }

    fn update_scal(&mut self) {
        for i in 0..self.n {
            self.inv_scal[i] = 1.0 / (self.atol_int[i] + self.rtol_int * self.y[i].abs());
        }
    }

    /// Integrates until t = `t_end` exactly (the last step is cut to land on it).
    pub fn advance<S: OdeSystem>(&mut self, sys: &S, t_end: f64) -> Result<(), SolverError> {
        let mut steps = 0;
        while self.t < t_end {
            if steps == self.max_steps {
                return Err(SolverError::TooManySteps {
                    t: self.t,
                    limit: self.max_steps,
                });
            }
            self.step(sys, t_end)?;
            steps += 1;
        }
        Ok(())
    }

    /// Value of the last step's collocation polynomial at `t` in [t_old, t] (dense output,
    /// order 3 in between the step's nodes, exact at them).
    pub fn interpolate(&self, t: f64, out: &mut [f64]) {
        if !self.have_poly || self.h_old == 0.0 {
            out.copy_from_slice(&self.y);
            return;
        }
        let s = (t - self.t) / self.h_old;
        let n = self.n;
        for (i, o) in out.iter_mut().enumerate().take(n) {
            let (a1, a2, a3) = (self.cont[i], self.cont[n + i], self.cont[2 * n + i]);
            *o = self.y[i] + s * (a1 + (s - C2M1) * (a2 + (s - C1M1) * a3));
        }
    }

    /// Takes one accepted step, never past `t_end`.
    pub fn step<S: OdeSystem>(&mut self, sys: &S, t_end: f64) -> Result<(), SolverError> {
        if self.f0_pending {
            sys.rhs(self.t, &self.y, &mut self.f0).map_err(at(self.t))?;
            self.stats.rhs_evals += 1;
            self.f0_pending = false;
        }
        let h_entry = self.h.min(self.h_max);
        let mut h = h_entry;
        let mut last = false;
        if self.t + 1.05 * h >= t_end {
            h = t_end - self.t;
            last = true;
        }
        loop {
            if 0.1 * h.abs() <= self.t.abs() * UROUND || h <= 0.0 {
                return Err(SolverError::StepTooSmall {
                    t: self.t,
                    h,
                    reason: "repeated step rejections".into(),
                });
            }
            if self.need_jac {
                sys.jacobian(self.t, &self.y, &mut self.jac)
                    .map_err(at(self.t))?;
                self.stats.jac_evals += 1;
                self.need_jac = false;
                self.jac_current = true;
                self.lu_h = f64::NAN;
            }
            // a step cut to land on t_end differs from the factored h by the rounding of
            // t_end − t, a few ulps of t: 1.8e-12 of a 1 ms step at t = 10 s, where a bound
            // relative to h alone refactored every other held step (lu_h is NaN when there are
            // no factors)
            let rounding = 4.0 * f64::EPSILON * t_end.abs().max(self.t.abs());
            let factored = (h - self.lu_h).abs() <= 1e-12 * h + rounding;
            if !factored && let Err(lu::Singular(col)) = self.decompose(h) {
                h *= 0.5;
                self.reject = true;
                last = false;
                if 0.1 * h <= self.t.abs() * UROUND {
                    return Err(SolverError::StepTooSmall {
                        t: self.t,
                        h,
                        reason: format!("singular iteration matrix at column {col}"),
                    });
                }
                continue;
            }
            self.starting_values(h);
            // (before the first step there is no jump measured: see `jump`)
            if self.after_jump && self.have_poly {
                self.predict_jump();
            }
            let newt = match self.newton(sys, h) {
                Newton::Converged(k) => k,
                Newton::Failed(factor, reason) => {
                    h *= factor;
                    self.reject = true;
                    last = false;
                    self.need_jac = !self.jac_current;
                    if 0.1 * h <= self.t.abs() * UROUND {
                        return Err(SolverError::StepTooSmall {
                            t: self.t,
                            h,
                            reason,
                        });
                    }
                    continue;
                }
            };
            let err = self.error_estimate(sys, h);
            // new step size (Hairer & Wanner IV.8.21-8.24)
            let fac = SAFE.min(SAFE * (1 + 2 * NIT) as f64 / (newt + 2 * NIT) as f64);
            let mut quot = (fourth_root(err) / fac).clamp(FACR, FACL);
            let mut h_new = h / quot;
            if err < 1.0 {
                for i in 0..self.n {
                    self.work[i] = self.y[i] + self.z[2 * self.n + i];
                }
                let t_new = if last { t_end } else { self.t + h };
                if last {
                    // a requested time, where an input jump usually follows and its restart
                    // evaluates f anyway: meanwhile f there is the one the last Newton iteration
                    // evaluated at its third stage (within the Newton tolerance of y + Z3), and
                    // without a restart the next step evaluates it (`f0_pending`)
                    self.err_vec
                        .copy_from_slice(&self.stage_f[2 * self.n..3 * self.n]);
                    self.f0_pending = true;
                } else if let Err(e) = sys.rhs(t_new, &self.work, &mut self.err_vec) {
                    // the new end point must be evaluable before the step is committed
                    h *= 0.5;
                    self.reject = true;
                    last = false;
                    self.need_jac = !self.jac_current;
                    if 0.1 * h <= self.t.abs() * UROUND {
                        return Err(SolverError::StepTooSmall {
                            t: self.t,
                            h,
                            reason: e.0,
                        });
                    }
                    continue;
                } else {
                    self.stats.rhs_evals += 1;
                }
                if self.stats.accepted > 0 && !self.first {
                    let fac_gus = ((self.h_acc / h) * fourth_root(err * err / self.err_acc) / SAFE)
                        .clamp(FACR, FACL);
                    quot = quot.max(fac_gus);
                    h_new = h / quot;
                }
                self.h_acc = h;
                self.err_acc = err.max(1e-2);
                self.accept(h, t_new);
                let rejected_here = self.reject;
                if rejected_here {
                    h_new = h_new.min(h);
                }
                self.reject = false;
                self.first = false;
                let thet = if self.after_jump {
                    THET_AFTER_JUMP
                } else {
                    THET
                };
                self.after_jump = false;
                self.stats.accepted += 1;
                self.need_jac = self.theta > thet;
                self.jac_current = false;
                let ratio = h_new / h;
                self.h = if last && !rejected_here {
                    // a step cut to land on t_end says little: resume with the size before the cut
                    h_entry.max(h_new.min(self.h_max))
                } else if !self.need_jac && (QUOT1..=QUOT2).contains(&ratio) {
                    // keep h, and with it the LU factors, while J is reused
                    h
                } else {
                    h_new.min(self.h_max)
                };
                return Ok(());
            }
            // rejected
            self.reject = true;
            last = false;
            if self.stats.accepted > 0 {
                self.stats.rejected += 1;
            }
            h = if self.first { 0.1 * h } else { h_new };
            self.need_jac = !self.jac_current;
        }
    }

    /// E1 = (γ/h) I − J and E2 = ((α + iβ)/h) I − J, factored.
    fn decompose(&mut self, h: f64) -> Result<(), lu::Singular> {
        self.stats.decompositions += 1;
        self.lu_h = f64::NAN;
        self.e1.factor_shifted(GAMMA / h, &self.jac)?;
        self.e2
            .factor_shifted(Complex::new(ALPHA / h, BETA / h), &self.jac)?;
        self.lu_h = h;
        Ok(())
    }

    /// Newton starting values: zero on a first step, else the last step's collocation
    /// polynomial extrapolated to the new nodes.
    fn starting_values(&mut self, h: f64) {
        let n = self.n;
        if self.first || !self.have_poly {
            self.z.fill(0.0);
            self.w.fill(0.0);
            return;
        }
        let c3q = h / self.h_old;
        let cq = [C1 * c3q, C2 * c3q, c3q];
        // the Newton form's last term is the one through the step's start: dropping it leaves
        // the quadratic through the three stages
        let through_start = if self.poly_jumped { 0.0 } else { 1.0 };
        for i in 0..n {
            let (a1, a2, a3) = (
                self.cont[i],
                self.cont[n + i],
                through_start * self.cont[2 * n + i],
            );
            let mut zi = [0.0; 3];
            for k in 0..3 {
                zi[k] = cq[k] * (a1 + (cq[k] - C2M1) * (a2 + (cq[k] - C1M1) * a3));
                self.z[k * n + i] = zi[k];
            }
            for (k, wk) in mul3(&TI, zi).into_iter().enumerate() {
                self.w[k * n + i] = wk;
            }
        }
    }

    /// Adds the stages' linear response to the jump of f at the current point to the
    /// starting values: with F → F + Δf at every stage, the simplified Newton system
    /// (Λ/h ⊗ I − I ⊗ J) ΔW = (T⁻¹ ⊗ I)(1 ⊗ Δf) gives ΔW with one pair of the solves
    /// already factored and no evaluation of f (book/src/solver.md, "The input jump
    /// predicted"). The extrapolated polynomial knows nothing of the jump; without this the
    /// first Newton iteration spends three evaluations of f to learn it, and the contraction it
    /// measures then forces a new Jacobian.
    fn predict_jump(&mut self) {
        let n = self.n;
        let s = TI.map(|r| r[0] + r[1] + r[2]);
        let (d1, d2) = (&mut self.err_vec[..n], &mut self.rhs2[..n]);
        for ((d1, d2), j) in d1.iter_mut().zip(d2.iter_mut()).zip(&self.jump) {
            *d1 = s[0] * j;
            *d2 = Complex::new(s[1] * j, s[2] * j);
        }
        self.e1.solve(d1);
        self.e2.solve(d2);
        let [w1, w2, w3] = stages_mut(&mut self.w, n);
        let [z1, z2, z3] = stages_mut(&mut self.z, n);
        let (d1, d2) = (&self.err_vec[..n], &self.rhs2[..n]);
        for i in 0..n {
            let d = [d1[i], d2[i].re, d2[i].im];
            w1[i] += d[0];
            w2[i] += d[1];
            w3[i] += d[2];
            let dz = mul3(&T, d);
            z1[i] += dz[0];
            z2[i] += dz[1];
            z3[i] += dz[2];
        }
    }

    fn newton<S: OdeSystem>(&mut self, sys: &S, h: f64) -> Newton {
        let n = self.n;
        let (fac1, alphn, betan) = (GAMMA / h, ALPHA / h, BETA / h);
        // (after a restart faccon is 1, and so is its power: no call to pow in a held step)
        if self.faccon != 1.0 {
            self.faccon = self.faccon.max(UROUND).powf(0.8);
        }
        self.theta = THET;
        let (mut dynold, mut thqold) = (0.0, 0.0);
        for newt in 1..=NIT {
            for (k, c) in [C1, C2, 1.0].into_iter().enumerate() {
                let zk = &self.z[k * n..(k + 1) * n];
                for ((w, y), z) in self.work.iter_mut().zip(&self.y).zip(zk) {
                    *w = y + z;
                }
                if let Err(e) = sys.rhs(
                    self.t + c * h,
                    &self.work,
                    &mut self.stage_f[k * n..(k + 1) * n],
                ) {
                    return Newton::Failed(0.5, e.0);
                }
            }
            self.stats.rhs_evals += 3;
            self.stats.newton_iterations += 1;
            // right-hand sides of the transformed, decoupled linear systems (every slice of
            // length n, so that the loops index without bounds checks)
            let [f1, f2, f3] = stages(&self.stage_f, n);
            let [w1, w2, w3] = stages(&self.w, n);
            let (z1, rhs2) = (&mut self.z[..n], &mut self.rhs2[..n]);
            for i in 0..n {
                let f = [f1[i], f2[i], f3[i]];
                let a = mul3(&TI, f);
                z1[i] = a[0] - fac1 * w1[i];
                rhs2[i] = Complex::new(
                    a[1] - alphn * w2[i] + betan * w3[i],
                    a[2] - alphn * w3[i] - betan * w2[i],
                );
            }
            self.e1.solve(z1);
            self.e2.solve(rhs2);
            let mut sum = 0.0;
            let [w1, w2, w3] = stages_mut(&mut self.w, n);
            let (z1, rhs2, inv_scal) = (&self.z[..n], &self.rhs2[..n], &self.inv_scal[..n]);
            for i in 0..n {
                let (d1, d2, d3) = (z1[i], rhs2[i].re, rhs2[i].im);
                let w = inv_scal[i];
                sum += (d1 * w).powi(2) + (d2 * w).powi(2) + (d3 * w).powi(2);
                w1[i] += d1;
                w2[i] += d2;
                w3[i] += d3;
            }
            let dyno = (sum / (3 * n) as f64).sqrt();
            if !dyno.is_finite() {
                return Newton::Failed(0.5, "Newton iteration produced a non-finite update".into());
            }
            if newt > 1 && newt < NIT {
                let thq = dyno / dynold;
                self.theta = if newt == 2 {
                    thq
                } else {
                    (thq * thqold).sqrt()
                };
                thqold = thq;
                if self.theta < 0.99 {
                    self.faccon = self.theta / (1.0 - self.theta);
                    let dyth =
                        self.faccon * dyno * self.theta.powi((NIT - 1 - newt) as i32) / self.fnewt;
                    if dyth >= 1.0 {
                        let qnewt = dyth.clamp(1e-4, 20.0);
                        let factor = 0.8 * qnewt.powf(-1.0 / (4.0 + (NIT - 1 - newt) as f64));
                        return Newton::Failed(
                            factor,
                            "Newton iteration converging too slowly".into(),
                        );
                    }
                } else {
                    return Newton::Failed(0.5, "Newton iteration diverging".into());
                }
            }
            dynold = dyno.max(UROUND);
            let [w1, w2, w3] = stages(&self.w, n);
            let [z1, z2, z3] = stages_mut(&mut self.z, n);
            for i in 0..n {
                [z1[i], z2[i], z3[i]] = mul3(&T, [w1[i], w2[i], w3[i]]);
            }
            if self.faccon * dyno <= self.fnewt {
                return Newton::Converged(newt);
            }
        }
        Newton::Failed(0.5, "Newton iteration did not converge".into())
    }

    /// err = ‖(I − γ0 h J)⁻¹ (γ0 h f0 + Σ e_i Z_i)‖, refined once on a first or rejected step
    /// to damp stiff components (Hairer & Wanner IV.8.19-8.20).
    fn error_estimate<S: OdeSystem>(&mut self, sys: &S, h: f64) -> f64 {
        let n = self.n;
        let hee = DD.map(|d| d / h);
        for i in 0..n {
            let f2 = hee[0] * self.z[i] + hee[1] * self.z[n + i] + hee[2] * self.z[2 * n + i];
            self.stage_f[i] = f2;
            self.err_vec[i] = f2 + self.f0[i];
        }
        self.e1.solve(&mut self.err_vec);
        if self.after_jump {
            // a jump leaves a stiff transient that L-stability removes (R(∞) = 0), but the
            // estimate above tends to the jump's size as hλ → −∞; filtering once more through
            // (I − γ0 h J)⁻¹ = (γ/h) E1⁻¹ sends its stiff limit to zero and leaves smooth
            // components unchanged to first order
            self.e1.solve(&mut self.err_vec);
            let fac1 = GAMMA / h;
            for v in self.err_vec.iter_mut() {
                *v *= fac1;
            }
        }
        let mut err = self.weighted_norm();
        if err >= 1.0 && (self.first || self.reject) {
            for i in 0..n {
                self.work[i] = self.y[i] + self.err_vec[i];
            }
            // stage_f[n..2n] is free scratch here
            let (f2, rest) = self.stage_f.split_at_mut(n);
            let f1 = &mut rest[..n];
            if sys.rhs(self.t, &self.work, f1).is_ok() {
                self.stats.rhs_evals += 1;
                for i in 0..n {
                    self.err_vec[i] = f1[i] + f2[i];
                }
                self.e1.solve(&mut self.err_vec);
                err = self.weighted_norm();
            }
        }
        err
    }

    fn weighted_norm(&self) -> f64 {
        let sum: f64 = (0..self.n)
            .map(|i| (self.err_vec[i] * self.inv_scal[i]).powi(2))
            .sum();
        (sum / self.n as f64).sqrt().max(1e-10)
    }

    /// The last accepted step, for quantities integrated alongside the state
    /// (`super::sensitivity`): read right after [`Radau5::step`] returns, while its stage
    /// increments are still in place.
    pub(super) fn last_step(&self) -> LastStep<'_> {
        let n = self.n;
        LastStep {
            t_old: self.t_old,
            h: self.h_old,
            y: &self.y,
            z: &self.z,
            blocks: self.e1.blocks(),
            n,
        }
    }

    /// Commits the step: y ← y + Z3, the dense-output polynomial, f0 (already in err_vec).
    fn accept(&mut self, h: f64, t_new: f64) {
        let n = self.n;
        for i in 0..n {
            let (z1, z2, z3) = (self.z[i], self.z[n + i], self.z[2 * n + i]);
            // divisions by the constants as multiplications by their reciprocals (folded)
            let c1 = (z2 - z3) * (1.0 / C2M1);
            let ak = (z1 - z2) * (1.0 / C1MC2);
            let acont3 = (ak - z1 * (1.0 / C1)) * (1.0 / C2);
            let c2 = (ak - c1) * (1.0 / C1M1);
            self.cont[i] = c1;
            self.cont[n + i] = c2;
            self.cont[2 * n + i] = c2 - acont3;
            self.y[i] = self.work[i];
        }
        self.f0.copy_from_slice(&self.err_vec);
        self.poly_jumped = self.after_jump;
        self.t_old = self.t;
        self.h_old = h;
        self.t = t_new;
        self.have_poly = true;
        self.update_scal();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::RhsError;
    use nalgebra::{Matrix3, Vector3};

    #[test]
    fn transformation_diagonalises_the_inverse_butcher_matrix() {
        let a = Matrix3::from_fn(|r, c| A[r][c]);
        let t = Matrix3::from_fn(|r, c| T[r][c]);
        let ti = Matrix3::from_fn(|r, c| TI[r][c]);
        let (g, al, be) = eigenvalues();
        for (closed, constant) in [(g, GAMMA), (al, ALPHA), (be, BETA)] {
            assert!(
                (closed - constant).abs() <= 1e-15 * constant,
                "{closed} vs {constant}"
            );
        }
        let want = Matrix3::new(g, 0.0, 0.0, 0.0, al, -be, 0.0, be, al);
        let got = ti * a.try_inverse().unwrap() * t;
        assert!((got - want).amax() < 1e-12, "{got}");
        assert!((ti * t - Matrix3::identity()).amax() < 1e-14);
        // c = A·1 sums
        let c = a * Vector3::repeat(1.0);
        assert!((c - Vector3::new(C1, C2, 1.0)).amax() < 1e-15);
    }

    /// Robertson's stiff chemical kinetics, the classic test of stiff solvers.
    struct Robertson;
    impl OdeSystem for Robertson {
        fn dim(&self) -> usize {
            3
        }
        fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), RhsError> {
            dy[0] = -0.04 * y[0] + 1e4 * y[1] * y[2];
            dy[2] = 3e7 * y[1] * y[1];
            dy[1] = -dy[0] - dy[2];
            Ok(())
        }
        fn jacobian(&self, _t: f64, y: &[f64], j: &mut [f64]) -> Result<(), RhsError> {
            let (a, b, c) = (-0.04, 1e4 * y[2], 1e4 * y[1]);
            let d = 6e7 * y[1];
            // columns
            j.copy_from_slice(&[a, -a, 0.0, b, -b - d, d, c, -c, 0.0]);
            Ok(())
        }
    }

    #[test]
    fn solves_robertson_to_the_known_solution() {
        let tol = Tolerances {
            rtol: 1e-8,
            atol: vec![1e-12, 1e-16, 1e-12],
        };
        let mut s = Radau5::new(3, tol);
        s.init(&Robertson, 0.0, &[1.0, 0.0, 0.0], 1e-8).unwrap();
        s.advance(&Robertson, 40.0).unwrap();
        // reference values at t = 40 (Hairer & Wanner's test set)
        let want = [
            0.715_827_068_742_2,
            9.185_534_764_529_9e-6,
            0.284_163_745_722_3,
        ];
        for (y, w) in s.y().iter().zip(want) {
            assert!((y - w).abs() <= 1e-7 * w, "y = {y} vs {w}");
        }
        assert_eq!(s.t(), 40.0);
        assert!(s.stats().accepted < 400, "{:?}", s.stats());
    }

    /// y' = −y + sin t, where the dense output can be checked against the exact solution.
    struct Forced;
    impl OdeSystem for Forced {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), RhsError> {
            dy[0] = -y[0] + t.sin();
            Ok(())
        }
        fn jacobian(&self, _t: f64, _y: &[f64], j: &mut [f64]) -> Result<(), RhsError> {
            j[0] = -1.0;
            Ok(())
        }
    }

    fn forced_exact(t: f64) -> f64 {
        0.5 * (t.sin() - t.cos()) + 1.5 * (-t).exp()
    }

    #[test]
    fn dense_output_and_exact_stops_are_accurate() {
        let mut s = Radau5::new(
            1,
            Tolerances {
                rtol: 1e-9,
                atol: vec![1e-12],
            },
        );
        s.init(&Forced, 0.0, &[1.0], 1e-4).unwrap();
        let mut out = [0.0];
        let mut t_out: f64 = 0.0;
        while s.t() < 10.0 {
            s.step(&Forced, 10.0).unwrap();
            while t_out <= s.t() {
                s.interpolate(t_out, &mut out);
                assert!((out[0] - forced_exact(t_out)).abs() < 1e-7, "t = {t_out}");
                t_out += 0.1;
            }
        }
        assert_eq!(s.t(), 10.0);
        assert!((s.y()[0] - forced_exact(10.0)).abs() < 1e-9);
    }

    #[test]
    fn a_copy_replays_bit_for_bit() {
        let tol = Tolerances {
            rtol: 1e-6,
            atol: vec![1e-10, 1e-14, 1e-10],
        };
        let mut s = Radau5::new(3, tol);
        s.init(&Robertson, 0.0, &[1.0, 0.0, 0.0], 1e-8).unwrap();
        s.advance(&Robertson, 0.3).unwrap();
        let saved = s.clone();
        s.advance(&Robertson, 5.0).unwrap();
        let mut replay = saved;
        replay.advance(&Robertson, 5.0).unwrap();
        assert_eq!(
            s.y().iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            replay.y().iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        );
        assert_eq!(s.stats(), replay.stats());
    }

    struct Undefined;
    impl OdeSystem for Undefined {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), RhsError> {
            if y[0] > 2.0 {
                return Err(RhsError("y above 2".into()));
            }
            dy[0] = 1.0;
            Ok(())
        }
        fn jacobian(&self, _t: f64, _y: &[f64], j: &mut [f64]) -> Result<(), RhsError> {
            j[0] = 0.0;
            Ok(())
        }
    }

    #[test]
    fn leaving_the_domain_is_reported_not_a_nan() {
        let mut s = Radau5::new(
            1,
            Tolerances {
                rtol: 1e-6,
                atol: vec![1e-9],
            },
        );
        s.init(&Undefined, 0.0, &[0.0], 1e-3).unwrap();
        let e = s.advance(&Undefined, 5.0).unwrap_err();
        assert!(matches!(e, SolverError::StepTooSmall { .. }), "{e}");
        assert!(e.to_string().contains("y above 2"), "{e}");
        assert!(s.t() <= 2.0 && s.y()[0] <= 2.0);
    }
}
