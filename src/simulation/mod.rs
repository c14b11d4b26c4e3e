//! Model + solver + input → a trajectory, or one communication step at a time. The CLI, the
//! FMU, identification and diagnosis all run the model through this one door.

pub mod input;
pub mod sensitivity;

use serde::{Deserialize, Serialize};

use crate::model::{ModelError, Platform};
use crate::solver::sensitivity::SensitivityError;
use crate::solver::{Bs23, MAX_STEPS, OdeSystem, Radau5, RhsError, SolverError, Stats, Tolerances};
pub use input::{Input, InputError, Interpolation, Piece, Tone};

/// Relative tolerance of every way of running the model unless the user picks another
/// (book/src/model.md, "Accuracy contract"; the FMU's DefaultExperiment declares the same).
pub const DEFAULT_RTOL: f64 = 1e-6;

/// The tolerance rule, written once for every way of running the model: a relative tolerance
/// is finite and within (0, 0.1), and the absolute tolerance of state i is rtol · scale_i (the
/// state's typical size), so that every state is controlled to the same relative accuracy.
/// Runs that must resolve more than the default (finite differences in the identification,
/// synthetic data) tighten rtol by a factor and pass it through here like any other.
pub fn tolerances(rtol: f64, scales: &[f64]) -> Result<Tolerances, SimError> {
    check_rtol("relative tolerance rtol", rtol)?;
    Ok(Tolerances::scaled(rtol, scales))
}

/// Checks a relative tolerance against the rule above; the message names it as `what`.
pub fn check_rtol(what: &str, rtol: f64) -> Result<(), SimError> {
    if rtol.is_finite() && rtol > 0.0 && rtol < 0.1 {
        Ok(())
    } else {
        Err(SimError::Setting(format!(
            "{what} = {rtol:e}: must be in (0, 0.1)"
        )))
    }
}

/// Relative length under which the rest of a held step is not worth a segment of its own.
const SLIVER: f64 = 1e-12;

/// First step size [s] from a fresh start: the electrical modes have a 2.7 ns time constant.
const FIRST_STEP: f64 = 1e-9;

/// The step a model must be non-stiff at for the explicit pair [s]: the FMUs' communication
/// step (the paper's 1 kHz sampling).
const NON_STIFF_STEP: f64 = 1e-3;

/// The largest h ρ (step size times the spectral radius of ∂f/∂x) at which a step counts as
/// not stiff: well inside the explicit pair's stability interval (−2.5, 0] ([`Bs23::stiffness`]),
/// so that the pair's steps are set by its accuracy, not by its stability.
const NON_STIFF_H_RHO: f64 = 1.0;

/// Why a simulation could not go on.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SimError {
    /// The initial state could not be computed or evaluated.
    #[error(transparent)]
    Model(#[from] ModelError),
    #[error("solver: {0}")]
    Solver(#[from] SolverError),
    /// A setting is out of range (named, with its value).
    #[error("{0}")]
    Setting(String),
    /// The sensitivities could not follow the solution (`sensitivity`).
    #[error(transparent)]
    Sensitivity(SensitivityError),
}

/// One smooth piece of the voltage the model sees: a piece of the command, late by `delay`
/// (the `delay` effect; 0 without it).
#[derive(Clone, Copy)]
struct Drive<'a> {
    piece: Piece<'a>,
    delay: f64,
}

impl Drive<'_> {
    fn held(u: [f64; 3]) -> Drive<'static> {
        Drive {
            piece: Piece::Constant(u),
            delay: 0.0,
        }
    }
    fn value(&self, t: f64) -> [f64; 3] {
        self.piece.value(t - self.delay)
    }
    /// The same piece of the command, `by` later (a held piece is the same at any time).
    fn later(&self, by: f64) -> Drive<'_> {
        Drive {
            piece: self.piece,
            delay: self.delay + by,
        }
    }
}

/// The platform driven by one smooth piece of input: the solver's view of the model.
struct Driven<'a> {
    model: &'a Platform,
    piece: Drive<'a>,
}

