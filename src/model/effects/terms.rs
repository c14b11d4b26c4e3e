//! The families' terms around the actuator equations (book/src/effects.md, "How effects
//! enter the model"): the extra states of each actuator, the voltage the actuator's port
//! receives, the torques on θ, the extra circuit branch, and their energy, dissipation and
//! Jacobian entries. Each family writes its own terms as a [`Law`]; the registry's laws, one
//! field each, are called in registry order, statically.
//!
//! Each actuator's block of states is its five (θ, l_p, p, Q1, Q2) followed by the extra
//! states of the active families, in registry order. Only `coupling` links the blocks.

use super::{Effect, EffectParams, Laws};
use crate::model::actuator::{self, Actuator, P, Q1, Q2, StateInfo, THETA};
use crate::model::shell::DomainError;

/// An extra state of one actuator: stage `stage` of a family's state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Extra {
    pub effect: Effect,
    pub stage: usize,
}

impl Extra {
    /// The states the parameter table can switch on, in block order: the family states every
    /// configuration can name (the FMU's state variables).
    pub fn table_states() -> impl Iterator<Item = Extra> {
        Effect::ALL.into_iter().flat_map(|effect| {
            (0..effect.family().table_stages).map(move |stage| Extra { effect, stage })
        })
    }

    /// Name of the first stage, unit and meaning; every stage shares unit and meaning.
    pub fn info(self) -> StateInfo {
        self.effect
            .family()
            .state
            .expect("a family with states names them")
    }

    /// Name without the actuator suffix: the first stage's name, numbered from the second.
    pub fn name(self) -> String {
        let name = self.info().name;
        if self.stage > 0 {
            format!("{name}{}", self.stage + 1)
        } else {
            name.into()
        }
    }
}

/// The extra states of one actuator block as the laws take them.
#[derive(Default)]
pub struct States(Vec<Extra>);

impl States {
    /// Adds stage `stage` of `effect`'s state; its index in the block.
    pub fn push(&mut self, effect: Effect, stage: usize) -> usize {
        self.0.push(Extra { effect, stage });
        actuator::N + self.0.len() - 1
    }

    /// The states of a family of elements (weight, and a time or an angle) on a fixed grid, the
    /// creep's branches or the hysteresis's plays (effects.md, "How effects enter the model"):
    /// stage 0 the free element, 1 … n the grid's, the synthetic ones after them; (index,
    /// weight, time or angle) of each that is on. The free and synthetic elements are on with
    /// a weight above 0; the grid's come all together when `grid_on`, a weight of 0 among them
    /// included: a fit moves weights to and from 0, and a state that came and went with its
    /// weight would have no sensitivity.
    pub fn push_grid(
        &mut self,
        effect: Effect,
        free: (f64, f64),
        grid: impl Iterator<Item = (f64, f64)>,
        grid_on: bool,
        spread: impl Iterator<Item = (f64, f64)>,
    ) -> Vec<(usize, f64, f64)> {
        let on = |(w, x): (f64, f64)| (w, x, w > 0.0);
        std::iter::once(on(free))
            .chain(grid.map(|(w, x)| (w, x, grid_on)))
            .chain(spread.map(on))
            .enumerate()
            .filter(|(_, (_, _, on))| *on)
            .map(|(stage, (w, x, _))| (self.push(effect, stage), w, x))
            .collect()
    }
}

/// The voltage at an actuator's port.
#[derive(Clone, Copy)]
pub struct Port {
    /// Voltage at the actuator's port after the input path's stages \[V\].
    pub u_eff: f64,
    /// ∂u_eff / ∂(what the port reads: `column`, or the command U).
    pub slope: f64,
    /// The state of the block the port reads (the last amplifier stage); `None`: the command.
    pub column: Option<usize>,
}

/// Where a family's terms are evaluated: actuator `i` of the three, its command `u` and the
/// voltage its port receives.
pub struct At<'a> {
    pub a: &'a [&'a Actuator; 3],
    pub x: [&'a [f64]; 3],
    pub u: f64,
    pub i: usize,
    pub port: Port,
}

impl At<'_> {
    pub fn act(&self) -> &Actuator {
        self.a[self.i]
    }

    pub fn xi(&self) -> &[f64] {
        self.x[self.i]
    }

    /// ∂(G0 ga(θ) u_eff)/∂(what the port reads): how the port drives the circuit.
    pub fn source(&self) -> f64 {
        let act = self.act();
        act.g0 * act.ga(self.xi()[THETA]) * self.port.slope
    }
}

/// ∂H/∂θ_i of the static energies and its derivative in θ_i, summed over the families.
#[derive(Clone, Copy, Default)]
pub struct Torque {
    pub h_t: f64,
    pub h_tt: f64,
}

