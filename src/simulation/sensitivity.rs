//! A run of the model from rest with the sensitivities of its outputs to chosen parameter
//! directions, integrated alongside the state (`crate::solver::sensitivity`): what a
//! finite-difference Jacobian of the simulated outputs gets from one simulation per parameter,
//! from one simulation.
//!
//! A direction is the model with one coordinate θ_j moved by a small `step`; ∂f/∂θ_j, the rest
//! state's and the outputs' own dependence on θ_j are the differences of the two models divided
//! by the step (cheap: no simulation), and the dynamics carry them through the variational
//! equation. The delay `tau_d` acts on the input's timing, not on f: a direction that moves it
//! sees the piece of the command it is in that much later, and where the delayed command steps,
//! the step's moving in time makes s jump by (f before − f after) · ∂τ_d/∂θ_j. At τ_d = 0 that
//! derivative is one-sided (the first command's arrival separates from the start), and such a
//! direction is refused.

use super::{Driven, Input, Integrator, Observer, Sample, SimError, Simulator, Start};
use crate::model::{Params, Platform};
use crate::solver::sensitivity::{ParametricSystem, Sensitivities};
use crate::solver::{OdeSystem, RhsError};

/// One parameter direction: the parameters with coordinate θ_j moved by `step`.
#[derive(Clone, Debug)]
pub struct Direction {
    pub params: Params,
    pub step: f64,
}

/// The samples of a run and the sensitivities of its outputs.
#[derive(Clone, Debug)]
pub struct Sensitive {
    pub samples: Vec<Sample>,
    directions: usize,
    /// ∂(h1, h2, h3, tip_x, tip_y, tip_z)/∂θ_j at sample k, at k · directions + j.
    outputs: Vec<[f64; 6]>,
}

impl Sensitive {
    /// ∂(h1, h2, h3, tip_x, tip_y, tip_z)/∂θ_j at sample k.
    pub fn output(&self, k: usize, j: usize) -> [f64; 6] {
        self.outputs[k * self.directions + j]
    }
}

/// The platform driven by one piece of input, with ∂f/∂θ from the directions' models.
struct Parametric<'a, 'd> {
    driven: &'a Driven<'d>,
    models: &'a [Platform],
    steps: &'a [f64],
    /// Per direction, the one actuator it moves (see [`own_actuator`]).
    own: &'a [Option<usize>],
    /// Per direction, how much later it has the command arrive [s] (its τ_d − the run's).
    later: &'a [f64],
}

impl OdeSystem for Parametric<'_, '_> {
    fn dim(&self) -> usize {
        self.driven.dim()
    }
    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), RhsError> {
        self.driven.rhs(t, y, dy)
    }
    fn jacobian(&self, t: f64, y: &[f64], jac: &mut [f64]) -> Result<(), RhsError> {
        self.driven.jacobian(t, y, jac)
    }
    fn jacobian_blocks(&self) -> Vec<usize> {
        self.driven.jacobian_blocks()
    }
}

impl ParametricSystem for Parametric<'_, '_> {
    fn n_params(&self) -> usize {
        self.models.len()
    }
    fn rhs_params(&self, t: f64, y: &[f64], fp: &mut [f64]) -> Result<(), RhsError> {
        let (n, nb) = (y.len(), y.len() / 3);
        let u = self.driven.piece.value(t);
        let mut base = vec![0.0; n];
        self.driven.rhs(t, y, &mut base)?;
        let columns = fp.chunks_mut(n);
        for ((((model, step), own), &later), column) in self
            .models
            .iter()
            .zip(self.steps)
            .zip(self.own)
            .zip(self.later)
            .zip(columns)
        {
            let fail = |e: crate::model::ModelError| RhsError(e.to_string());
            let u = if later == 0.0 {
                u
            } else {
                self.driven.piece.later(later).value(t)
            };
            // an actuator's own parameter: its block alone, the others' are exactly zero
            let rows = match *own {
                Some(i) => {
                    column.fill(0.0);
                    let rows = nb * i..nb * (i + 1);
                    model
                        .actuator_rhs(i, y, u, &mut column[rows.clone()])
                        .map_err(fail)?;
                    rows
                }
                None => {
                    model.rhs(y, u, column).map_err(fail)?;
                    0..n
                }
            };
            for (c, b) in column[rows.clone()].iter_mut().zip(&base[rows]) {
                *c = (*c - b) / step;
            }
        }
        Ok(())
    }
}