impl OdeSystem for Driven<'_> {
    fn dim(&self) -> usize {
        self.model.n_states()
    }
    fn rhs(&self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), RhsError> {
        self.model
            .rhs(x, self.piece.value(t), dx)
            .map_err(|e| RhsError(e.to_string()))
    }
    fn jacobian(&self, t: f64, x: &[f64], jac: &mut [f64]) -> Result<(), RhsError> {
        self.model
            .jacobian(x, self.piece.value(t), jac)
            .map_err(|e| RhsError(e.to_string()))
    }
    fn jacobian_blocks(&self) -> Vec<usize> {
        self.model.jacobian_blocks()
    }
}

/// The integrator of a run. A model that is not stiff at the co-simulation step starts with the
/// explicit Bogacki–Shampine pair: its Jacobian's spectral radius ρ at the start, bounded by the
/// largest row sum of |∂f/∂x|, keeps h ρ ≤ [`NON_STIFF_H_RHO`] at h = [`NON_STIFF_STEP`]. It
/// stays with it while every step's own estimate of h ρ does ([`Bs23::stiffness`]); the first
/// step that exceeds it hands the run to Radau IIA at that point for good (an effect's stiff
/// state, a larger drive). Either way every step meets the same error control.
#[derive(Clone, Debug, Serialize, Deserialize)]
enum Integrator {
    Radau(Box<Radau5>),
    Explicit(Box<Bs23>),
}

impl Integrator {
    /// The integrator for `sys` from `y` at `t`, by the rule above.
    fn choose(
        sys: &Driven<'_>,
        t: f64,
        y: &[f64],
        tol: Tolerances,
    ) -> Result<Integrator, SolverError> {
        let n = y.len();
        let mut jac = vec![0.0; n * n];
        sys.jacobian(t, y, &mut jac)
            .map_err(|e| SolverError::Rhs { t, message: e.0 })?;
        // Gershgorin: every eigenvalue lies within a row's sum of |entries| (column-major)
        let rho = (0..n)
            .map(|r| (0..n).map(|c| jac[c * n + r].abs()).sum::<f64>())
            .fold(0.0, f64::max);
        Ok(if rho * NON_STIFF_STEP <= NON_STIFF_H_RHO {
            Integrator::Explicit(Box::new(Bs23::new(n, tol)))
        } else {
            Integrator::Radau(Box::new(Radau5::new(n, tol)))
        })
    }

    fn init(&mut self, sys: &Driven<'_>, t: f64, y: &[f64], h0: f64) -> Result<(), SolverError> {
        match self {
            Integrator::Radau(r) => r.init(sys, t, y, h0),
            Integrator::Explicit(e) => e.init(sys, t, y, h0),
        }
    }

    fn restart(&mut self, sys: &Driven<'_>) -> Result<(), SolverError> {
        match self {
            Integrator::Radau(r) => r.restart(sys),
            Integrator::Explicit(e) => e.restart(sys),
        }
    }

    fn t(&self) -> f64 {
        match self {
            Integrator::Radau(r) => r.t(),
            Integrator::Explicit(e) => e.t(),
        }
    }

    fn y(&self) -> &[f64] {
        match self {
            Integrator::Radau(r) => r.y(),
            Integrator::Explicit(e) => e.y(),
        }
    }