/// A family's terms, derived once from its parameters; every method's default adds nothing.
/// Rows and columns are counted inside actuator i's block unless said otherwise.
pub trait Law: Sized {
    type Params;

    /// The terms of `p`, taking their states from `states` (none while the family is off).
    fn new(p: &Self::Params, states: &mut States) -> Self;

    /// Whether the terms link the actuators' blocks.
    fn links_actuators(&self) -> bool {
        false
    }

    /// Passes the port voltage through the family's stage of the input path
    /// (effects.md, "The voltage at the port").
    fn port(&self, _xi: &[f64], _port: &mut Port) {}

    /// Rows beyond Q1 and Q2 that the port voltage drives through G0 ga(θ) u_eff.
    fn port_rows(&self, _rows: &mut impl FnMut(usize)) {}

    /// Adds the family's static energy's ∂H/∂θ_i and its derivative at angles θ.
    fn static_torque(&self, _a: &[&Actuator; 3], _theta: [f64; 3], _i: usize, _t: &mut Torque) {}

    /// Adds the family's dynamic terms to actuator i's block of ẋ.
    fn add_rhs(&self, _at: &At, _dx: &mut [f64]) -> Result<(), DomainError> {
        Ok(())
    }

    /// Adds the entries of ∂ẋ/∂x of [`Law::add_rhs`] (and of the static torque's coupling
    /// across the blocks) through `add(row, col, value)`, counted in the whole state vector;
    /// `offset[j]` is where block j starts.
    fn add_jacobian(
        &self,
        _at: &At,
        _offset: [usize; 3],
        _add: &mut impl FnMut(usize, usize, f64),
    ) -> Result<(), DomainError> {
        Ok(())
    }

    /// Adds the family's entries of ∂ẋ/∂U beyond the port's.
    fn add_input_jacobian(&self, _at: &At, _add: &mut impl FnMut(usize, f64)) {}

    /// Energy stored in the family's terms \[J\], all actuators.
    fn energy(&self, _a: &[&Actuator; 3], _x: [&[f64]; 3]) -> f64 {
        0.0
    }

    /// Power at actuator i's port beyond the actuator's own y·u_eff \[W\].
    fn port_power(&self, _at: &At) -> f64 {
        0.0
    }

    /// Dissipation of actuator i beyond the actuator's own \[W\].
    fn dissipation(&self, _act: &Actuator, _xi: &[f64]) -> Result<f64, DomainError> {
        Ok(0.0)
    }

    /// Appends the family's states at rest (U = 0, θ at its rest value).
    fn rest(&self, _theta: f64, _out: &mut Vec<f64>) {}

    /// Appends the scale of each of the family's states, for absolute tolerances.
    fn scales(&self, _a: &Actuator, _theta_star: f64, _out: &mut Vec<f64>) {}
}

/// How much looser than θ's own a state that acts on θ only through a torque may be kept.
const LOOSEST_TORQUE_STATE: f64 = 10.0;

/// The absolute-tolerance scale of a state x that acts on actuator `a`'s angle only through a
/// torque −k x (book/src/solver.md, "States weighted by their effect on θ"): an error δx moves θ
/// by about k δx / Kb, so θ's scale θ* times Kb/k, never tighter than θ*, at most
/// [`LOOSEST_TORQUE_STATE`] times looser (at a weight near 0 the state still carries the
/// weight's sensitivity).
pub(super) fn torque_state_scale(a: &Actuator, theta_star: f64, k: f64) -> f64 {
    theta_star * (a.par.kb / k).clamp(1.0, LOOSEST_TORQUE_STATE)
}

/// The terms of the active families, derived once from the parameters.
#[derive(Clone, Debug)]
pub struct Terms {
    /// No family is on: the platform skips the terms (the paper's model, at its own speed).
    pub neutral: bool,
    /// The extra states of every actuator, in block order.
    pub extras: Vec<Extra>,
    laws: Laws,
}

impl Terms {
    pub fn new(fx: &EffectParams) -> Terms {
        let mut states = States::default();
        let laws = Laws::new(fx, &mut states);
        Terms {
            neutral: fx.active().is_empty(),
            extras: states.0,
            laws,
        }
    }

    /// States per actuator block.
    pub fn block_size(&self) -> usize {
        actuator::N + self.extras.len()
    }

    /// Whether the terms link the actuators' blocks.
    pub fn links_actuators(&self) -> bool {
        self.laws.links_actuators()
    }

    /// The extra states at rest (U = 0, θ at its rest value).
    pub fn rest(&self, theta: f64) -> Vec<f64> {
        let mut out = Vec::with_capacity(self.extras.len());
        self.laws.rest(theta, &mut out);
        out
    }