/// Follows the run's steps with the sensitivities and records the outputs' at the samples.
struct Follower<'a> {
    base: &'a Platform,
    models: &'a [Platform],
    steps: &'a [f64],
    /// Per direction: the outputs' map is the base model's (no ∂g/∂θ).
    same_map: Vec<bool>,
    /// Per direction, the one actuator it moves (see [`own_actuator`]).
    own: Vec<Option<usize>>,
    /// Per direction, how much later it has the command arrive [s] (its τ_d − the run's).
    later: Vec<f64>,
    sens: Sensitivities,
    s: Vec<f64>,
    /// ∂g/∂x as its entries (output, state, value): a dozen of 6 × n, the heights' angles
    dg: Vec<(usize, usize, f64)>,
    /// The states `dg` reads, whose sensitivities alone a sample interpolates.
    read: Vec<usize>,
    out: Sensitive,
}

impl Observer for Follower<'_> {
    fn stepped(&mut self, solver: &Integrator, sys: &Driven<'_>) -> Result<(), SimError> {
        // the full model, whose electrical modes keep it with Radau IIA from the start
        let Integrator::Radau(solver) = solver else {
            return Err(SimError::Setting(
                "sensitivities follow Radau IIA's stages, and this run is explicit".into(),
            ));
        };
        let sys = Parametric {
            driven: sys,
            models: self.models,
            steps: self.steps,
            own: &self.own,
            later: &self.later,
        };
        self.sens
            .follow(solver, &sys)
            .map_err(SimError::Sensitivity)
    }

    fn sampled(&mut self, sample: &Sample, x: &[f64]) {
        let n = x.len();
        // ∂y/∂θ = ∂g/∂x s + ∂g/∂θ (the outputs' own dependence, for a geometric parameter)
        self.dg.clear();
        self.base
            .output_jacobian_entries(x, |o, c, v| self.dg.push((o, c, v)));
        self.read.clear();
        self.read.extend(self.dg.iter().map(|&(_, c, _)| c));
        self.read.sort_unstable();
        self.read.dedup();
        self.sens.interpolate(sample.t, &self.read, &mut self.s);
        // the outputs themselves only where a direction moves their map
        let y = (!self.same_map.iter().all(|&same| same)).then(|| self.base.outputs(x));
        for (j, (model, step)) in self.models.iter().zip(self.steps).enumerate() {
            let s = &self.s[j * n..(j + 1) * n];
            let mut d = [0.0; 6];
            for &(o, c, v) in &self.dg {
                d[o] += v * s[c];
            }
            if let (false, Some(y)) = (self.same_map[j], &y) {
                let yj = model.outputs(x);
                for o in 0..6 {
                    d[o] += (yj[o] - y[o]) / step;
                }
            }
            self.out.outputs.push(d);
        }
        self.out.samples.push(*sample);
    }

    /// A step of the delayed command moves with τ_d: s jumps by (f before − f after) ∂τ_d/∂θ_j.
    fn jumped(&mut self, x: &[f64], before: [f64; 3], after: [f64; 3]) -> Result<(), SimError> {
        if self.later.iter().all(|&l| l == 0.0) {
            return Ok(());
        }
        let n = x.len();
        let (mut f_before, mut f_after) = (vec![0.0; n], vec![0.0; n]);
        self.base.rhs(x, before, &mut f_before)?;
        self.base.rhs(x, after, &mut f_after)?;
        let ds: Vec<f64> = self
            .later
            .iter()
            .zip(self.steps)
            .flat_map(|(later, step)| {
                let rate = later / step;
                f_before
                    .iter()
                    .zip(&f_after)
                    .map(move |(b, a)| rate * (b - a))
            })
            .collect();
        self.sens.jump(&ds);
        Ok(())
    }
}

