//! The explicit Runge–Kutta pair of Bogacki & Shampine (1989), "A 3(2) pair of Runge–Kutta
//! formulas", Appl. Math. Lett. 2(4), 321–325 (MATLAB's ode23), for a system that is not stiff
//! at the step: order 3 advanced, the embedded order-2 solution for the error estimate, its
//! last stage f at the new point (first same as last); step-size control of Hairer, Nørsett &
//! Wanner I, II.4 (4.11)–(4.13); the cubic Hermite interpolant of the step's end points and
//! slopes for dense output (order 3, Shampine & Reichelt 1997); and the estimate h ρ of the
//! stiffness the step met, from its last two stages (Hairer & Wanner II, IV.2, "Automatic
//! stiffness detection"), which says when the pair is the wrong method.
//!
//! Butcher tableau (c | A, then b of order 3 and b̂ of order 2):
//!
//! ```text
//!  0  |
//! 1/2 | 1/2
//! 3/4 | 0    3/4
//!  1  | 2/9  1/3  4/9
//! ----+--------------------
//!  b  | 2/9  1/3  4/9  0
//!  b̂  | 7/24 1/4  1/3  1/8
//! ```
//!
//! All work arrays are allocated in [`Bs23::new`]; stepping allocates nothing. The whole state
//! is `Clone` and serde-serialisable, so a restored copy replays bit for bit.

use serde::{Deserialize, Serialize};

use super::{OdeSystem, RhsError, SolverError, Stats, Tolerances};

/// The error weights b − b̂ of the four stages.
const E: [f64; 4] = [-5.0 / 72.0, 1.0 / 12.0, 1.0 / 9.0, -1.0 / 8.0];
const SAFE: f64 = 0.9;
/// Step-size ratio limits: h_new/h in [1/5, 5].
const FAC_MIN: f64 = 0.2;
const FAC_MAX: f64 = 5.0;
const UROUND: f64 = 1e-16;

/// x^(−1/6) for x ≥ 1e-30 to about 5e-5 relative, without a division: a sixth of the bits
/// (of the exponent, mostly) subtracted from a constant as the first guess (within 3.2 %), then
/// two Newton steps y ← y (7 − x y⁶)/6 on y⁻⁶ = x. For the step-size factor from the mean square
/// of the scaled error, err^(−1/3) = (err²)^(−1/6), which needs no more; `cbrt` is a software
/// call here that took a tenth of a held step.
fn inverse_sixth_root(x: f64) -> f64 {
    const GUESS: u64 = 0x4A97_2000_0000_0000;
    let mut y = f64::from_bits(GUESS - x.to_bits() / 6);
    for _ in 0..2 {
        let y3 = y * y * y;
        y *= (7.0 - x * y3 * y3) / 6.0;
    }
    y
}

/// The system's failure to evaluate at time `t`, as the solver reports it.
fn at(t: f64) -> impl FnOnce(RhsError) -> SolverError {
    move |e| SolverError::Rhs { t, message: e.0 }
}

/// The Bogacki–Shampine 3(2) integrator and its whole state.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Bs23 {
    n: usize,
    tol: Tolerances,
    t: f64,
    y: Vec<f64>,
    /// f(t, y) at the current point (stage 1 of the next step).
    f0: Vec<f64>,
    /// The step size the next step will try.
    h: f64,
    /// The last accepted step [t_old, t_old + h_old]: its start and the slopes at its ends,
    /// for dense output (f at its end is the system's before any restart).
    t_old: f64,
    h_old: f64,
    y_old: Vec<f64>,
    f_old: Vec<f64>,
    f_end: Vec<f64>,
    /// Stages 2 and 3, the stage point and the new state of the step being tried.
    k2: Vec<f64>,
    k3: Vec<f64>,
    stage: Vec<f64>,
    y_new: Vec<f64>,
    /// h ρ of the last accepted step: h ‖f(y_new) − f(Y3)‖ / ‖y_new − Y3‖.
    h_rho: f64,
    first: bool,
    stats: Stats,
}

