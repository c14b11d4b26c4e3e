//! The platform: three independent actuators (15 states) and the kinematics to the tip.
//!
//! State layout: actuator i occupies x[5i .. 5i+5] as (θ, l_p, p, Q1, Q2).

use super::actuator::{self, Actuator, StateInfo};
use super::effects::terms::{Extra, Terms};
use super::invariant_curve::Curve;
use super::kinematics::Kinematics;
use super::linalg::bounded_svd;
use super::params::{ParamError, Params};
use super::reduction::Reduction;
use super::shell::DomainError;

/// What a reduced Jacobian differentiates by: the reduced states or the commands.
#[derive(Clone, Copy)]
pub(super) enum Wrt {
    States,
    Inputs,
}

/// The model cannot be evaluated at a state.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("actuator {actuator}: {cause}")]
pub struct ModelError {
    /// 1-based actuator index.
    pub actuator: usize,
    pub cause: DomainError,
}

/// The HASEL platform model, built from validated parameters: the three actuators of the paper
/// and the terms of the active effects (none by default).
#[derive(Clone, Debug)]
pub struct Platform {
    params: Params,
    pub actuators: [Actuator; 3],
    pub kinematics: Kinematics,
    pub(super) terms: Terms,
    /// States per actuator block of the full model: its five, then its effect states.
    pub(super) nb: usize,
    /// The full model or one of its reductions (`reduced`), which keeps a prefix of the five.
    pub(super) reduction: Reduction,
    /// Each actuator's invariant curve l_p(θ), tabulated for the slow model (empty otherwise).
    pub(super) curves: Vec<Curve>,
}

/// Newton iterations of [`Platform::settled_state`] at most: the settled states enter ẋ
/// almost linearly, so two or three reach rounding.
const SETTLE_NEWTON: usize = 8;

/// Number of states of the paper's model.
pub const N_STATES: usize = 3 * actuator::N;

/// One state of an actuator's block, whichever effects are on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BlockState {
    /// One of the paper's five, by its index in [`actuator::STATES`].
    Paper(usize),
    /// An effect's state, present while the effect is on.
    Extra(Extra),
}

impl BlockState {
    /// Name, unit and meaning (for an effect state: of its first stage).
    pub fn info(self) -> StateInfo {
        match self {
            BlockState::Paper(k) => actuator::STATES[k],
            BlockState::Extra(e) => e.info(),
        }
    }

    /// Name without the actuator suffix.
    pub fn name(self) -> String {
        match self {
            BlockState::Paper(k) => actuator::STATES[k].name.into(),
            BlockState::Extra(e) => e.name(),
        }
    }
}

impl Platform {
    /// Validates the parameters and derives the constants.
    pub fn new(params: Params) -> Result<Platform, ParamError> {
        params.validate()?;
        let terms = Terms::new(&params.effects);
        Ok(Platform {
            actuators: [0, 1, 2].map(|i| Actuator::new(&params, i)),
            kinematics: Kinematics::new(&params),
            nb: terms.block_size(),
            terms,
            params,
            reduction: Reduction::Full,
            curves: Vec::new(),
        })
    }

    /// The reduced model `reduction` of the platform of `params` (src/model/reduced.rs).
    pub fn reduced(params: Params, reduction: Reduction) -> Result<Platform, ParamError> {
        let full = Platform::new(params)?;
        let curves = if reduction.kept() <= actuator::L_P {
            let lv = full.params.lv;
            full.actuators.iter().map(|a| Curve::new(a, lv)).collect()
        } else {
            Vec::new()
        };
        Ok(Platform {
            reduction,
            curves,
            ..full
        })
    }

    /// Which model this is: the full one or a reduction.
    pub fn reduction(&self) -> Reduction {
        self.reduction
    }

    /// Whether this is the full model: states, ẋ and energy as the paper's.
    fn is_full(&self) -> bool {
        self.reduction == Reduction::Full
    }

    /// `full(self, arg)` for the full model, `reduced(self, arg)` for a reduction.
    fn per_model<A, T>(
        &self,
        arg: A,
        full: impl FnOnce(&Self, A) -> T,
        reduced: impl FnOnce(&Self, A) -> T,
    ) -> T {
        if self.is_full() {
            full(self, arg)
        } else {
            reduced(self, arg)
        }
    }

    /// States per actuator block of this model: the paper's states it keeps, then the
    /// effect states.
    pub(super) fn rb(&self) -> usize {
        self.reduction.kept() + self.nb - actuator::N
    }

    pub fn params(&self) -> &Params {
        &self.params
    }

    pub fn n_states(&self) -> usize {
        3 * self.rb()
    }

