//! Reduced models of the platform by singular perturbation (Tikhonov), from the same parameters
//! and effects as the full one.
//!
//! The full model (book/src/model.md, "Dynamics") has three time scales: the charges relax with
//! the circuit's RC constants (3–23 ns), the momentum with I/b (4–57 µs), the motion one sees
//! takes 0.03–0.4 s. With ε the ratio of a fast to the slow time scale, Tikhonov's theorem
//! replaces the fast states by their quasi-steady values, the root of their rows of ẋ = f(x)
//! with the slow states frozen, at an error O(ε) after the fast transient:
//!
//! ```text
//! x = lift(z, U):  z the slow states;  f_F(lift(z, U), U) = 0 for the fast states F
//! ż = f_z(lift(z, U), U)
//! ```
//!
//! - **quasi-static** (`z` = θ, l_p, p and the effects' states; F = Q1, Q2): the circuit's rows
//!   (G0+G1) V1 + G0 V2 = G0 ga U, G0 V1 + (G0+G2) V2 = G0 ga U give the DC circuit of
//!   model.md, "Statics": V1 = R1 i, V2 = R2 i, i = ga(θ) U / (R0 + R1 + R2)
//!   (`Actuator::dc_state`); the mechanics feel the electrostatic force of that V2.
//! - **slow** (`z` = θ and the effects' states; F = p, Q1, Q2; l_p on the invariant curve):
//!   ṗ = 0 is the force balance ∂H/∂θ + d ∂H/∂l_p + b ω = 0 (model.md, "Dynamics"), so
//!   θ̇ = ω = −(∂H/∂θ + d ∂H/∂l_p) / b: the energy's gradient along the curve over the damping.
//!   l̇_p = d θ̇ keeps (θ, l_p) on the curve through (0, Lp) (`Actuator::l_p_on_curve`,
//!   model.md, "Initial state"), so l_p = L(θ) is no state.
//!   Without effects the lift's charges give V2 = R2 i, so θ̇ = a(θ) + b(θ) U² comes from the
//!   geometry along the curve alone (`Actuator::slow_rate`), tabulated with the curve: one
//!   interpolation per actuator, not the lift's three geometries.
//!
//! With effects the drift stage and the clipping change the circuit's rows and the effects'
//! torques the force balance; the fast states are then the root of the same rows of the full
//! f by Newton (`Platform::settle`), from the DC circuit's values. The effects' states relax
//! on the slow time scale or slower and stay states.
//!
//! **Jacobian.** With T = dx/dz (the identity on z, dL/dθ = d(θ, L) for l_p on the curve, and
//! T_F = −f_{F,F}⁻¹ f_{F,x} T on the fast states by the implicit function theorem):
//! ∂ż/∂z = f_{z,x} T, and likewise ∂ż/∂U = f_{z,U} + f_{z,F} ∂x_F/∂U with
//! ∂x_F/∂U = −f_{F,F}⁻¹ f_{F,U}.
//!
//! **Port-Hamiltonian form.** The reduced storage is the full H without the energy of the fast
//! states, each quadratic in its own state (model.md, "Energy"): E_F = ½ Σ_F x_k ∂H/∂x_k
//! (Q1²/(2 C1) + Q2²/(2 C2), and for the slow model p²/(2 I)), so H_r = H − E_F does not depend
//! on x_F. Along the reduced flow ẋ_z = f_z, ẋ_l = f_l on the curve and f_F = 0, so with the
//! full balance ∇H · f = P_supplied − P_dissipated (model.md, "Energy balance"):
//!
//! ```text
//! dH_r/dt = ∇H · f − ∇E_F · f = P_supplied − P_dissipated + P_e,
//! P_e = −(∂E_F/∂θ θ̇ + ∂E_F/∂l_p l̇_p) = −½ Q2 (∂V2/∂θ θ̇ + ∂V2/∂l_p l̇_p) = ½ V2² dC2/dt
//! ```
//!
//! P_e is the electromechanical power the electrode's field does on the films: in the full
//! model the current that charges C2 as it zips carries it through the port; the reduced
//! circuit neglects that current (order ε) and books P_e as supplied beside the DC loop's
//! power (which its resistors dissipate). So the reduced model's supplied power is
//! P_supplied + P_e, its dissipated power the full model's at the lifted state (the damping b ω²
//! and the DC loop's resistors, the effects' terms included), and the balance
//! dH_r/dt = supplied − dissipated holds exactly along its trajectories.