impl Bs23 {
    /// An integrator for `n` states; call [`Bs23::init`] before stepping.
    pub fn new(n: usize, tol: Tolerances) -> Bs23 {
        assert_eq!(tol.atol.len(), n, "one absolute tolerance per state");
        Bs23 {
            n,
            tol,
            t: 0.0,
            y: vec![0.0; n],
            f0: vec![0.0; n],
            h: 1e-6,
            t_old: 0.0,
            h_old: 0.0,
            y_old: vec![0.0; n],
            f_old: vec![0.0; n],
            f_end: vec![0.0; n],
            k2: vec![0.0; n],
            k3: vec![0.0; n],
            stage: vec![0.0; n],
            y_new: vec![0.0; n],
            h_rho: 0.0,
            first: true,
            stats: Stats::default(),
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
        self.h_old = 0.0;
        self.h_rho = 0.0;
        self.first = true;
        self.restart(sys)
    }

    /// Continues after a discontinuity of the system at the current point (an input jump):
    /// f is evaluated anew; the step size carries over (the error control shrinks it if the
    /// jump needs it).
    pub fn restart<S: OdeSystem>(&mut self, sys: &S) -> Result<(), SolverError> {
        sys.rhs(self.t, &self.y, &mut self.f0).map_err(at(self.t))?;
        self.stats.rhs_evals += 1;
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

    /// The stiffness the last accepted step met, h ρ with ρ the estimate of the spectral
    /// radius of ∂f/∂y along it: the pair is stable for h ρ within about 2.5 on the negative
    /// real axis (the stability polynomial 1 + z + z²/2 + z³/6 of any three-stage method of
    /// order 3, Hairer & Wanner II, IV.2), and where error control needs no smaller step than
    /// that the problem is stiff at the step.
    pub fn stiffness(&self) -> f64 {
        self.h_rho
    }

    /// The tolerances the steps are controlled to.
    pub fn tolerances(&self) -> &Tolerances {
        &self.tol
    }

    /// The last step's cubic Hermite interpolant at `t` in [t_old, t] (dense output).
    pub fn interpolate(&self, t: f64, out: &mut [f64]) {
        if self.h_old == 0.0 {
            out.copy_from_slice(&self.y);
            return;
        }
        let h = self.h_old;
        let s = (t - self.t_old) / h;
        let (s2, s3) = (s * s, s * s * s);
        let (h00, h10, h01, h11) = (
            2.0 * s3 - 3.0 * s2 + 1.0,
            s3 - 2.0 * s2 + s,
            -2.0 * s3 + 3.0 * s2,
            s3 - s2,
        );
        for (i, o) in out.iter_mut().enumerate().take(self.n) {
            *o = h00 * self.y_old[i]
                + h * (h10 * self.f_old[i] + h11 * self.f_end[i])
                + h01 * self.y[i];
        }
    }

    /// y + h Σ a_k k_k into `stage`.
    fn stage_point(&mut self, h: f64, a: [f64; 3]) {
        for i in 0..self.n {
            self.stage[i] =
                self.y[i] + h * (a[0] * self.f0[i] + a[1] * self.k2[i] + a[2] * self.k3[i]);
        }
    }

    /// The stages of a step of size h, up to the new state (stage 4 is f there, into
    /// `f_end`), and the square of its error norm (Hairer, Nørsett & Wanner I, II.4 (4.11)).
    fn attempt<S: OdeSystem>(&mut self, sys: &S, h: f64, t_new: f64) -> Result<f64, RhsError> {
        let n = self.n;
        self.stage_point(h, [0.5, 0.0, 0.0]);
        sys.rhs(self.t + 0.5 * h, &self.stage, &mut self.k2)?;
        self.stage_point(h, [0.0, 0.75, 0.0]);
        sys.rhs(self.t + 0.75 * h, &self.stage, &mut self.k3)?;
        for i in 0..n {
            self.y_new[i] = self.y[i]
                + h * (2.0 / 9.0 * self.f0[i] + 1.0 / 3.0 * self.k2[i] + 4.0 / 9.0 * self.k3[i]);
        }
        sys.rhs(t_new, &self.y_new, &mut self.f_end)?;
        let mut sum = 0.0;
        for i in 0..n {
            let e = h
                * (E[0] * self.f0[i]
                    + E[1] * self.k2[i]
                    + E[2] * self.k3[i]
                    + E[3] * self.f_end[i]);
            let scale = self.tol.atol[i] + self.tol.rtol * self.y[i].abs().max(self.y_new[i].abs());
            sum += (e / scale) * (e / scale);
        }
        Ok(sum / n as f64)
    }

    /// Takes one accepted step, never past `t_end`.
    pub fn step<S: OdeSystem>(&mut self, sys: &S, t_end: f64) -> Result<(), SolverError> {
        let mut h = self.h;
        let mut last = false;
        if self.t + 1.05 * h >= t_end {
            h = t_end - self.t;
            last = true;
        }
        let mut rejected = false;
        loop {
            if 0.1 * h.abs() <= self.t.abs() * UROUND || h <= 0.0 {
                return Err(SolverError::StepTooSmall {
                    t: self.t,
                    h,
                    reason: "repeated step rejections".into(),
                });
            }
            let t_new = if last { t_end } else { self.t + h };
            let tried = self.attempt(sys, h, t_new);
            self.stats.rhs_evals += 3;
            let err2 = match tried {
                Ok(err2) if err2.is_finite() => err2,
                // a stage outside the system's domain: a smaller step may stay inside
                _ => {
                    h *= 0.5;
                    last = false;
                    rejected = true;
                    continue;
                }
            };
            // q = min(p, p̂) = 2: h_new = h · (1/err)^(1/3), bounded (HNW I, II.4 (4.13));
            // err = 0 takes the largest factor
            let fac = (SAFE * inverse_sixth_root(err2.max(1e-30))).clamp(FAC_MIN, FAC_MAX);
            if err2 <= 1.0 {
                self.accept(h, t_new);
                self.stats.accepted += 1;
                let h_new = if rejected { h * fac.min(1.0) } else { h * fac };
                // a step cut to land on t_end says little: resume with the size before the cut
                self.h = if last { self.h.max(h_new) } else { h_new };
                self.first = false;
                return Ok(());
            }
            if !self.first {
                self.stats.rejected += 1;
            }
            h *= fac.min(1.0);
            last = false;
            rejected = true;
        }
    }

    /// Commits the tried step [t, t + h] that ends at `t_new`.
    fn accept(&mut self, h: f64, t_new: f64) {
        // h ρ from the last two stages: Y3 is still in `stage`, f(Y3) in k3
        let (mut num, mut den) = (0.0, 0.0);
        for i in 0..self.n {
            num += (self.f_end[i] - self.k3[i]) * (self.f_end[i] - self.k3[i]);
            den += (self.y_new[i] - self.stage[i]) * (self.y_new[i] - self.stage[i]);
        }
        self.h_rho = if den > 0.0 {
            h * (num / den).sqrt()
        } else {
            0.0
        };
        std::mem::swap(&mut self.y_old, &mut self.y);
        std::mem::swap(&mut self.y, &mut self.y_new);
        std::mem::swap(&mut self.f_old, &mut self.f0);
        self.f0.copy_from_slice(&self.f_end);
        self.t_old = self.t;
        self.h_old = t_new - self.t;
        self.t = t_new;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// y' = λ (y − cos t) − sin t: the solution y = cos t + e^{λt}(y0 − 1).
    struct Relaxing(f64);
    impl OdeSystem for Relaxing {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), RhsError> {
            dy[0] = self.0 * (y[0] - t.cos()) - t.sin();
            Ok(())
        }
        fn jacobian(&self, _: f64, _: &[f64], jac: &mut [f64]) -> Result<(), RhsError> {
            jac[0] = self.0;
            Ok(())
        }
    }

    fn exact(lambda: f64, t: f64) -> f64 {
        t.cos() + (lambda * t).exp()
    }

    fn solver(rtol: f64) -> Bs23 {
        Bs23::new(1, Tolerances::scaled(rtol, &[1.0]))
    }

    fn advance(s: &mut Bs23, sys: &Relaxing, t_end: f64) {
        while s.t() < t_end {
            s.step(sys, t_end).unwrap();
        }
    }

    /// Error control: the global error follows the tolerance (the local error is controlled, and
    /// the global error gathers it: 1.1, 4.6 and 10.2 times rtol measured), and a tighter
    /// tolerance takes more steps; the requested end is hit exactly.
    #[test]
    fn the_error_follows_the_tolerance() {
        let lambda = -20.0;
        let sys = Relaxing(lambda);
        let mut steps = 0;
        for rtol in [1e-4, 1e-6, 1e-8] {
            let mut s = solver(rtol);
            s.init(&sys, 0.0, &[2.0], 1e-6).unwrap();
            advance(&mut s, &sys, 2.0);
            assert_eq!(s.t(), 2.0);
            let err = (s.y()[0] - exact(lambda, 2.0)).abs();
            assert!(err <= 20.0 * rtol, "rtol {rtol:e}: error {err:e}");
            assert!(s.stats().accepted > steps, "rtol {rtol:e}");
            steps = s.stats().accepted;
        }
    }

    /// The dense output between the steps is as accurate as the steps (2.35e-6 between them,
    /// 2.34e-6 at them, measured).
    #[test]
    fn dense_output_is_of_the_steps_accuracy() {
        let lambda = -5.0;
        let sys = Relaxing(lambda);
        let mut s = solver(1e-7);
        s.init(&sys, 0.0, &[2.0], 1e-6).unwrap();
        let mut out = [0.0];
        let (mut worst, mut at_steps): (f64, f64) = (0.0, 0.0);
        while s.t() < 3.0 {
            s.step(&sys, 3.0).unwrap();
            at_steps = at_steps.max((s.y()[0] - exact(lambda, s.t())).abs());
            for k in 1..4 {
                let t = s.t_old + s.h_old * k as f64 / 4.0;
                s.interpolate(t, &mut out);
                worst = worst.max((out[0] - exact(lambda, t)).abs());
            }
        }
        assert!(
            worst <= 1.1 * at_steps,
            "{worst:e} between, {at_steps:e} at the steps"
        );
    }

    #[test]
    fn the_inverse_sixth_root_is_one() {
        for k in 0..=4000 {
            let x = 10f64.powf(-30.0 + 40.0 * k as f64 / 4000.0);
            let (y, want) = (inverse_sixth_root(x), x.powf(-1.0 / 6.0));
            assert!((y - want).abs() <= 5e-5 * want, "{x:e}: {y:e}");
        }
    }

    /// h ρ estimates h |λ| of a linear system, and grows with λ at the same step.
    #[test]
    fn the_stiffness_estimate_is_h_times_the_eigenvalue() {
        for lambda in [-10.0, -1000.0] {
            let sys = Relaxing(lambda);
            let mut s = solver(1e-6);
            s.init(&sys, 0.0, &[1.5], 1e-4).unwrap();
            s.step(&sys, 1.0).unwrap();
            // (the forcing moves f between the last two stages' times: 2 % at λ = −10)
            let want = s.h_old * lambda.abs();
            assert!(
                (s.stiffness() - want).abs() <= 0.05 * want,
                "λ {lambda}: {} against {want}",
                s.stiffness()
            );
        }
    }

    /// A copy replays bit for bit, also through serialisation.
    #[test]
    fn a_restored_copy_replays_bit_for_bit() {
        let sys = Relaxing(-30.0);
        let mut s = solver(1e-6);
        s.init(&sys, 0.0, &[2.0], 1e-6).unwrap();
        advance(&mut s, &sys, 0.1);
        let bytes = postcard::to_stdvec(&s).unwrap();
        let mut copy: Bs23 = postcard::from_bytes(&bytes).unwrap();
        advance(&mut s, &sys, 0.5);
        advance(&mut copy, &sys, 0.5);
        assert_eq!(s.y()[0].to_bits(), copy.y()[0].to_bits());
        assert_eq!(s.stats(), copy.stats());
    }
}