    fn name(&self) -> &'static str {
        match self {
            Integrator::Radau(_) => "Radau IIA",
            Integrator::Explicit(_) => "Bogacki-Shampine 3(2)",
        }
    }

    fn stats(&self) -> Stats {
        match self {
            Integrator::Radau(r) => r.stats(),
            Integrator::Explicit(e) => e.stats(),
        }
    }

    fn interpolate(&self, t: f64, out: &mut [f64]) {
        match self {
            Integrator::Radau(r) => r.interpolate(t, out),
            Integrator::Explicit(e) => e.interpolate(t, out),
        }
    }

    /// One accepted step, never past `t_end`; an explicit step that met h ρ above
    /// [`NON_STIFF_H_RHO`] hands the run to Radau IIA (its first step the explicit pair's
    /// last).
    fn step(&mut self, sys: &Driven<'_>, t_end: f64) -> Result<(), SolverError> {
        match self {
            Integrator::Radau(r) => r.step(sys, t_end),
            Integrator::Explicit(e) => {
                let t_start = e.t();
                e.step(sys, t_end)?;
                if e.stiffness() > NON_STIFF_H_RHO {
                    let mut radau = Radau5::new(e.y().len(), e.tolerances().clone());
                    radau.init(sys, e.t(), e.y(), e.t() - t_start)?;
                    *self = Integrator::Radau(Box::new(radau));
                }
                Ok(())
            }
        }
    }

    /// Integrates until t = `t_end` exactly.
    fn advance(&mut self, sys: &Driven<'_>, t_end: f64) -> Result<(), SolverError> {
        let mut steps = 0;
        while let Integrator::Explicit(e) = self {
            if e.t() >= t_end {
                return Ok(());
            }
            if steps == MAX_STEPS {
                return Err(SolverError::TooManySteps {
                    t: e.t(),
                    limit: MAX_STEPS,
                });
            }
            self.step(sys, t_end)?;
            steps += 1;
        }
        match self {
            Integrator::Radau(r) => r.advance(sys, t_end),
            Integrator::Explicit(_) => unreachable!("left the loop above"),
        }
    }
}

/// What a run tells besides its samples (`Simulator::run_observed`).
trait Observer {
    /// After every accepted step, with the system that made it.
    fn stepped(&mut self, solver: &Integrator, sys: &Driven<'_>) -> Result<(), SimError>;
    /// At every output time, with the state there.
    fn sampled(&mut self, sample: &Sample, x: &[f64]);
    /// Where the voltage the model sees jumps from `before` to `after` at a breakpoint of the
    /// delayed command inside the run, at state `x`.
    fn jumped(&mut self, _x: &[f64], _before: [f64; 3], _after: [f64; 3]) -> Result<(), SimError> {
        Ok(())
    }
}

/// The outputs at one instant: heights h_i and the antenna tip \[m\].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sample {
    pub t: f64,
    pub u: [f64; 3],
    pub h: [f64; 3],
    pub tip: [f64; 3],
}

impl Sample {
    /// The outputs of `model` at state `x`, time `t` and input `u`: the heights once, and the
    /// tip from them (model.md, "Kinematics").
    pub fn of(model: &Platform, t: f64, u: [f64; 3], x: &[f64]) -> Sample {
        let y = model.outputs(x);
        Sample {
            t,
            u,
            h: [y[0], y[1], y[2]],
            tip: [y[3], y[4], y[5]],
        }
    }
}

/// The largest differences |Δh| and |Δtip| \[m\] between two runs' samples from time `from` on,
/// sample by sample (the runs sampled at the same times): how far one model is from another.
pub fn largest_difference(a: &[Sample], b: &[Sample], from: f64) -> (f64, f64) {
    let (mut dh, mut dtip): (f64, f64) = (0.0, 0.0);
    for (x, y) in a.iter().zip(b).filter(|(x, _)| x.t >= from) {
        for i in 0..3 {
            dh = dh.max((x.h[i] - y.h[i]).abs());
            dtip = dtip.max((x.tip[i] - y.tip[i]).abs());
        }
    }
    (dh, dtip)
}

/// How far back the command before a mid-run start is continued [s]: past the longest
/// transport delay a fit may give the `delay` effect.
const PRE_RUN: f64 = 0.05;
/// The held steps it is continued in [s].
const PRE_RUN_STEP: f64 = 1e-3;

/// Where a run starts (book/src/identify.md, "Records that start mid-run").
#[derive(Clone, Debug, PartialEq)]
pub enum Start {
    /// The rest state at U = 0, the command 0 before the run.
    Rest,
    /// Mid-run, on the slow manifold at the run's first command, which held before the run
    /// ([`Platform::settled_state`]): the actuators at angles `theta` \[rad\], the effects'
    /// states at `slow` (each actuator's in block order), settled with the charges where
    /// `slow` does not give them all.
    Settled { theta: [f64; 3], slow: Vec<f64> },
}