use nalgebra::DMatrix;

use super::actuator::{L_P, N, P, Q2, THETA};
use super::platform::{ModelError, Platform, Wrt};
use super::reduction::Reduction;
use super::shell::{DomainError, Shell};

impl Platform {
    /// Index in the full state of this model's state `k`.
    fn full_index(&self, k: usize) -> usize {
        let (rb, kept) = (self.rb(), self.reduction.kept());
        let (i, j) = (k / rb, k % rb);
        self.nb * i + if j < kept { j } else { N + j - kept }
    }

    /// Whether the full state `k` is one of the fast states the reduction solves for.
    fn is_fast(&self, k: usize) -> bool {
        let j = k % self.nb;
        j >= self.reduction.kept().max(P) && j < N
    }

    /// l_p on actuator `i`'s invariant curve at θ.
    fn l_p_on_curve(&self, i: usize, theta: f64) -> Result<f64, DomainError> {
        let a = &self.actuators[i];
        match self.curves.get(i) {
            Some(curve) => curve.l_p(a, theta),
            None => a.l_p_on_curve(theta),
        }
    }

    /// Whether the full state `k` is an l_p the reduction keeps on its curve.
    fn on_curve(&self, k: usize) -> bool {
        k % self.nb == L_P && self.reduction.kept() <= L_P
    }

    /// This model's states of the full state `x`.
    pub(super) fn project(&self, x: &[f64]) -> Vec<f64> {
        (0..self.n_states())
            .map(|k| x[self.full_index(k)])
            .collect()
    }

    /// The full state on the slow manifold at this model's state `z` and command `u`: l_p on
    /// its curve where the model drops it, the charges of the DC circuit and, in the slow model,
    /// the momentum of the force balance. Without effects that is the root of the fast rows of
    /// f (the circuit's rows are linear in the charges, ṗ affine in p with slope −b/I); with
    /// them, Newton goes on from there to the root.
    fn lift(&self, z: &[f64], u: [f64; 3]) -> Result<Vec<f64>, ModelError> {
        let mut x = vec![0.0; 3 * self.nb];
        for (k, &v) in z.iter().enumerate() {
            x[self.full_index(k)] = v;
        }
        let keeps_l_p = self.reduction.kept() > L_P;
        let guess = self.each(|i, a| {
            let xi = &x[self.nb * i..self.nb * (i + 1)];
            let theta = xi[THETA];
            let l_p = if keeps_l_p {
                xi[L_P]
            } else {
                self.l_p_on_curve(i, theta)?
            };
            let i_dc = a.dc_current(theta, self.port_voltage(xi, u[i]));
            a.dc_state(theta, l_p, i_dc)
        })?;
        for (i, dc) in guess.iter().enumerate() {
            let o = self.nb * i;
            let fast = P.max(self.reduction.kept());
            x[o + L_P] = dc[L_P];
            x[o + fast..o + N].copy_from_slice(&dc[fast..]);
        }
        if self.reduction.kept() <= P {
            self.balance_momentum(&mut x, u)?;
        }
        if !self.terms.neutral {
            self.settle(&mut x, u, |k| self.is_fast(k))?;
        }
        Ok(x)
    }

    /// Sets each actuator's momentum where ṗ = 0 from the p in `x`, along ṗ's slope in p
    /// without effects, ∂ṗ/∂p = −b/I (src/model/actuator.rs, module doc).
    fn balance_momentum(&self, x: &mut [f64], u: [f64; 3]) -> Result<(), ModelError> {
        let mut f = vec![0.0; x.len()];
        self.full_rhs(x, u, &mut f)?;
        for (i, a) in self.actuators.iter().enumerate() {
            let k = self.nb * i + P;
            x[k] += f[k] * a.inertia / a.par.b;
        }
        Ok(())
    }