/// Simulates `input` from `start` of `params` at `times[0]` (relative tolerance `rtol`), sampled
/// at `times`, with the outputs' sensitivities to each of `directions`.
pub fn simulate_sensitive(
    params: &Params,
    directions: &[Direction],
    start: &Start,
    input: &Input,
    times: &[f64],
    rtol: f64,
) -> Result<Sensitive, SimError> {
    let platform =
        |p: &Params| Platform::new(p.clone()).map_err(|e| SimError::Setting(e.to_string()));
    let base = platform(params)?;
    let models = directions
        .iter()
        .map(|d| platform(&d.params))
        .collect::<Result<Vec<_>, _>>()?;
    let steps: Vec<f64> = directions.iter().map(|d| d.step).collect();
    let n = base.n_states();
    for (j, (m, d)) in models.iter().zip(directions).enumerate() {
        if m.n_states() != n {
            return Err(SimError::Setting(format!(
                "sensitivity direction {j} changes the number of states ({} to {n}): an effect switched on or off has no derivative",
                m.n_states()
            )));
        }
        if params.effects.delay.tau_d == 0.0
            && d.params.effects.delay.tau_d != params.effects.delay.tau_d
        {
            return Err(SimError::Setting(format!(
                "sensitivity direction {j} moves the delay tau_d from 0, where its derivative is one-sided"
            )));
        }
        if !(d.step.is_finite() && d.step != 0.0) {
            return Err(SimError::Setting(format!(
                "sensitivity direction {j}: step {} must be finite and non-zero",
                d.step
            )));
        }
    }
    let t0 = times.first().copied().unwrap_or(0.0);
    let u0 = input.value(t0);
    let x0 = start.state(&base, u0)?;
    let mut s0 = Vec::with_capacity(n * models.len());
    for (m, step) in models.iter().zip(&steps) {
        let x0_j = start.state(m, u0)?;
        s0.extend(x0_j.iter().zip(&x0).map(|(a, b)| (a - b) / step));
    }
    let mut follower = Follower {
        base: &base,
        models: &models,
        steps: &steps,
        same_map: models.iter().map(|m| base.same_output_map(m)).collect(),
        own: directions
            .iter()
            .map(|d| own_actuator(&base, &d.params))
            .collect(),
        later: directions
            .iter()
            .map(|d| d.params.effects.delay.tau_d - params.effects.delay.tau_d)
            .collect(),
        sens: Sensitivities::new(n, models.len(), t0, &s0),
        s: vec![0.0; n * models.len()],
        dg: Vec::new(),
        read: Vec::new(),
        out: Sensitive {
            samples: Vec::with_capacity(times.len()),
            directions: models.len(),
            outputs: Vec::with_capacity(times.len() * models.len()),
        },
    };
    let mut sim = Simulator::starting(base.clone(), start, input, t0, rtol)?;
    sim.run_observed(input, times, &mut follower)?;
    Ok(follower.out)
}