impl Start {
    /// The state it names for `model`, whose first command is `u0`.
    pub fn state(&self, model: &Platform, u0: [f64; 3]) -> Result<Vec<f64>, ModelError> {
        match self {
            Start::Rest => model.rest_state(),
            Start::Settled { theta, slow } => model.settled_state(*theta, slow, u0),
        }
    }
}

/// A running simulation of the platform: its model, the integrator and the input last applied.
#[derive(Clone, Debug)]
pub struct Simulator {
    model: Platform,
    solver: Integrator,
    /// Voltage the model sees at the current point (the command, late by the delay), to detect
    /// jumps between calls.
    u_now: [f64; 3],
    /// Commands held by [`Simulator::step_held`] (start time, value), oldest first, kept as far
    /// back as the delay reaches; before the first the command was 0 (the rest state's).
    history: Vec<(f64, [f64; 3])>,
    /// Scratch copy of the state at the start of a held step, for a rollback on failure.
    x_start: Vec<f64>,
}

/// Everything of a [`Simulator`] beyond its model: restoring it replays bit for bit.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Snapshot {
    solver: Integrator,
    u_now: [f64; 3],
    history: Vec<(f64, [f64; 3])>,
}

impl Simulator {
    /// Starts at the rest state at `t0` with relative tolerance `rtol` (atol scaled per state).
    pub fn new(model: Platform, t0: f64, rtol: f64) -> Result<Simulator, SimError> {
        let x0 = model.rest_state()?;
        Simulator::from_state(model, t0, &x0, rtol)
    }

    /// Starts at `start` at `t0`, where `input` begins: from rest (the command 0 before), or
    /// mid-run, where what a transport delay replays first is the command before `t0`: the
    /// trend of its first samples continued back over `PRE_RUN` in held steps of
    /// `PRE_RUN_STEP`, its first value before that.
    pub fn starting(
        model: Platform,
        start: &Start,
        input: &Input,
        t0: f64,
        rtol: f64,
    ) -> Result<Simulator, SimError> {
        let u0 = input.value(t0);
        let x0 = start.state(&model, u0)?;
        let mut sim = Simulator::from_state(model, t0, &x0, rtol)?;
        if let Start::Settled { .. } = start {
            let slope = input.value(t0 + PRE_RUN_STEP);
            let steps = (PRE_RUN / PRE_RUN_STEP) as usize;
            sim.history = std::iter::once((f64::NEG_INFINITY, u0))
                .chain((1..=steps).rev().map(|k| {
                    let back = k as f64 * PRE_RUN_STEP;
                    (
                        t0 - back,
                        [0, 1, 2].map(|i| u0[i] - (slope[i] - u0[i]) * k as f64),
                    )
                }))
                .collect();
        }
        Ok(sim)
    }

    /// Starts at state `x0` at `t0`.
    pub fn from_state(
        model: Platform,
        t0: f64,
        x0: &[f64],
        rtol: f64,
    ) -> Result<Simulator, SimError> {
        let tol = tolerances(rtol, &model.state_scales())?;
        if !t0.is_finite() {
            return Err(SimError::Setting(format!(
                "start time t0 = {t0}: must be finite"
            )));
        }
        let sys = Driven {
            model: &model,
            piece: Drive::held([0.0; 3]),
        };
        let mut solver = Integrator::choose(&sys, t0, x0, tol)?;
        solver.init(&sys, t0, x0, FIRST_STEP)?;
        Ok(Simulator {
            x_start: x0.to_vec(),
            model,
            solver,
            u_now: [0.0; 3],
            history: Vec::new(),
        })
    }

    /// The integrator's whole state and the input last applied.
    pub fn snapshot(&self) -> Snapshot {
        Snapshot {
            solver: self.solver.clone(),
            u_now: self.u_now,
            history: self.history.clone(),
        }
    }

    /// A simulator of `model` continuing exactly from `snapshot`.
    pub fn from_snapshot(model: Platform, snapshot: Snapshot) -> Result<Simulator, SimError> {
        if snapshot.solver.y().len() != model.n_states() {
            return Err(SimError::Setting(format!(
                "snapshot has {} states, the model {}",
                snapshot.solver.y().len(),
                model.n_states()
            )));
        }
        Ok(Simulator {
            x_start: snapshot.solver.y().to_vec(),
            model,
            solver: snapshot.solver,
            u_now: snapshot.u_now,
            history: snapshot.history,
        })
    }