    pub(super) fn reduced_rhs(
        &self,
        z: &[f64],
        u: [f64; 3],
        dz: &mut [f64],
    ) -> Result<(), ModelError> {
        if self.reduction == Reduction::Slow && self.terms.neutral {
            // θ alone per actuator: its rate from the curve's table, without the lift
            let rates = self.each(|i, a| self.curves[i].slow_rate(a, z[i], u[i]))?;
            dz.copy_from_slice(&rates);
            return Ok(());
        }
        let x = self.lift(z, u)?;
        let mut f = vec![0.0; x.len()];
        self.full_rhs(&x, u, &mut f)?;
        for (k, d) in dz.iter_mut().enumerate() {
            *d = f[self.full_index(k)];
        }
        Ok(())
    }

    /// The lifted state of `z` at `u` and the full model's ∂f/∂x there, dense.
    fn lifted_with_jacobian(
        &self,
        z: &[f64],
        u: [f64; 3],
    ) -> Result<(Vec<f64>, DMatrix<f64>), ModelError> {
        let x = self.lift(z, u)?;
        let n = x.len();
        let mut j = DMatrix::zeros(n, n);
        self.full_jacobian_entries(&x, u, |r, c, v| j[(r, c)] += v)?;
        Ok((x, j))
    }

    /// Completes the derivative `t` of the lifted state (columns: the directions) on the
    /// fast states, which follow the others along f_F = 0: t_F = −f_{F,F}⁻¹ (f_{F,x} t + b_F),
    /// with `b` the direct derivative of f along each direction (the input map for ∂/∂U, 0
    /// for ∂/∂z). A singular f_{F,F} (no isolated root) gives NaN, which the solver rejects.
    fn through_fast_states(&self, jac: &DMatrix<f64>, t: &mut DMatrix<f64>, b: &DMatrix<f64>) {
        let fast: Vec<usize> = (0..jac.nrows()).filter(|&k| self.is_fast(k)).collect();
        let m = fast.len();
        let jff = DMatrix::from_fn(m, m, |r, c| jac[(fast[r], fast[c])]);
        let rhs = jac * &*t + b;
        let rhs_f = DMatrix::from_fn(m, t.ncols(), |r, c| -rhs[(fast[r], c)]);
        let solved = jff
            .lu()
            .solve(&rhs_f)
            .unwrap_or_else(|| DMatrix::from_element(m, t.ncols(), f64::NAN));
        for (r, &k) in fast.iter().enumerate() {
            t.row_mut(k).copy_from(&solved.row(r));
        }
    }

    /// Whether ∂ż_r/∂z_c can be nonzero: within an actuator's block, or across through the
    /// angle θ_c when the effects link the actuators (the coupling's energy depends on the
    /// heights alone; book/src/effects.md, "Jacobian").
    fn linked(&self, r: usize, c: usize) -> bool {
        let rb = self.rb();
        r / rb == c / rb || (self.terms.links_actuators() && c % rb == THETA)
    }

    /// The entries of ∂ż/∂z (`wrt` [`Wrt::States`]) or ∂ż/∂U ([`Wrt::Inputs`]) through
    /// `add(row, col, value)`, as the full model's: the derivative of the lifted state along
    /// each direction (module doc, "Jacobian"), then the full model's f along it.
    pub(super) fn reduced_entries(
        &self,
        z: &[f64],
        u: [f64; 3],
        wrt: Wrt,
        mut add: impl FnMut(usize, usize, f64),
    ) -> Result<(), ModelError> {
        let (x, jac) = self.lifted_with_jacobian(z, u)?;
        let (n, m) = (x.len(), z.len());
        let (mut t, direct) = match wrt {
            Wrt::States => (self.slow_tangent(&x, m)?, DMatrix::zeros(n, m)),
            Wrt::Inputs => {
                let mut b = DMatrix::zeros(n, 3);
                self.full_input_jacobian_entries(&x, u, |r, j, v| b[(r, j)] += v)?;
                (DMatrix::zeros(n, 3), b)
            }
        };
        self.through_fast_states(&jac, &mut t, &direct);
        let d = &jac * &t + &direct;
        // a command reaches the rows of its actuator's block only: the coupling takes angles
        let linked = |r: usize, c: usize| match wrt {
            Wrt::States => self.linked(r, c),
            Wrt::Inputs => r / self.rb() == c,
        };
        for r in 0..m {
            for c in (0..d.ncols()).filter(|&c| linked(r, c)) {
                add(r, c, d[(self.full_index(r), c)]);
            }
        }
        Ok(())
    }