/// The one actuator whose own parameters alone `moved` changes from `base`'s, where `base`'s
/// Jacobian's blocks are the actuators' (none links them): f changes only on that block.
fn own_actuator(base: &Platform, moved: &Params) -> Option<usize> {
    if base.jacobian_blocks().len() != 3 {
        return None;
    }
    let (params, mut rest, mut own) = (base.params(), moved.clone(), None);
    for def in crate::model::params::parameters() {
        let (Some(i), v) = (def.actuator, (def.get)(params)) else {
            continue;
        };
        if (def.get)(&rest) != v {
            if own.is_some_and(|k| k != i) {
                return None;
            }
            own = Some(i);
            (def.set)(&mut rest, v);
        }
    }
    // nothing else moved: not a common parameter, nor a state of anything outside the table
    (rest == *params).then_some(own).flatten()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simulation::Interpolation;

    /// The outputs' sensitivities to Kb_1 and gamma1_2 (in log coordinates) against central
    /// differences of simulations, on a 60 V sine at 3π rad/s: the paper's model, and with the
    /// actuators coupled (one block of J) and an effect's parameter among the directions.
    #[test]
    fn output_sensitivities_match_central_differences() {
        let input = sampled(Interpolation::Spline, |t| {
            30.0 * (1.0 - (3.0 * std::f64::consts::PI * t).cos())
        });
        check_against_differences(&Params::default(), &input, &["Kb_1", "gamma1_2"]);
        let mut coupled = Params::default();
        coupled.set("k_c", 1000.0).unwrap();
        check_against_differences(&coupled, &input, &["Kb_1", "k_c"]);
    }

    /// The sensitivity to a transport delay of 10.3 ms (off the samples' grid) against central
    /// differences, on a measured command that is at 10 V before the run (so its arrival is a
    /// step) and steps by 25 V at 0.3 s between two pieces of a sine: the two steps arrive
    /// later as τ_d grows, and s jumps there.
    #[test]
    fn the_delays_sensitivity_matches_central_differences() {
        let mut delayed = Params::default();
        delayed.set("tau_d", 0.0103).unwrap();
        let input = sampled(Interpolation::Measured, |t| {
            10.0 + 20.0 * (1.0 - (3.0 * std::f64::consts::PI * t).cos())
                + if t >= 0.3 { 25.0 } else { 0.0 }
        });
        check_against_differences(&delayed, &input, &["tau_d", "Kb_1"]);
    }

    /// `volts(t)` on the three actuators (scaled 1, 0.8, 0.6) sampled every ms for 1.5 s.
    fn sampled(interpolation: Interpolation, volts: impl Fn(f64) -> f64) -> Input {
        let times: Vec<f64> = (0..=1500).map(|k| k as f64 * 1e-3).collect();
        let u = times
            .iter()
            .map(|&t| [1.0, 0.8, 0.6].map(|s| s * volts(t)))
            .collect();
        Input::sampled(times, u, interpolation).unwrap()
    }

    fn check_against_differences(params: &Params, input: &Input, names: &[&str]) {
        let times: Vec<f64> = (0..=1500).map(|k| k as f64 * 1e-3).collect();
        let moved = |name: &str, dln: f64| {
            let mut p = params.clone();
            p.set(name, params.get(name).unwrap() * dln.exp()).unwrap();
            p
        };
        let directions: Vec<Direction> = names
            .iter()
            .map(|n| Direction {
                params: moved(n, 1e-6),
                step: 1e-6,
            })
            .collect();
        let got =
            simulate_sensitive(params, &directions, &Start::Rest, input, &times, 1e-8).unwrap();
        let run = |p: &Params| {
            let mut sim = Simulator::new(Platform::new(p.clone()).unwrap(), 0.0, 1e-12).unwrap();
            let mut out = Vec::new();
            sim.run_at(input, &times, |s| out.push(s.h)).unwrap();
            out
        };
        let h = 1e-3;
        for (j, name) in names.iter().enumerate() {
            let (plus, minus) = (run(&moved(name, h)), run(&moved(name, -h)));
            for i in 0..3 {
                let fd: Vec<f64> = (0..times.len())
                    .map(|k| (plus[k][i] - minus[k][i]) / (2.0 * h))
                    .collect();
                let size = fd.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                // within 1e-4 of the size, plus the reference's noise where h_i does not
                // depend on the parameter (another actuator's)
                for k in 0..times.len() {
                    let s = got.output(k, j)[i];
                    assert!(
                        (s - fd[k]).abs() <= 1e-4 * size + 1e-10,
                        "t = {}: dh{}/dln {name} = {s:e}, central differences {:e} (size {size:e})",
                        times[k],
                        i + 1,
                        fd[k]
                    );
                }
            }
        }
    }

    /// A direction that moves one actuator's own parameters names that actuator; a common
    /// parameter, two actuators' or a model whose effects link the actuators name none.
    #[test]
    fn a_direction_names_the_one_actuator_it_moves() {
        let p = Params::default();
        let base = Platform::new(p.clone()).unwrap();
        let moved = |names: &[&str], from: &Params| {
            let mut q = from.clone();
            for n in names {
                q.set(n, from.get(n).unwrap() * 1.001).unwrap();
            }
            q
        };
        assert_eq!(own_actuator(&base, &moved(&["Kb_1"], &p)), Some(0));
        assert_eq!(
            own_actuator(&base, &moved(&["gamma1_2", "b_2"], &p)),
            Some(1)
        );
        assert_eq!(own_actuator(&base, &moved(&["Kb_1", "b_3"], &p)), None);
        assert_eq!(own_actuator(&base, &moved(&["m"], &p)), None);
        let mut coupled = p.clone();
        coupled.set("k_c", 1000.0).unwrap();
        let linked = Platform::new(coupled.clone()).unwrap();
        assert_eq!(own_actuator(&linked, &moved(&["Kb_1"], &coupled)), None);
    }
}