    /// Actuator i's block of this model's states.
    fn block<'x>(&self, x: &'x [f64], i: usize) -> &'x [f64] {
        &x[self.rb() * i..self.rb() * (i + 1)]
    }

    /// Actuator i's block of the full model's states.
    fn full_block<'x>(&self, x: &'x [f64], i: usize) -> &'x [f64] {
        &x[self.nb * i..self.nb * (i + 1)]
    }

    fn full_blocks<'x>(&self, x: &'x [f64]) -> [&'x [f64]; 3] {
        [0, 1, 2].map(|i| self.full_block(x, i))
    }

    fn refs(&self) -> [&Actuator; 3] {
        [0, 1, 2].map(|i| &self.actuators[i])
    }

    /// The states of each actuator's block, in block order: the paper's five, then the
    /// effect states of this configuration.
    pub fn block_states(&self) -> impl Iterator<Item = BlockState> + '_ {
        (0..self.reduction.kept())
            .map(BlockState::Paper)
            .chain(self.terms.extras.iter().map(|&e| BlockState::Extra(e)))
    }

    /// Names of the states, `theta_1, l_p_1, p_1, Q1_1, Q2_1, <effect states>_1, theta_2, …`.
    pub fn state_names(&self) -> Vec<String> {
        (1..=3)
            .flat_map(|i| {
                self.block_states()
                    .map(move |s| format!("{}_{i}", s.name()))
            })
            .collect()
    }

    /// Index of the state called `name` (see [`Platform::state_names`]).
    pub fn state_index(&self, name: &str) -> Option<usize> {
        self.state_names().iter().position(|n| n == name)
    }

    /// Index in x of actuator `i`'s (0-based) state `s`; `None` while `s` is the state of an
    /// effect that is off. No allocation: for per-call lookups such as the FMU's.
    pub fn state_position(&self, i: usize, s: BlockState) -> Option<usize> {
        let k = self.block_states().position(|b| b == s)?;
        Some(self.rb() * i + k)
    }

    pub(super) fn each<T>(
        &self,
        mut f: impl FnMut(usize, &Actuator) -> Result<T, DomainError>,
    ) -> Result<[T; 3], ModelError> {
        let wrap = |i: usize, r: Result<T, DomainError>| {
            r.map_err(|cause| ModelError {
                actuator: i + 1,
                cause,
            })
        };
        Ok([
            wrap(0, f(0, &self.actuators[0]))?,
            wrap(1, f(1, &self.actuators[1]))?,
            wrap(2, f(2, &self.actuators[2]))?,
        ])
    }

    /// The voltage actuator block `xi` receives for the command `u` [V].
    pub(super) fn port_voltage(&self, xi: &[f64], u: f64) -> f64 {
        if self.terms.neutral {
            u
        } else {
            self.terms.port(xi, u).u_eff
        }
    }

    /// ẋ = f(x, U) of this model (of the full one: `Platform::full_rhs`).
    pub fn rhs(&self, x: &[f64], u: [f64; 3], dx: &mut [f64]) -> Result<(), ModelError> {
        self.per_model(
            dx,
            |m, dx| m.full_rhs(x, u, dx),
            |m, dx| m.reduced_rhs(x, u, dx),
        )
    }

    /// ẋ = f(x, U) of the full model: each actuator at the voltage its port receives, then the
    /// effects' terms.
    pub(super) fn full_rhs(
        &self,
        x: &[f64],
        u: [f64; 3],
        dx: &mut [f64],
    ) -> Result<(), ModelError> {
        let nb = self.nb;
        self.each(|i, _| self.full_actuator_rhs(i, x, u, &mut dx[nb * i..nb * (i + 1)]))?;
        Ok(())
    }

    /// Actuator i's block of the full model's ẋ = f(x, U) into `dxi`: the actuator at the
    /// voltage its port receives, then the effects' terms.
    fn full_actuator_rhs(
        &self,
        i: usize,
        x: &[f64],
        u: [f64; 3],
        dxi: &mut [f64],
    ) -> Result<(), DomainError> {
        let n = actuator::N;
        let xs = self.full_blocks(x);
        self.actuators[i].rhs(&xs[i][..n], self.port_voltage(xs[i], u[i]), &mut dxi[..n])?;
        if self.terms.neutral {
            return Ok(());
        }
        self.terms.add_rhs(&self.refs(), xs, u[i], i, dxi)
    }

    /// Actuator i's block of ẋ = f(x, U) into `dxi`, for a model whose Jacobian's blocks are
    /// the actuators' ([`Platform::jacobian_blocks`]): only actuator i's states and its own and
    /// the common parameters enter it, so a parameter of actuator i moves no other block.
    pub fn actuator_rhs(
        &self,
        i: usize,
        x: &[f64],
        u: [f64; 3],
        dxi: &mut [f64],
    ) -> Result<(), ModelError> {
        if self.is_full() {
            return self
                .full_actuator_rhs(i, x, u, dxi)
                .map_err(|cause| ModelError {
                    actuator: i + 1,
                    cause,
                });
        }
        let mut dx = vec![0.0; x.len()];
        self.rhs(x, u, &mut dx)?;
        dxi.copy_from_slice(self.block(&dx, i));
        Ok(())
    }

    /// ∂f/∂x into `jac`, column-major `n_states × n_states`.
    pub fn jacobian(&self, x: &[f64], u: [f64; 3], jac: &mut [f64]) -> Result<(), ModelError> {
        let dim = self.n_states();
        jac.fill(0.0);
        self.jacobian_entries(x, u, |r, c, v| jac[c * dim + r] += v)
    }

    /// The entries of ∂f/∂x through `add(row, col, value)` (an entry may come in parts that add
    /// up). Every entry the equations can make nonzero is given, whatever its value here, so
    /// the positions given are the Jacobian's structure for this model.
    pub fn jacobian_entries(
        &self,
        x: &[f64],
        u: [f64; 3],
        add: impl FnMut(usize, usize, f64),
    ) -> Result<(), ModelError> {
        self.per_model(
            add,
            |m, add| m.full_jacobian_entries(x, u, add),
            |m, add| m.reduced_entries(x, u, Wrt::States, add),
        )
    }

    /// The entries of the full model's ∂f/∂x, as [`Platform::jacobian_entries`]: each
    /// actuator's own, at the voltage its port receives, then the effects' terms.
    pub(super) fn full_jacobian_entries(
        &self,
        x: &[f64],
        u: [f64; 3],
        mut add: impl FnMut(usize, usize, f64),
    ) -> Result<(), ModelError> {
        let nb = self.nb;
        let xs = self.full_blocks(x);
        let refs = self.refs();
        let offset = [0, nb, 2 * nb];
        self.each(|i, a| {
            let o = offset[i];
            a.jacobian(
                &xs[i][..actuator::N],
                self.port_voltage(xs[i], u[i]),
                |r, c, v| add(o + r, o + c, v),
            )?;
            if self.terms.neutral {
                return Ok(());
            }
            self.terms
                .add_jacobian(&refs, xs, u[i], i, offset, &mut add)
        })?;
        Ok(())
    }

    /// ∂f/∂U into `jac`, column-major `n_states × 3` (column j: the command U_j). The command
    /// enters ẋ = (J − R)∇H + g(x) U (model.md, "Dynamics") through g(x) = G0 ga(θ) (e_Q1 + e_Q2)
    /// at the port voltage; with effects, through the first amplifier stage, or through the
    /// clipping's slope into the circuit and the drift stages (`effects::terms`).
    pub fn input_jacobian(
        &self,
        x: &[f64],
        u: [f64; 3],
        jac: &mut [f64],
    ) -> Result<(), ModelError> {
        let dim = self.n_states();
        jac.fill(0.0);
        self.input_jacobian_entries(x, u, |r, j, v| jac[j * dim + r] += v)
    }

    /// The entries of ∂f/∂U through `add(row, j, value)` (column j: the command U_j), every
    /// entry the equations can make nonzero, as in [`Platform::jacobian_entries`].
    pub fn input_jacobian_entries(
        &self,
        x: &[f64],
        u: [f64; 3],
        add: impl FnMut(usize, usize, f64),
    ) -> Result<(), ModelError> {
        self.per_model(
            add,
            |m, add| m.full_input_jacobian_entries(x, u, add),
            |m, add| m.reduced_entries(x, u, Wrt::Inputs, add),
        )
    }

    /// The entries of the full model's ∂f/∂U, as [`Platform::input_jacobian_entries`].
    pub(super) fn full_input_jacobian_entries(
        &self,
        x: &[f64],
        u: [f64; 3],
        mut add: impl FnMut(usize, usize, f64),
    ) -> Result<(), ModelError> {
        let nb = self.nb;
        let xs = self.full_blocks(x);
        let refs = self.refs();
        self.each(|i, a| {
            let o = nb * i;
            if self.terms.neutral {
                // g(x) = G0 ga(θ) (e_Q1 + e_Q2)
                let g = a.structure(&xs[i][..actuator::N])?.g;
                add(o + actuator::Q1, i, g[actuator::Q1]);
                add(o + actuator::Q2, i, g[actuator::Q2]);
            } else {
                self.terms
                    .add_input_jacobian(&refs, xs, u[i], i, |r, v| add(o + r, i, v));
            }
            Ok(())
        })?;
        Ok(())
    }

    /// The outputs y = (h1, h2, h3, tip_x, tip_y, tip_z) \[m\], as the FMU's.
    pub fn outputs(&self, x: &[f64]) -> [f64; 6] {
        let h = self.heights(x);
        let tip = self.kinematics.tip(h);
        [h[0], h[1], h[2], tip[0], tip[1], tip[2]]
    }

    /// ∂y/∂x of [`Platform::outputs`] into `jac`, column-major `6 × n_states`: the heights
    /// h_i = ½ Lv sin θ_i give ∂h_i/∂θ_i = ½ Lv cos θ_i (model.md, "Kinematics"); the tip,
    /// an explicit function of the heights (FKM: Tip = C_p + L n), gives ∂Tip/∂θ_i =
    /// ∂Tip/∂h_i · ∂h_i/∂θ_i with ∂Tip/∂h from [`Kinematics::tip_jacobian`]. No other state
    /// moves an output.
    pub fn output_jacobian(&self, x: &[f64], jac: &mut [f64]) {
        jac[..6 * self.n_states()].fill(0.0);
        self.output_jacobian_entries(x, |r, c, v| jac[c * 6 + r] = v);
    }

    /// The entries of ∂y/∂x through `set(output, state, value)`, each once: the structure of
    /// ∂y/∂x, whatever the values (see [`Platform::output_jacobian`]).
    pub fn output_jacobian_entries(&self, x: &[f64], mut set: impl FnMut(usize, usize, f64)) {
        let tip = self.kinematics.tip_jacobian(self.heights(x));
        for i in 0..3 {
            let col = self.rb() * i + actuator::THETA;
            let slope = self.actuators[i].height_slope(self.block(x, i)[actuator::THETA]);
            set(i, col, slope);
            for k in 0..3 {
                set(3 + k, col, tip[(k, i)] * slope);
            }
        }
    }

    /// Whether `other` maps states to outputs as this model does (the same heights
    /// h_i = ½ Lv sin θ_i and the same kinematics), so that only the states tell their outputs
    /// apart.
    pub fn same_output_map(&self, other: &Platform) -> bool {
        self.kinematics == other.kinematics
            && (0..3).all(|i| self.actuators[i].height(1.0) == other.actuators[i].height(1.0))
    }

    /// ∂y/∂U of [`Platform::outputs`], row-major 6 × 3: zero, the outputs depend on the states
    /// only (no direct feedthrough).
    pub fn output_input_jacobian(&self) -> [[f64; 3]; 6] {
        [[0.0; 3]; 6]
    }

    /// The voltage each actuator's port receives for the commands `u` at state `x` \[V\]: U
    /// itself, or after the amplifier's lag and clipping when those effects are on.
    pub fn port_voltages(&self, x: &[f64], u: [f64; 3]) -> [f64; 3] {
        // the port reads the effect states only, which every model keeps after its own
        let kept = self.reduction.kept();
        [0, 1, 2].map(|i| {
            let mut xi = vec![0.0; self.nb];
            let own = self.block(x, i);
            xi[..kept].copy_from_slice(&own[..kept]);
            xi[actuator::N..].copy_from_slice(&own[kept..]);
            self.port_voltage(&xi, u[i])
        })
    }

    /// The effects' extra states of each actuator block, in block order (after its five).
    pub fn extra_states(&self) -> &[Extra] {
        &self.terms.extras
    }

    /// Sizes of the diagonal blocks of ∂f/∂x: the actuators are independent unless coupled.
    pub fn jacobian_blocks(&self) -> Vec<usize> {
        if self.terms.links_actuators() {
            vec![self.n_states()]
        } else {
            vec![self.rb(); 3]
        }
    }

    /// The initial state (book/src/model.md, "Initial state"): each actuator at its U = 0
    /// equilibrium under gravity (and the static loads of the effects), solved actuator by
    /// actuator until the coupling settles.
    pub fn rest_state(&self) -> Result<Vec<f64>, ModelError> {
        Ok(self.own_state(self.full_rest_state()?))
    }

    /// This model's state of the full model's state `x` (`x` itself, or its reduced coordinates).
    fn own_state(&self, x: Vec<f64>) -> Vec<f64> {
        self.per_model(x, |_, x| x, |m, x| m.project(&x))
    }

    fn full_rest_state(&self) -> Result<Vec<f64>, ModelError> {
        let refs = self.refs();
        let mut rest = self.uncoupled_rest_blocks()?;
        for _ in 0..50 {
            let before = rest.map(|r| r[actuator::THETA]);
            for i in 0..3 {
                let theta = rest.map(|r| r[actuator::THETA]);
                let load = |t: f64| {
                    let mut th = theta;
                    th[i] = t;
                    self.terms.rest_load(&refs, th, i)
                };
                rest[i] = self.actuators[i]
                    .rest_state_with(load)
                    .map_err(|cause| ModelError {
                        actuator: i + 1,
                        cause,
                    })?;
            }
            let moved = (0..3).map(|i| (rest[i][actuator::THETA] - before[i]).abs());
            if moved.fold(0.0, f64::max) <= 1e-15 {
                break;
            }
        }
        Ok(self.with_effects_at_rest(&rest))
    }

    /// A state on the slow manifold (book/src/model.md, "A start mid-run"): the actuators at
    /// angles `theta`, (θ, l_p) on the invariant curve, p = 0, the effects' states at `slow`
    /// (each actuator's extra states in block order, actuator after actuator) or, where `slow`
    /// does not give them all, settled with the rest: every other state (the charges, the
    /// effects' states) at ẋ = 0 at command `u` with the mechanics held. What a record that
    /// starts mid-run starts from: the angles move on the slow time scale (tens of ms to
    /// 0.4 s), the charges relax in ns; the effects' states follow the angle and the command
    /// (creep, amplifier, trapped charge) slowly enough to stand elsewhere than settled when
    /// the device was driven before.
    pub fn settled_state(
        &self,
        theta: [f64; 3],
        slow: &[f64],
        u: [f64; 3],
    ) -> Result<Vec<f64>, ModelError> {
        Ok(self.own_state(self.full_settled_state(theta, slow, u)?))
    }

    fn full_settled_state(
        &self,
        theta: [f64; 3],
        slow: &[f64],
        u: [f64; 3],
    ) -> Result<Vec<f64>, ModelError> {
        let blocks = self.each(|i, a| {
            let t = theta[i];
            Ok([t, a.l_p_on_curve(t)?, 0.0, 0.0, 0.0])
        })?;
        let mut x = self.with_effects_at_rest(&blocks);
        let extras = self.nb - actuator::N;
        let given = slow.len() == 3 * extras && extras > 0;
        if given {
            for (i, block) in slow.chunks(extras).enumerate() {
                x[self.nb * i + actuator::N..self.nb * (i + 1)].copy_from_slice(block);
            }
        }
        let settles = |k: usize| {
            let j = k % self.nb;
            j > actuator::P && (j < actuator::N || !given)
        };
        self.settle(&mut x, u, settles)?;
        Ok(x)
    }

    /// Number of the effects' states, over the three actuators.
    pub fn n_effect_states(&self) -> usize {
        3 * (self.nb - actuator::N)
    }

    /// The effects' states of `x`, each actuator's in block order, actuator after actuator:
    /// the `slow` of [`Platform::settled_state`].
    pub fn effect_states(&self, x: &[f64]) -> Vec<f64> {
        (0..3)
            .flat_map(|i| &self.block(x, i)[self.reduction.kept()..])
            .copied()
            .collect()
    }

    /// Newton on the states `settles` picks, to ẋ = 0 for them at command `u` with the others
    /// held, in the states' scaled coordinates; a direction that does not move ẋ (a
    /// hysteretic state that does not relax) keeps its value.
    pub(super) fn settle(
        &self,
        x: &mut [f64],
        u: [f64; 3],
        settles: impl Fn(usize) -> bool,
    ) -> Result<(), ModelError> {
        let n = x.len();
        let free: Vec<usize> = (0..n).filter(|&k| settles(k)).collect();
        let scale = self.full_state_scales();
        let (mut f, mut jac) = (vec![0.0; n], vec![0.0; n * n]);
        for _ in 0..SETTLE_NEWTON {
            self.full_rhs(x, u, &mut f)?;
            jac.fill(0.0);
            self.full_jacobian_entries(x, u, |r, c, v| jac[c * n + r] += v)?;
            let m = free.len();
            let a = nalgebra::DMatrix::from_fn(m, m, |r, c| {
                jac[free[c] * n + free[r]] * scale[free[c]] / scale[free[r]]
            });
            let b = nalgebra::DVector::from_fn(m, |r, _| -f[free[r]] / scale[free[r]]);
            // a state the fit tries at the domain's edge must not hang the diagnosis
            let Some(svd) = bounded_svd(a) else {
                break;
            };
            let eps = 1e-12 * svd.singular_values.max();
            let Ok(step) = svd.solve(&b, eps) else {
                break;
            };
            for (r, &k) in free.iter().enumerate() {
                x[k] += step[r] * scale[k];
            }
            if step.amax() < 1e-13 {
                break;
            }
        }
        Ok(())
    }

    /// Where [`Platform::rest_state`] starts: each actuator at its own U = 0 equilibrium, as if
    /// the effects put no static load on it, and the effects' states at rest. A state inside
    /// the model's domain for a tenth of the work, enough where the state's value does not
    /// matter (the positions of the Jacobian's entries, `fmu::structure`).
    pub fn uncoupled_rest_state(&self) -> Result<Vec<f64>, ModelError> {
        Ok(self.own_state(self.with_effects_at_rest(&self.uncoupled_rest_blocks()?)))
    }

    fn uncoupled_rest_blocks(&self) -> Result<[[f64; actuator::N]; 3], ModelError> {
        self.each(|_, a| a.rest_state())
    }

    /// The state vector of the actuators' states `blocks`, each followed by its effect states
    /// at rest.
    fn with_effects_at_rest(&self, blocks: &[[f64; actuator::N]; 3]) -> Vec<f64> {
        blocks
            .iter()
            .flat_map(|r| r.iter().copied().chain(self.terms.rest(r[actuator::THETA])))
            .collect()
    }

    /// Actuator heights h_i = ½ Lv sin θ_i \[m\].
    pub fn heights(&self, x: &[f64]) -> [f64; 3] {
        [0, 1, 2].map(|i| self.actuators[i].height(self.block(x, i)[actuator::THETA]))
    }

    /// Antenna tip from the FKM \[m\].
    pub fn tip(&self, x: &[f64]) -> [f64; 3] {
        self.kinematics.tip(self.heights(x))
    }

    /// Stored energy H \[J\] of this model, the effects' terms included.
    pub fn energy(&self, x: &[f64]) -> Result<f64, ModelError> {
        self.per_model(x, Self::full_energy, Self::reduced_energy)
    }

    pub(super) fn full_energy(&self, x: &[f64]) -> Result<f64, ModelError> {
        let xs = self.full_blocks(x);
        let own: f64 = self
            .each(|i, a| a.energy(&xs[i][..actuator::N]))?
            .iter()
            .sum();
        Ok(own + self.terms.energy(&self.refs(), xs))
    }

    /// Power supplied to this model \[W\]: of the full one, through the electrical ports at the
    /// voltages they receive.
    pub fn supplied_power(&self, x: &[f64], u: [f64; 3]) -> Result<f64, ModelError> {
        self.per_model(
            x,
            |m, x| m.full_supplied_power(x, u),
            |m, x| m.reduced_supplied_power(x, u),
        )
    }

    pub(super) fn full_supplied_power(&self, x: &[f64], u: [f64; 3]) -> Result<f64, ModelError> {
        let (xs, refs) = (self.full_blocks(x), self.refs());
        Ok(self
            .each(|i, a| {
                Ok(
                    a.port_output(&xs[i][..actuator::N])? * self.port_voltage(xs[i], u[i])
                        + self.terms.port_power(&refs, xs, u[i], i),
                )
            })?
            .iter()
            .sum())
    }

    /// Dissipated power at state `x` with the commands at 0 \[W\]: of the full model, its
    /// dissipated power at `x` whatever the command (see [`Platform::dissipated_power_at`]).
    pub fn dissipated_power(&self, x: &[f64]) -> Result<f64, ModelError> {
        self.dissipated_power_at(x, [0.0; 3])
    }

    /// Dissipated power at state `x` under the commands `u`, the effects' dashpots, resistors
    /// and hysteretic work included \[W\]. Only a reduced model's depends on `u`: its
    /// quasi-static charges (and momentum) follow the command.
    pub fn dissipated_power_at(&self, x: &[f64], u: [f64; 3]) -> Result<f64, ModelError> {
        self.per_model(x, Self::full_dissipated_power, |m, x| {
            m.reduced_dissipated_power(x, u)
        })
    }

    pub(super) fn full_dissipated_power(&self, x: &[f64]) -> Result<f64, ModelError> {
        let xs = self.full_blocks(x);
        Ok(self
            .each(|i, a| {
                Ok(a.dissipation(&xs[i][..actuator::N])? + self.terms.dissipation(a, xs[i])?)
            })?
            .iter()
            .sum())
    }

    /// dH/dt along the flow with the large electrical terms cancelled analytically \[W\].
    pub fn stored_power(&self, x: &[f64], u: [f64; 3]) -> Result<f64, ModelError> {
        self.per_model(
            x,
            |m, x| m.full_stored_power(x, u),
            |m, x| m.reduced_stored_power(x, u),
        )
    }

    pub(super) fn full_stored_power(&self, x: &[f64], u: [f64; 3]) -> Result<f64, ModelError> {
        let (xs, refs) = (self.full_blocks(x), self.refs());
        Ok(self
            .each(|i, a| {
                Ok(
                    a.stored_power(&xs[i][..actuator::N], self.port_voltage(xs[i], u[i]))?
                        + self.terms.port_power(&refs, xs, u[i], i)
                        - self.terms.dissipation(a, xs[i])?,
                )
            })?
            .iter()
            .sum())
    }

    /// Per-state scale for absolute tolerances (see [`Actuator::state_scales`]).
    pub fn state_scales(&self) -> Vec<f64> {
        self.own_state(self.full_state_scales())
    }

    pub(super) fn full_state_scales(&self) -> Vec<f64> {
        self.actuators
            .iter()
            .flat_map(|a| {
                let own = a.state_scales();
                own.into_iter()
                    .chain(self.terms.scales(a, own[actuator::THETA]))
            })
            .collect()
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    fn platform() -> Platform {
        Platform::new(Params::default()).unwrap()
    }

    /// The slow manifold's state: at the rest angles and 0 V, the rest state; mid-stroke at a
    /// held command, every state but the mechanics' at rest (ẋ = 0 there), an amplifier's output
    /// at the command and a creep element relaxed to the angle.
    #[test]
    fn a_settled_state_is_at_rest_in_all_but_the_mechanics() {
        let p = platform();
        let rest = p.rest_state().unwrap();
        let theta = [0, 1, 2].map(|i| rest[i * actuator::N]);
        let settled = p.settled_state(theta, &[], [0.0; 3]).unwrap();
        for (k, (a, b)) in settled.iter().zip(&rest).enumerate() {
            assert!(
                (a - b).abs() <= 1e-12 * p.state_scales()[k],
                "state {k}: {a:e} {b:e}"
            );
        }
        let mut params = Params::default();
        params.set("tau_a", 0.02).unwrap();
        params.set("k_v", 0.1).unwrap();
        params.set("tau_v", 0.5).unwrap();
        let p = Platform::new(params).unwrap();
        let u = [40.0, 55.0, 20.0];
        let x = p.settled_state([0.004, 0.008, 0.002], &[], u).unwrap();
        let mut dx = vec![0.0; x.len()];
        p.rhs(&x, u, &mut dx).unwrap();
        let scales = p.state_scales();
        for (k, name) in p.state_names().iter().enumerate() {
            // the charges relax at ~1e8 /s: a rate of 1e-3 scale/s is 1e-11 of the scale away
            if !(name.starts_with("theta") || name.starts_with("l_p") || name.starts_with("p_")) {
                assert!(
                    dx[k].abs() <= 1e-3 * scales[k],
                    "{name}: d/dt = {:e}",
                    dx[k]
                );
            }
        }
        for i in 0..3 {
            let at = |n: &str| x[p.state_index(&format!("{n}_{}", i + 1)).unwrap()];
            assert!((at("U_amp") - u[i]).abs() < 1e-9, "{}", at("U_amp"));
            assert!((at("z_v") - at("theta")).abs() < 1e-15);
        }
    }

    #[test]
    fn a_settled_state_keeps_the_effects_states_it_is_given() {
        let mut params = Params::default();
        params.set("tau_a", 0.02).unwrap();
        params.set("k_v", 0.1).unwrap();
        params.set("tau_v", 0.5).unwrap();
        let p = Platform::new(params).unwrap();
        let (theta, u) = ([0.004, 0.008, 0.002], [40.0, 55.0, 20.0]);
        let settled = p.settled_state(theta, &[], u).unwrap();
        // the amplifier behind its command, the creep behind its angle
        let slow: Vec<f64> = p
            .effect_states(&settled)
            .iter()
            .enumerate()
            .map(|(k, v)| v * (0.5 + 0.1 * k as f64))
            .collect();
        let x = p.settled_state(theta, &slow, u).unwrap();
        assert_eq!(p.effect_states(&x), slow);
        let mut dx = vec![0.0; x.len()];
        p.rhs(&x, u, &mut dx).unwrap();
        let scales = p.state_scales();
        for (k, name) in p.state_names().iter().enumerate() {
            if name.starts_with('Q') {
                assert!(dx[k].abs() <= 1e-3 * scales[k], "{name}: {:e}", dx[k]);
            }
        }
        // a start that does not give them all settles them
        assert_eq!(p.settled_state(theta, &slow[1..], u).unwrap(), settled);
    }

    /// A state away from rest with charges, momentum and a zipped electrode.
    fn busy_state(p: &Platform) -> Vec<f64> {
        let mut x = Vec::new();
        for (i, a) in p.actuators.iter().enumerate() {
            let theta = 0.004 * (i as f64 + 1.0);
            let l_p = a.l_p_on_curve(theta).unwrap();
            x.extend_from_slice(&[theta, l_p, 3e-8 * (i as f64 - 1.0), 2e-9, 3e-8]);
        }
        x
    }

    #[test]
    fn rest_state_matches_the_spec_and_stays_put() {
        let p = platform();
        let x = p.rest_state().unwrap();
        let h = p.heights(&x);
        // book/src/model.md, "Initial state": θ ≈ −2.2e-4 rad, h ≈ −1.31 / −1.33 / −1.33 µm,
        // l_p − Lp ≈ −0.68 µm
        for (hi, want) in h.iter().zip([-1.31e-6, -1.33e-6, -1.33e-6]) {
            assert!((hi - want).abs() < 0.006e-6, "h = {h:?}");
        }
        assert!((x[1] - 0.014 + 0.68e-6).abs() < 0.01e-6);
        let mut dx = vec![0.0; N_STATES];
        p.rhs(&x, [0.0; 3], &mut dx).unwrap();
        // ṗ ≈ 0 relative to the size of its terms (Kb θ ≈ 7e-5 N m)
        for i in 0..3 {
            assert!(dx[5 * i + 2].abs() < 1e-15, "p_dot = {}", dx[5 * i + 2]);
        }
    }

    /// The analytic ∂f/∂x of `p` at `x`, `u` against central differences, each entry relative
    /// to its row's largest entry times the column's state scale.
    pub(crate) fn assert_jacobian_matches(p: &Platform, x: &[f64], u: [f64; 3]) {
        let n = p.n_states();
        let mut jac = vec![0.0; n * n];
        p.jacobian(x, u, &mut jac).unwrap();
        let scales = p.state_scales();
        let names = p.state_names();
        let (mut fp, mut fm) = (vec![0.0; n], vec![0.0; n]);
        for c in 0..n {
            let hc = 1e-6 * scales[c];
            let (mut xp, mut xm) = (x.to_vec(), x.to_vec());
            xp[c] += hc;
            xm[c] -= hc;
            p.rhs(&xp, u, &mut fp).unwrap();
            p.rhs(&xm, u, &mut fm).unwrap();
            for r in 0..n {
                let fd = (fp[r] - fm[r]) / (2.0 * hc);
                let an = jac[c * n + r];
                let row_scale = (0..n)
                    .map(|k| (jac[k * n + r] * scales[k]).abs())
                    .fold(0.0, f64::max);
                // the difference's own rounding: a few ulps of f over the relative step
                let rounding = 4.0 * f64::EPSILON * fp[r].abs().max(fm[r].abs()) / 1e-6;
                assert!(
                    (an - fd).abs() * scales[c] <= 1e-6 * row_scale + rounding + 1e-300,
                    "d{}/d{}: analytic {an:e} vs fd {fd:e}",
                    names[r],
                    names[c]
                );
            }
        }
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let p = platform();
        assert_jacobian_matches(&p, &busy_state(&p), [60.0, 25.0, -40.0]);
    }

    #[test]
    fn power_balance_holds_pointwise() {
        // ∇H · f = y U − D: the port-Hamiltonian structure, relative to the supplied power
        let p = platform();
        let x = busy_state(&p);
        let u = [60.0, 25.0, -40.0];
        let mut dx = vec![0.0; N_STATES];
        p.rhs(&x, u, &mut dx).unwrap();
        let mut dh = 0.0;
        for (i, a) in p.actuators.iter().enumerate() {
            let g = a.grad_h(&x[5 * i..5 * i + 5]).unwrap();
            dh += (0..5).map(|k| g[k] * dx[5 * i + k]).sum::<f64>();
        }
        let supplied = p.supplied_power(&x, u).unwrap();
        let dissipated = p.dissipated_power(&x).unwrap();
        let scale = supplied.abs() + dissipated;
        assert!((dh - (supplied - dissipated)).abs() < 1e-12 * scale);
        let stored = p.stored_power(&x, u).unwrap();
        assert!((dh - stored).abs() < 1e-12 * scale, "{dh} vs {stored}");
    }

    #[test]
    fn evaluation_outside_the_domain_names_the_actuator() {
        let p = platform();
        let mut x = p.rest_state().unwrap();
        x[5 + 1] = 0.011; // l_p of actuator 2 below Lv
        let mut dx = vec![0.0; N_STATES];
        let e = p.rhs(&x, [0.0; 3], &mut dx).unwrap_err();
        assert_eq!(e.actuator, 2);
        assert!(
            e.to_string()
                .starts_with("actuator 2: shell geometry undefined")
        );
    }
}