    /// dx/dz off the fast states: the identity on z, dL/dθ = d(θ, L) for l_p on its curve.
    fn slow_tangent(&self, x: &[f64], m: usize) -> Result<DMatrix<f64>, ModelError> {
        let mut t = DMatrix::zeros(x.len(), m);
        for c in 0..m {
            t[(self.full_index(c), c)] = 1.0;
        }
        for k in (0..x.len()).filter(|&k| self.on_curve(k)) {
            let i = k / self.nb;
            let shell =
                Shell::new(x[k - L_P + THETA], x[k], self.params().lv).map_err(|cause| {
                    ModelError {
                        actuator: i + 1,
                        cause,
                    }
                })?;
            t[(k, i * self.rb() + THETA)] = shell.d;
        }
        Ok(t)
    }

    /// P_e = −(∂E_F/∂θ θ̇ + ∂E_F/∂l_p l̇_p) at the full state `x` along ẋ = f (module doc):
    /// ∂E_F/∂θ = ½ Q2 ∂V2/∂θ at fixed charge, likewise for l_p; p²/(2 I) does not move with them.
    fn electromechanical_power(&self, x: &[f64], u: [f64; 3]) -> Result<f64, ModelError> {
        let mut f = vec![0.0; x.len()];
        self.full_rhs(x, u, &mut f)?;
        let per_actuator = self.each(|i, a| {
            let o = self.nb * i;
            let v = a.voltages(&x[o..o + N])?;
            Ok(-0.5 * x[o + Q2] * (v.v2_t * f[o + THETA] + v.v2_l * f[o + L_P]))
        })?;
        Ok(per_actuator.iter().sum())
    }

    /// H_r = H − E_F (module doc): since each fast state's energy is quadratic in it and no
    /// other term holds it, H at the state with the fast states at 0 and l_p on its curve.
    pub(super) fn reduced_energy(&self, z: &[f64]) -> Result<f64, ModelError> {
        let mut x = vec![0.0; 3 * self.nb];
        for (k, &v) in z.iter().enumerate() {
            x[self.full_index(k)] = v;
        }
        for k in (0..x.len()).filter(|&k| self.on_curve(k)) {
            let i = k / self.nb;
            x[k] = self
                .l_p_on_curve(i, x[k - L_P + THETA])
                .map_err(|cause| ModelError {
                    actuator: i + 1,
                    cause,
                })?;
        }
        self.full_energy(&x)
    }

    /// P_supplied + P_e at the lifted state (module doc).
    pub(super) fn reduced_supplied_power(&self, z: &[f64], u: [f64; 3]) -> Result<f64, ModelError> {
        let x = self.lift(z, u)?;
        Ok(self.full_supplied_power(&x, u)? + self.electromechanical_power(&x, u)?)
    }

    /// The full model's dissipated power at the lifted state: the lifted charges (and momentum)
    /// follow the command.
    pub(super) fn reduced_dissipated_power(
        &self,
        z: &[f64],
        u: [f64; 3],
    ) -> Result<f64, ModelError> {
        self.full_dissipated_power(&self.lift(z, u)?)
    }