    pub fn model(&self) -> &Platform {
        &self.model
    }

    pub fn t(&self) -> f64 {
        self.solver.t()
    }

    pub fn state(&self) -> &[f64] {
        self.solver.y()
    }

    /// The integrator's work since it started (the explicit pair's is left behind when it
    /// hands the run to Radau IIA).
    pub fn stats(&self) -> Stats {
        self.solver.stats()
    }

    /// The integrator that steps the run now: "Radau IIA" or "Bogacki-Shampine 3(2)"
    /// (`Integrator`).
    pub fn method(&self) -> &'static str {
        self.solver.name()
    }

    fn delay(&self) -> f64 {
        self.model.params().effects.delay.tau_d
    }

    /// The held command in effect at time `s` and the time it is replaced (or +∞).
    fn held_at(&self, s: f64) -> ([f64; 3], f64) {
        let k = self.history.partition_point(|&(tk, _)| tk <= s);
        let next = self.history.get(k).map_or(f64::INFINITY, |&(tk, _)| tk);
        (
            if k == 0 {
                [0.0; 3]
            } else {
                self.history[k - 1].1
            },
            next,
        )
    }

    /// The outputs at the current point.
    pub fn sample(&self) -> Sample {
        Sample::of(&self.model, self.t(), self.u_now, self.solver.y())
    }

    /// Makes `piece` the input from now on; restarts the integrator where the input jumps.
    fn apply(&mut self, piece: Drive<'_>) -> Result<(), SimError> {
        let u = piece.value(self.t());
        if u != self.u_now {
            for (i, v) in u.iter().enumerate() {
                if !v.is_finite() {
                    return Err(SimError::Setting(format!(
                        "input U{} = {v} at t = {}: must be finite",
                        i + 1,
                        self.t()
                    )));
                }
            }
            self.u_now = u;
            self.solver.restart(&Driven {
                model: &self.model,
                piece,
            })?;
        }
        Ok(())
    }

    /// Integrates to `t_end` with the input held at `u` (one co-simulation step). On failure
    /// the simulator is back at the start of the step (integrator history restarted).
    pub fn step_held(&mut self, u: [f64; 3], t_end: f64) -> Result<(), SimError> {
        let (t_start, u_start, kept) = (self.t(), self.u_now, self.history.clone());
        self.x_start.copy_from_slice(self.solver.y());
        let result = self.held_segments(u, t_end);
        if result.is_err() {
            let sys = Driven {
                model: &self.model,
                piece: Drive::held(u_start),
            };
            // the state at t_start was evaluable before, so this cannot fail
            self.solver.init(&sys, t_start, &self.x_start, FIRST_STEP)?;
            self.u_now = u_start;
            self.history = kept;
        }
        result
    }

    /// Records `u` as the command from now on and integrates to `t_end` through the pieces in
    /// which the delayed command is constant.
    fn held_segments(&mut self, u: [f64; 3], t_end: f64) -> Result<(), SimError> {
        let delay = self.delay();
        if delay == 0.0 {
            return self.advance_held(u, t_end);
        }
        let t = self.t();
        self.history.retain(|&(tk, _)| tk < t);
        if self.history.last().is_none_or(|&(_, last)| last != u) {
            self.history.push((t, u));
        }
        // a command arriving within rounding of a segment's ends counts as arrived there: a
        // sliver of 1e-17 s is no step an integrator can take
        let tol = SLIVER * t_end.abs().max(1.0);
        while self.t() < t_end {
            let now = self.t();
            let (mut c, mut next) = self.held_at(now - delay);
            while next + delay <= now + tol {
                (c, next) = self.held_at(next);
            }
            let arrival = next + delay;
            self.advance_held(
                c,
                if arrival >= t_end - tol {
                    t_end
                } else {
                    arrival
                },
            )?;
        }
        // forget what the delay can no longer reach (keep the command in effect there)
        let reach = self.history.partition_point(|&(tk, _)| tk <= t_end - delay);
        self.history.drain(..reach.saturating_sub(1));
        Ok(())
    }

    fn advance_held(&mut self, u: [f64; 3], t_end: f64) -> Result<(), SimError> {
        let piece = Drive::held(u);
        self.apply(piece)?;
        self.solver.advance(
            &Driven {
                model: &self.model,
                piece,
            },
            t_end,
        )?;
        Ok(())
    }

    /// The piece of the delayed drive that starts at `t` of a run of `input` begun at
    /// `t_run`, and where it ends: before the run, the held history (0 at rest).
    fn drive_at<'i>(&self, input: &'i Input, t_run: f64, t: f64) -> (Drive<'i>, f64) {
        let delay = self.delay();
        // a piece whose delayed end rounds to t is over: move on to the next one
        let mut s = t - delay;
        loop {
            if delay > 0.0 && s < t_run {
                let (c, next) = self.held_at(s);
                let end = next.min(t_run);
                if end + delay > t {
                    return (Drive::held(c), end + delay);
                }
                s = end;
            } else {
                let (piece, end) = input.piece_at(s);
                if end + delay > t {
                    return (Drive { piece, delay }, end + delay);
                }
                s = end;
            }
        }
    }

    /// Integrates `input` to `t_end`, calling `on_sample` at t0 and at every multiple of `dt`
    /// after it up to `t_end`.
    pub fn run(
        &mut self,
        input: &Input,
        t_end: f64,
        dt: f64,
        on_sample: impl FnMut(&Sample),
    ) -> Result<(), SimError> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(SimError::Setting(format!(
                "output step dt = {dt}: must be > 0"
            )));
        }
        let t0 = self.t();
        let last = ((t_end - t0) / dt * (1.0 + 1e-12)).floor().max(0.0) as u64;
        let times: Vec<f64> = (0..=last)
            .map(|k| (t0 + k as f64 * dt).min(t_end))
            .collect();
        self.run_at(input, &times, on_sample)
    }

    /// Integrates `input` through the increasing `times` (none before the current time),
    /// calling `on_sample` at each: outputs come from the integrator's dense output inside
    /// smooth pieces; the integrator stops exactly at every breakpoint of the input and at the
    /// last time. At most [`MAX_STEPS`] steps lie between two output times or breakpoints.
    pub fn run_at(
        &mut self,
        input: &Input,
        times: &[f64],
        on_sample: impl FnMut(&Sample),
    ) -> Result<(), SimError> {
        /// Samples only.
        struct Samples<F>(F);
        impl<F: FnMut(&Sample)> Observer for Samples<F> {
            fn stepped(&mut self, _: &Integrator, _: &Driven<'_>) -> Result<(), SimError> {
                Ok(())
            }
            fn sampled(&mut self, sample: &Sample, _: &[f64]) {
                (self.0)(sample)
            }
        }
        self.run_observed(input, times, &mut Samples(on_sample))
    }

    /// [`Simulator::run_at`], telling `observer` of every accepted step and of the state at
    /// every output time.
    fn run_observed(
        &mut self,
        input: &Input,
        times: &[f64],
        observer: &mut impl Observer,
    ) -> Result<(), SimError> {
        let Some(&t_end) = times.last() else {
            return Ok(());
        };
        if let Some(k) = (0..times.len()).find(|&k| {
            !times[k].is_finite() || times[k] < self.t() || (k > 0 && times[k] < times[k - 1])
        }) {
            return Err(SimError::Setting(format!(
                "output time {} (number {k}) is not increasing from t = {}",
                times[k],
                self.t()
            )));
        }
        let mut x = vec![0.0; self.model.n_states()];
        let mut k = 0;
        let t_run = self.t();
        let mut last: Option<Drive<'_>> = None;
        loop {
            let (piece, piece_end) = self.drive_at(input, t_run, self.t());
            self.apply(piece)?;
            // the first piece takes over from whatever came before the run, not at a breakpoint
            if let Some(last) = last {
                let (before, after) = (last.value(self.t()), self.u_now);
                if before != after {
                    observer.jumped(self.solver.y(), before, after)?;
                }
            }
            last = Some(piece);
            let seg_end = if t_end - piece_end <= SLIVER * t_end.abs().max(1.0) {
                t_end
            } else {
                piece_end
            };
            let sys = Driven {
                model: &self.model,
                piece,
            };
            // steps since the last output time or breakpoint: a run whose steps shrink until it
            // crawls (accepted steps of 1.5e-16 s near t = 0 were met inside a fit, where Radau's
            // vanishing-step guard, relative to |t|, cannot see them) stops at `MAX_STEPS`, a
            // failed trial to a fit, instead of running on
            let mut steps = 0;
            loop {
                while k < times.len() && times[k] <= self.t() {
                    self.solver.interpolate(times[k], &mut x);
                    let sample = Sample::of(&self.model, times[k], input.value(times[k]), &x);
                    observer.sampled(&sample, &x);
                    k += 1;
                    steps = 0;
                }
                if self.t() >= seg_end {
                    break;
                }
                if steps == MAX_STEPS {
                    return Err(SolverError::TooManySteps {
                        t: self.t(),
                        limit: MAX_STEPS,
                    }
                    .into());
                }
                self.solver.step(&sys, seg_end)?;
                steps += 1;
                observer.stepped(&self.solver, &sys)?;
            }
            if k == times.len() {
                return Ok(());
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{Params, Reduction};

    fn slow(params: Params) -> Platform {
        Platform::reduced(params, Reduction::Slow).unwrap()
    }

    /// The slow model starts with the explicit pair, the stiff models with Radau IIA, and so
    /// does the slow model with an effect that adds a fast state (an amplifier lag of 10 µs).
    #[test]
    fn the_integrator_follows_the_models_stiffness() {
        let explicit = "Bogacki-Shampine 3(2)";
        for r in Reduction::ALL {
            let model = Platform::reduced(Params::default(), r).unwrap();
            let sim = Simulator::new(model, 0.0, DEFAULT_RTOL).unwrap();
            assert_eq!(
                sim.method() == explicit,
                r == Reduction::Slow,
                "{}",
                r.name()
            );
        }
        let mut lagged = Params::default();
        lagged.set("tau_a", 1e-5).unwrap();
        let sim = Simulator::new(slow(lagged), 0.0, DEFAULT_RTOL).unwrap();
        assert_eq!(sim.method(), "Radau IIA");
        let mut slow_lag = Params::default();
        slow_lag.set("tau_a", 0.1).unwrap();
        let sim = Simulator::new(slow(slow_lag), 0.0, DEFAULT_RTOL).unwrap();
        assert_eq!(sim.method(), explicit);
    }

    /// The step budget counts from the last output time: 500 s of the paper's sine without an
    /// output in between takes more than [`MAX_STEPS`] explicit steps (about 230 a second) and
    /// stops with the error where the budget ran out, its earlier samples delivered; with an
    /// output every second the same run ends.
    #[test]
    fn a_run_stops_where_its_steps_between_two_outputs_run_out() {
        let input = Input::sine(60.0, 3.0 * std::f64::consts::PI);
        let mut sim = Simulator::new(slow(Params::default()), 0.0, DEFAULT_RTOL).unwrap();
        let mut samples = 0;
        let e = sim
            .run_at(&input, &[0.0, 500.0], |_| samples += 1)
            .unwrap_err();
        let SimError::Solver(SolverError::TooManySteps { t, limit }) = e else {
            panic!("{e}")
        };
        assert_eq!((samples, limit), (1, MAX_STEPS));
        assert!(t > 100.0 && t < 500.0 && t == sim.t(), "t = {t}");
        let mut sim = Simulator::new(slow(Params::default()), 0.0, DEFAULT_RTOL).unwrap();
        let mut samples = 0;
        sim.run(&input, 500.0, 1.0, |_| samples += 1).unwrap();
        assert_eq!(samples, 501);
        assert!(sim.stats().accepted > MAX_STEPS);
    }

    /// A step held for 5 s: the explicit pair's steps grow as the motion settles until one
    /// meets h ρ > 1, and Radau IIA takes over there; the run ends where one at a hundredfold
    /// tighter tolerance does, within the tolerance.
    #[test]
    fn a_settling_run_hands_over_to_radau_and_stays_accurate() {
        let input = Input::constant([60.0, 40.0, 20.0]);
        let run = |rtol: f64| {
            let mut sim = Simulator::new(slow(Params::default()), 0.0, rtol).unwrap();
            let mut last = None;
            sim.run(&input, 5.0, 0.5, |s| last = Some(*s)).unwrap();
            (sim.method(), last.unwrap())
        };
        let (method, loose) = run(DEFAULT_RTOL);
        let (_, tight) = run(1e-8);
        assert_eq!(method, "Radau IIA");
        for i in 0..3 {
            let dh = (loose.h[i] - tight.h[i]).abs();
            assert!(
                dh <= 1e-6 * tight.h[i].abs() + 1e-12,
                "h{}: {dh:e} m",
                i + 1
            );
        }
    }

    /// A snapshot taken while the explicit pair steps replays bit for bit, through serde.
    #[test]
    fn an_explicit_run_replays_from_its_snapshot() {
        let input = Input::sine(60.0, 3.0 * std::f64::consts::PI);
        let mut sim = Simulator::new(slow(Params::default()), 0.0, DEFAULT_RTOL).unwrap();
        let held = |sim: &mut Simulator, from: usize, to: usize| {
            for k in from..to {
                sim.step_held(input.value(k as f64 * 1e-3), (k + 1) as f64 * 1e-3)
                    .unwrap();
            }
        };
        held(&mut sim, 0, 100);
        let bytes = postcard::to_stdvec(&sim.snapshot()).unwrap();
        let snapshot: Snapshot = postcard::from_bytes(&bytes).unwrap();
        let mut copy = Simulator::from_snapshot(slow(Params::default()), snapshot).unwrap();
        held(&mut sim, 100, 200);
        held(&mut copy, 100, 200);
        assert_eq!(sim.method(), "Bogacki-Shampine 3(2)");
        let bits = |s: &Simulator| s.state().iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&sim), bits(&copy));
        assert_eq!(sim.stats(), copy.stats());
    }

    /// An effect's state that acts on θ through a torque is kept to the accuracy that torque
    /// needs (book/src/solver.md, "States weighted by their effect on θ"): five plays on a 6 s,
    /// 60 V sine at 1e-6 take at most twice the paper's model's steps, whatever their weights
    /// (at θ*'s own scale they took three times as many, a weight of 1e-6 included), and the
    /// heights stay within 2.5e-4 of their range of a run at 1e-10.
    #[test]
    fn a_plays_state_does_not_set_the_step() {
        let times: Vec<f64> = (0..=6000).map(|k| k as f64 * 1e-3).collect();
        let input = Input::sine(60.0, 3.0 * std::f64::consts::PI);
        let run = |p: &Params, rtol: f64| {
            let mut sim = Simulator::new(Platform::new(p.clone()).unwrap(), 0.0, rtol).unwrap();
            let mut h = Vec::new();
            sim.run_at(&input, &times, |s| h.push(s.h)).unwrap();
            (h, sim.stats().accepted)
        };
        let (_, paper) = run(&Params::default(), 1e-6);
        let kb = Params::default().act[0].kb;
        for total in [1e-6, 0.02 * kb, 0.4 * kb] {
            let mut p = Params::default();
            p.effects.hysteresis.grid = [total / 5.0; 5];
            let ((h, steps), (reference, _)) = (run(&p, 1e-6), run(&p, 1e-10));
            assert!(
                steps <= 2 * paper,
                "plays of {total:e} in all: {steps} steps, the paper's model {paper}"
            );
            let range = reference.iter().fold(0.0f64, |m, r| m.max(r[0].abs()));
            for (a, b) in h.iter().zip(&reference) {
                for i in 0..3 {
                    assert!(
                        (a[i] - b[i]).abs() <= 2.5e-4 * range,
                        "plays of {total:e}: h{} off by {:e} of {range:e}",
                        i + 1,
                        (a[i] - b[i]).abs()
                    );
                }
            }
        }
    }
}