    /// Scale of each extra state for absolute tolerances.
    pub fn scales(&self, a: &Actuator, theta_star: f64) -> Vec<f64> {
        let mut out = Vec::with_capacity(self.extras.len());
        self.laws.scales(a, theta_star, &mut out);
        out
    }

    /// The voltage at the actuator's port: U through the input path's stages.
    pub fn port(&self, xi: &[f64], u: f64) -> Port {
        let mut port = Port {
            u_eff: u,
            slope: 1.0,
            column: None,
        };
        self.laws.port(xi, &mut port);
        port
    }

    fn at<'a>(&self, a: &'a [&'a Actuator; 3], x: [&'a [f64]; 3], u: f64, i: usize) -> At<'a> {
        At {
            a,
            x,
            u,
            i,
            port: self.port(x[i], u),
        }
    }

    /// ∂H_effects/∂θ_i of the static terms at angles θ, and its derivative in θ_i.
    fn static_torque(&self, a: &[&Actuator; 3], theta: [f64; 3], i: usize) -> Torque {
        let mut t = Torque::default();
        self.laws.static_torque(a, theta, i, &mut t);
        t
    }

    /// The static load on actuator i at angles θ, for the rest state.
    pub fn rest_load(&self, a: &[&Actuator; 3], theta: [f64; 3], i: usize) -> f64 {
        self.static_torque(a, theta, i).h_t
    }

    /// Adds the terms to actuator i's block of ẋ (`dx`, whose first five entries hold the
    /// actuator's own equations evaluated at the port voltage).
    pub fn add_rhs(
        &self,
        a: &[&Actuator; 3],
        x: [&[f64]; 3],
        u: f64,
        i: usize,
        dx: &mut [f64],
    ) -> Result<(), DomainError> {
        let theta = [x[0][THETA], x[1][THETA], x[2][THETA]];
        dx[P] -= self.static_torque(a, theta, i).h_t;
        self.laws.add_rhs(&self.at(a, x, u, i), dx)
    }

    /// The rows the port voltage drives: the circuit's Q1, Q2 and the families' rows.
    fn port_rows(&self, mut rows: impl FnMut(usize)) {
        rows(Q1);
        rows(Q2);
        self.laws.port_rows(&mut rows);
    }

    /// Adds the terms' entries of ∂ẋ/∂x through `add(row, col, value)`, rows and columns
    /// counted in the whole state vector; `offset[j]` is where block j starts. The actuator's
    /// own entries are already there (evaluated at the port voltage).
    pub fn add_jacobian(
        &self,
        a: &[&Actuator; 3],
        x: [&[f64]; 3],
        u: f64,
        i: usize,
        offset: [usize; 3],
        mut add: impl FnMut(usize, usize, f64),
    ) -> Result<(), DomainError> {
        let o = offset[i];
        let theta = [x[0][THETA], x[1][THETA], x[2][THETA]];
        add(o + P, o + THETA, -self.static_torque(a, theta, i).h_tt);
        let at = self.at(a, x, u, i);
        self.laws.add_jacobian(&at, offset, &mut add)?;
        // the port voltage's dependence on the state it reads
        if let Some(column) = at.port.column {
            let source = at.source();
            self.port_rows(|r| add(o + r, o + column, source));
        }
        Ok(())
    }

    /// ∂(actuator i's block of ẋ)/∂U through `add(row, value)`, rows counted inside the block:
    /// through the port where it reads the command (G0 ga(θ) times the input path's slope into
    /// the rows it drives), and the families' own entries (the first amplifier stage).
    pub fn add_input_jacobian(
        &self,
        a: &[&Actuator; 3],
        x: [&[f64]; 3],
        u: f64,
        i: usize,
        mut add: impl FnMut(usize, f64),
    ) {
        let at = self.at(a, x, u, i);
        if at.port.column.is_none() {
            let source = at.source();
            self.port_rows(|r| add(r, source));
        }
        self.laws.add_input_jacobian(&at, &mut add);
    }

    /// Energy stored in the terms \[J\].
    pub fn energy(&self, a: &[&Actuator; 3], x: [&[f64]; 3]) -> f64 {
        self.laws.energy(a, x)
    }

    /// Extra power at actuator i's port beyond the actuator's own y·u_eff \[W\].
    pub fn port_power(&self, a: &[&Actuator; 3], x: [&[f64]; 3], u: f64, i: usize) -> f64 {
        self.laws.port_power(&self.at(a, x, u, i))
    }

    /// Extra dissipation of actuator i beyond the actuator's own \[W\].
    pub fn dissipation(&self, act: &Actuator, xi: &[f64]) -> Result<f64, DomainError> {
        self.laws.dissipation(act, xi)
    }
}