    /// dH_r/dt: the full model's stored power at the lifted state (its electrical part is 0
    /// there, f_F = 0) + P_e.
    pub(super) fn reduced_stored_power(&self, z: &[f64], u: [f64; 3]) -> Result<f64, ModelError> {
        let x = self.lift(z, u)?;
        Ok(self.full_stored_power(&x, u)? + self.electromechanical_power(&x, u)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Params;
    use crate::model::Reduction;
    use crate::model::platform::tests::assert_jacobian_matches;

    fn reduced(r: Reduction) -> Platform {
        Platform::reduced(Params::default(), r).unwrap()
    }

    /// Mid-stroke, moving: the full model's busy state in this model's coordinates.
    fn moving_state(m: &Platform) -> Vec<f64> {
        let full = Platform::new(Params::default()).unwrap();
        let mut x = full
            .settled_state([0.004, 0.008, 0.002], &[], [40.0, 55.0, 20.0])
            .unwrap();
        for i in 0..3 {
            x[N * i + P] = 3e-8 * (i as f64 - 1.0);
        }
        m.project(&x)
    }

    /// Effects that change the fast rows: the coupling that links the actuators, the clipping
    /// and the drift stage in the circuit, hysteresis's torque through the velocity in the force
    /// balance, the amplifier's lag before the port.
    fn with_effects(r: Reduction) -> Platform {
        let mut p = Params::default();
        for (name, value) in [
            ("k_c", 40.0),
            ("U_max", 50.0),
            ("k_h", 0.04),
            ("theta_h", 2e-3),
            ("R3", 2e4),
            ("tau3", 0.5),
            ("tau_a", 0.02),
        ] {
            p.set(name, value).unwrap();
        }
        Platform::reduced(p, r).unwrap()
    }

    /// Mid-stroke with every effect's state off rest, in this model's coordinates.
    fn moving_state_with_effects(m: &Platform) -> Vec<f64> {
        let full = with_effects(Reduction::Full);
        let mut x = full
            .settled_state([0.004, 0.008, 0.002], &[], [40.0, 25.0, -30.0])
            .unwrap();
        let (nb, scales) = (full.n_states() / 3, full.state_scales());
        for i in 0..3 {
            // moving (|ω| has a kink at 0)
            x[nb * i + P] = 3e-8 * (i as f64 - 1.0) + 1e-9;
            // off rest and off the kinks of the hysteresis law at z_h = 0
            for k in nb * i + N..nb * (i + 1) {
                x[k] = 0.8 * x[k] + 0.1 * scales[k];
            }
        }
        m.project(&x)
    }

    const U_EFFECTS: [f64; 3] = [40.0, 25.0, -30.0];

    #[test]
    fn with_effects_the_lift_roots_the_fast_rows_and_the_jacobian_holds() {
        for r in [Reduction::QuasiStatic, Reduction::Slow] {
            let m = with_effects(r);
            let z = moving_state_with_effects(&m);
            assert_fast_rows_rooted(&m, &z, U_EFFECTS);
            assert_jacobian_matches(&m, &z, U_EFFECTS);
        }
    }

    /// The tabulated curve against the curve integrated from 0 in 4096 RK4 steps, between its
    /// nodes (beyond them it is the full model's integration itself).
    #[test]
    fn the_tabulated_curve_is_the_integrated_one() {
        let m = reduced(Reduction::Slow);
        let (mut worst, mut worst_16): (f64, f64) = (0.0, 0.0);
        for (i, a) in m.actuators.iter().enumerate() {
            let theta_star = std::f64::consts::FRAC_PI_2 / a.par.gamma2;
            // within the table's reach of 2 θ*
            for k in -274..=274 {
                let theta = theta_star * k as f64 / 137.0;
                let fine = (0..4096).try_fold(m.params().lp, |l, j| {
                    a.curve_step(theta * j as f64 / 4096.0, l, theta / 4096.0)
                });
                match (m.l_p_on_curve(i, theta), fine) {
                    (Ok(t), Ok(l)) => {
                        worst = worst.max((t - l).abs());
                        worst_16 = worst_16.max((a.l_p_on_curve(theta).unwrap() - l).abs());
                    }
                    (t, l) => assert_eq!(t.is_ok(), l.is_ok(), "{i} at {theta}"),
                }
            }
        }
        println!("largest difference {worst:e} m (integrated in 16 steps: {worst_16:e} m)");
        // no farther than the full model's own 16 steps from 0 (2e-14 m of l_p ≈ 14 mm)
        assert!(worst <= worst_16, "{worst:e} m against {worst_16:e} m");
    }

    /// The slow model's tabulated θ̇ = a + b U² against θ̇ of the full model at the lifted
    /// state (the route the model takes with effects), between the table's nodes and beyond.
    #[test]
    fn the_tabulated_rate_is_the_lifted_one() {
        let m = reduced(Reduction::Slow);
        let (mut worst, mut scale): (f64, f64) = (0.0, 0.0);
        let theta_star = std::f64::consts::FRAC_PI_2 / m.actuators[0].par.gamma2;
        // within the table's reach of 2 θ* and past it
        for k in -300..=300 {
            let z = [0.0, 1.0, 2.0].map(|j| theta_star * (k as f64 + j / 3.0) / 137.0);
            for u in [[0.0, 0.0, 0.0], [30.0, -60.0, 45.0]] {
                let mut dz = [0.0; 3];
                let (tabulated, lifted) = (
                    m.rhs(&z, u, &mut dz).map(|_| dz),
                    m.lift(&z, u).and_then(|x| {
                        let mut f = vec![0.0; x.len()];
                        m.full_rhs(&x, u, &mut f)?;
                        Ok([0, 1, 2].map(|i| f[m.full_index(i)]))
                    }),
                );
                match (tabulated, lifted) {
                    (Ok(t), Ok(l)) => {
                        for i in 0..3 {
                            worst = worst.max((t[i] - l[i]).abs());
                            scale = scale.max(l[i].abs());
                        }
                    }
                    (t, l) => assert_eq!(t.is_ok(), l.is_ok(), "at {z:?}"),
                }
            }
        }
        println!("largest difference {worst:e} rad/s of rates up to {scale:e} rad/s");
        // measured 2.2e-11 rad/s of 1.8 rad/s, past the table at −2.2 θ* and 60 V, where a and
        // b U² nearly cancel
        assert!(worst <= 1e-10 * scale, "{worst:e} rad/s");
    }

    /// The rate parts' slopes along the curve against central differences of the parts.
    #[test]
    fn the_rate_parts_slopes_are_their_derivatives_along_the_curve() {
        let m = reduced(Reduction::Slow);
        let a = &m.actuators[1];
        let parts = |theta: f64| a.slow_rate(theta, a.l_p_on_curve(theta).unwrap()).unwrap();
        for theta in [-0.02, 0.0, 0.005, 0.03, 0.1] {
            let dt = 1e-6;
            let (lo, at, hi) = (parts(theta - dt), parts(theta), parts(theta + dt));
            let a_t = (hi.a - lo.a) / (2.0 * dt);
            let b_t = (hi.b - lo.b) / (2.0 * dt);
            assert!(
                (a_t - at.a_t).abs() <= 1e-6 * at.a_t.abs(),
                "a' {a_t:e} {:e} at {theta}",
                at.a_t
            );
            assert!(
                (b_t - at.b_t).abs() <= 1e-6 * at.b_t.abs(),
                "b' {b_t:e} {:e} at {theta}",
                at.b_t
            );
        }
    }

    #[test]
    fn names_parse_and_unknown_names_list_the_allowed_ones() {
        for r in Reduction::ALL {
            assert_eq!(r.name().parse::<Reduction>().unwrap(), r);
        }
        let e = "reduced".parse::<Reduction>().unwrap_err();
        assert_eq!(
            e.to_string(),
            "unknown model \"reduced\": one of full, quasi-static, slow"
        );
    }

    #[test]
    fn reduced_models_keep_their_states() {
        assert_eq!(reduced(Reduction::QuasiStatic).n_states(), 9);
        assert_eq!(reduced(Reduction::Slow).n_states(), 3);
        let names = reduced(Reduction::QuasiStatic).state_names();
        assert_eq!(&names[..4], ["theta_1", "l_p_1", "p_1", "theta_2"]);
    }

    /// The lifted state of `z` at `u` has its fast rows at 0.
    fn assert_fast_rows_rooted(m: &Platform, z: &[f64], u: [f64; 3]) {
        let x = m.lift(z, u).unwrap();
        let mut f = vec![0.0; x.len()];
        m.full_rhs(&x, u, &mut f).unwrap();
        let scales = m.full_state_scales();
        for k in (0..x.len()).filter(|&k| m.is_fast(k)) {
            // the fast rates relax in ns to µs: 1e-6 scale/s is 1e-12 of the scale away
            assert!(
                f[k].abs() < 1e-6 * scales[k],
                "{:?} state {k}: {:e}",
                m.reduction(),
                f[k]
            );
        }
    }

    #[test]
    fn the_lift_roots_the_fast_rows() {
        for r in [Reduction::QuasiStatic, Reduction::Slow] {
            let m = reduced(r);
            assert_fast_rows_rooted(&m, &moving_state(&m), [40.0, 55.0, 20.0]);
        }
    }

    #[test]
    fn jacobians_match_finite_differences() {
        for r in [Reduction::QuasiStatic, Reduction::Slow] {
            let m = reduced(r);
            assert_jacobian_matches(&m, &moving_state(&m), [40.0, 55.0, 20.0]);
        }
    }

    /// Each reduced model moving, without effects and with them: the model, its state, the
    /// commands and whether the effects are on.
    fn moving_cases() -> Vec<(Platform, Vec<f64>, [f64; 3], bool)> {
        let mut cases = Vec::new();
        for r in [Reduction::QuasiStatic, Reduction::Slow] {
            let m = reduced(r);
            cases.push((m.clone(), moving_state(&m), [40.0, 55.0, 20.0], false));
            let m = with_effects(r);
            cases.push((m.clone(), moving_state_with_effects(&m), U_EFFECTS, true));
        }
        cases
    }

    #[test]
    fn input_jacobians_match_finite_differences() {
        for (m, z, u, effects) in moving_cases() {
            let r = m.reduction();
            let n = m.n_states();
            let mut b = vec![0.0; n * 3];
            m.input_jacobian(&z, u, &mut b).unwrap();
            let (mut fp, mut fm) = (vec![0.0; n], vec![0.0; n]);
            for j in 0..3 {
                let (mut up, mut um) = (u, u);
                up[j] += 1e-3;
                um[j] -= 1e-3;
                m.rhs(&z, up, &mut fp).unwrap();
                m.rhs(&z, um, &mut fm).unwrap();
                for k in 0..n {
                    let fd = (fp[k] - fm[k]) / 2e-3;
                    let an = b[j * n + k];
                    assert!(
                        (an - fd).abs() <= 1e-6 * an.abs().max(fd.abs()) + 1e-300,
                        "{r:?}, effects {effects}: d{k}/dU{j}: analytic {an:e} vs fd {fd:e}"
                    );
                }
            }
        }
    }

    #[test]
    fn power_balance_holds_pointwise() {
        // dH_r/dt along ż (central difference in time) = supplied − dissipated
        for (m, z, u, effects) in moving_cases() {
            let r = m.reduction();
            let mut f = vec![0.0; z.len()];
            m.rhs(&z, u, &mut f).unwrap();
            let eps = 1e-7;
            let at = |s: f64| {
                let y: Vec<f64> = z.iter().zip(&f).map(|(a, b)| a + s * b).collect();
                m.energy(&y).unwrap()
            };
            let dh = (at(eps) - at(-eps)) / (2.0 * eps);
            let supplied = m.supplied_power(&z, u).unwrap();
            let dissipated = m.dissipated_power_at(&z, u).unwrap();
            let stored = m.stored_power(&z, u).unwrap();
            println!(
                "{r:?}, effects {effects}: dH/dt {dh:e}, supplied {supplied:e}, dissipated {dissipated:e}, stored {stored:e}"
            );
            assert!(
                (dh - stored).abs() < 1e-6 * stored.abs(),
                "{r:?}, effects {effects}: dH/dt {dh:e} vs stored {stored:e}"
            );
            assert!(
                (stored - (supplied - dissipated)).abs() < 1e-12 * (supplied.abs() + dissipated),
                "{r:?}: stored {stored:e} vs supplied − dissipated {:e}",
                supplied - dissipated
            );
        }
    }
}
