//! The energy balance dH/dt = y·U − dissipation along a trajectory (book/src/model.md, "Energy
//! balance"), the first check of any implementation. The stored power is integrated as an extra
//! state by the same solver; the balance is measured against the energy supplied through the
//! ports, since the circuit's port power (~1e5 W peak) dwarfs the mechanical power (mW). The
//! reduced models keep the balance of their own storage (src/model/reduced.rs,
//! "Port-Hamiltonian form").

use hasel_fmu::model::{Params, Platform, Reduction};
use hasel_fmu::simulation::Input;
use hasel_fmu::solver::{OdeSystem, Radau5, RhsError, Tolerances};

/// The platform plus two quadrature states: ∫ dH/dt dt (the cancelled form) and ∫ |y U| dt.
struct WithEnergy<'a> {
    model: &'a Platform,
    input: Input,
}

impl OdeSystem for WithEnergy<'_> {
    fn dim(&self) -> usize {
        self.model.n_states() + 2
    }
    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), RhsError> {
        let n = self.model.n_states();
        let u = self.input.value(t);
        let x = &y[..n];
        let err = |e: hasel_fmu::model::ModelError| RhsError(e.to_string());
        self.model.rhs(x, u, &mut dy[..n]).map_err(err)?;
        dy[n] = self.model.stored_power(x, u).map_err(err)?;
        dy[n + 1] = self.model.supplied_power(x, u).map_err(err)?.abs();
        Ok(())
    }
    fn jacobian(&self, t: f64, y: &[f64], jac: &mut [f64]) -> Result<(), RhsError> {
        // the quadrature rows do not feed back: J = [[Jx, 0], [0, 0]] up to their rows,
        // which the simplified Newton iteration may leave out
        let (n, dim) = (self.model.n_states(), self.dim());
        let mut jx = vec![0.0; n * n];
        self.model
            .jacobian(&y[..n], self.input.value(t), &mut jx)
            .map_err(|e| RhsError(e.to_string()))?;
        jac.fill(0.0);
        for c in 0..n {
            jac[c * dim..c * dim + n].copy_from_slice(&jx[c * n..(c + 1) * n]);
        }
        Ok(())
    }
}

#[test]
fn stored_energy_follows_supplied_minus_dissipated_power() {
    for reduction in Reduction::ALL {
        balance_holds(&Platform::reduced(Params::default(), reduction).unwrap());
    }
}

/// Over 2 s of the paper's sine, the change of `model`'s energy against its integrated power
/// balance (the stored power, checked pointwise against supplied − dissipated by the unit
/// tests).
fn balance_holds(model: &Platform) {
    let name = model.reduction().name();
    let sys = WithEnergy {
        model,
        input: Input::sine(60.0, 3.0 * std::f64::consts::PI),
    };
    let n = model.n_states();
    let mut y0 = model.rest_state().unwrap();
    y0.extend([0.0, 0.0]);
    let mut scales = model.state_scales();
    scales.extend([1e-6, 1.0]);
    let mut solver = Radau5::new(n + 2, Tolerances::scaled(1e-9, &scales));
    solver.init(&sys, 0.0, &y0, 1e-9).unwrap();
    let h0 = model.energy(&y0[..n]).unwrap();
    let (mut worst, mut worst_abs, mut stored_max): (f64, f64, f64) = (0.0, 0.0, 0.0);
    for k in 1..=20 {
        solver.advance(&sys, 0.1 * k as f64).unwrap();
        let y = solver.y();
        let change = model.energy(&y[..n]).unwrap() - h0;
        let supplied = y[n + 1];
        worst = worst.max((change - y[n]).abs() / supplied);
        worst_abs = worst_abs.max((change - y[n]).abs());
        stored_max = stored_max.max(change.abs());
    }
    let y = solver.y();
    println!(
        "{name}: after 2 s: H - H0 = {:.3e} J, supplied {:.3e} J; worst imbalance {worst_abs:.2e} J = {worst:.2e} of the supplied energy",
        model.energy(&y[..n]).unwrap() - h0,
        y[n + 1]
    );
    // the stored energy changes by ~1e-4 J while ~1e5 J flow through the ports
    assert!(
        worst < 1e-10,
        "{name}: imbalance {worst:e} of the supplied energy"
    );
    assert!(
        worst_abs < 1e-3 * stored_max,
        "{name}: imbalance {worst_abs:e} J against stored {stored_max:e} J"
    );
}
