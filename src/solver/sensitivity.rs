//! Forward sensitivities s_j = ∂y/∂θ_j of a Radau IIA solution, integrated alongside it: the
//! variational equation ṡ = J(t, y) s + ∂f/∂θ (t, y) is solved on every step the integrator
//! accepted, by the same collocation method with the step's own size and stage values (the
//! "staggered direct" method of Caracotsios & Stewart, 1985; Hairer & Wanner IV.8 for the
//! method). The stage equations of s are linear: with J_k and ∂f/∂θ at the stage values Y_k,
//! the stage increments σ_k = S_k − s solve
//!
//! ```text
//! σ_k − h Σ_l a_kl J_l σ_l = h Σ_l a_kl (J_l s + ∂f/∂θ (Y_l)),     k = 1, 2, 3
//! ```
//!
//! one 3n × 3n system per step (per diagonal block of J: 3 × 15 for the decoupled platform),
//! factored once and solved for all parameters, exactly rather than by the state's simplified
//! Newton iteration (which, with J frozen at an older point, took about 5 iterations per
//! parameter and step). No extra simulation per parameter: a finite-difference Jacobian costs
//! one simulation per parameter.

use super::radau5::{A, C1, C1M1, C1MC2, C2, C2M1, Radau5};
use super::{OdeSystem, RhsError, lu};

/// A system ẏ = f(t, y; θ) that also gives ∂f/∂θ.
pub trait ParametricSystem: OdeSystem {
    /// Number of parameters θ.
    fn n_params(&self) -> usize;
    /// ∂f/∂θ at (t, y) into `fp`, column-major `dim × n_params`.
    fn rhs_params(&self, t: f64, y: &[f64], fp: &mut [f64]) -> Result<(), RhsError>;
}

/// Why the sensitivities could not follow a step.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SensitivityError {
    #[error("sensitivities at t = {t} s: {message}")]
    Rhs { t: f64, message: String },
    #[error("sensitivities at t = {t} s: singular stage equations (row {row})")]
    Singular { t: f64, row: usize },
}

/// The sensitivities of `m` parameters and the collocation polynomial of the last step.
#[derive(Clone, Debug)]
pub struct Sensitivities {
    n: usize,
    m: usize,
    /// ∂y/∂θ at the current point, column-major n × m.
    s: Vec<f64>,
    t: f64,
    h_old: f64,
    /// Per parameter, the dense-output coefficients as the state's (3 n each).
    cont: Vec<f64>,
    have_poly: bool,
    /// Stage Jacobians (3 of n × n) and ∂f/∂θ at the stages (3 of n × m).
    stage_jac: Vec<f64>,
    stage_fp: Vec<f64>,
    y_stage: Vec<f64>,
    /// The nonzeros (row, column, value) of one block of each stage's Jacobian, column by
    /// column, and which of the block's states they link.
    nz: [Vec<(usize, usize, f64)>; 3],
    linked: Vec<bool>,
    /// The stage equations of each block, factored (a factorization per block, so that the
    /// next step's equations of the block repeat its elimination); the order of a block's
    /// states in them, and each state's place in that order.
    lu: Vec<lu::SparseLu>,
    order: Vec<usize>,
    pos: Vec<usize>,
    /// The parameters whose σ on one block is not zero, solved together: their s there, state
    /// by state, and J_l s + ∂f/∂θ_j (Y_l) there, per state and stage (l = 0, 1, 2), side by
    /// side; their stage increments in the order of the equations, each row side by side.
    active: Vec<usize>,
    s_block: Vec<f64>,
    g: Vec<f64>,
    x: Vec<f64>,
    /// The increments σ (3 n per parameter, block by block, each block stage by stage).
    sigma: Vec<f64>,
}

impl Sensitivities {
    /// Starts at time `t0` with ∂y(t0)/∂θ = `s0` (column-major n × m).
    pub fn new(n: usize, m: usize, t0: f64, s0: &[f64]) -> Sensitivities {
        assert_eq!(
            s0.len(),
            n * m,
            "one initial sensitivity per state and parameter"
        );
        Sensitivities {
            n,
            m,
            s: s0.to_vec(),
            t: t0,
            h_old: 0.0,
            cont: vec![0.0; 3 * n * m],
            have_poly: false,
            stage_jac: vec![0.0; 3 * n * n],
            stage_fp: vec![0.0; 3 * n * m],
            y_stage: vec![0.0; n],
            nz: Default::default(),
            linked: Vec::new(),
            lu: Vec::new(),
            order: Vec::with_capacity(n),
            pos: Vec::with_capacity(n),
            active: Vec::with_capacity(m),
            s_block: Vec::with_capacity(n * m),
            g: Vec::with_capacity(3 * n * m),
            x: Vec::with_capacity(3 * n * m),
            sigma: vec![0.0; 3 * n * m],
        }
    }

    /// Advances the sensitivities over the step `solver` has just accepted (call right after
    /// each [`Radau5::step`]).
    pub fn follow<S: ParametricSystem>(
        &mut self,
        solver: &Radau5,
        sys: &S,
    ) -> Result<(), SensitivityError> {
        let st = solver.last_step();
        let (n, m, h) = (self.n, self.m, st.h);
        assert_eq!(
            st.n, n,
            "the sensitivities follow a solver of their dimension"
        );
        let t_end = st.t_old + h;
        // the stage values Y_k = y(t_old) + Z_k, and J and ∂f/∂θ there
        for (k, c) in [C1, C2, 1.0].into_iter().enumerate() {
            for i in 0..n {
                self.y_stage[i] = st.y[i] - st.z[2 * n + i] + st.z[k * n + i];
            }
            let t = st.t_old + c * h;
            let fail = |e: RhsError| SensitivityError::Rhs { t, message: e.0 };
            sys.jacobian(
                t,
                &self.y_stage,
                &mut self.stage_jac[k * n * n..(k + 1) * n * n],
            )
            .map_err(fail)?;
            sys.rhs_params(
                t,
                &self.y_stage,
                &mut self.stage_fp[k * n * m..(k + 1) * n * m],
            )
            .map_err(fail)?;
        }
        // J is block diagonal: each block's states and stages form a system of their own
        let mut o = 0;
        self.lu.resize_with(st.blocks.len(), Default::default);
        for (b, &mb) in st.blocks.iter().enumerate() {
            let dim = 3 * mb;
            self.block_entries(o, mb);
            self.order_states(mb);
            let (nz, pos, lu) = (&self.nz, &self.pos, &mut self.lu[b]);
            lu.start(dim);
            // unknown (stage l, state c) at 3 pos[c] + l; equation (stage k, state r) at
            // 3 pos[r] + k: σ_k − h Σ_l a_kl J_l σ_l
            for d in 0..dim {
                lu.set(d, d, 1.0);
            }
            for (l, entries) in nz.iter().enumerate() {
                for &(r, c, jrc) in entries {
                    for (k, a_k) in A.iter().enumerate() {
                        let v = h * a_k[l] * jrc;
                        if v != 0.0 {
                            let unit = if k == l && r == c { 1.0 } else { 0.0 };
                            lu.set(3 * pos[r] + k, 3 * pos[c] + l, unit - v);
                        }
                    }
                }
            }
            lu.factor()
                .map_err(|lu::Singular(row)| SensitivityError::Singular { t: t_end, row })?;
            self.solve_block(b, o, mb, h);
            o += mb;
        }
        // commit: s ← s + σ_3 and the collocation polynomial, as the state's
        for j in 0..m {
            let sigma = &self.sigma[j * 3 * n..(j + 1) * 3 * n];
            let cont = &mut self.cont[3 * n * j..3 * n * (j + 1)];
            let mut o = 0;
            for &mb in st.blocks {
                let b = &sigma[3 * o..3 * o + 3 * mb];
                for r in 0..mb {
                    let (z1, z2, z3) = (b[r], b[mb + r], b[2 * mb + r]);
                    let i = o + r;
                    let c1 = (z2 - z3) / C2M1;
                    let ak = (z1 - z2) / C1MC2;
                    let acont3 = (ak - z1 / C1) / C2;
                    let c2 = (ak - c1) / C1M1;
                    cont[i] = c1;
                    cont[n + i] = c2;
                    cont[2 * n + i] = c2 - acont3;
                    self.s[j * n + i] += z3;
                }
                o += mb;
            }
        }
        self.t = t_end;
        self.h_old = h;
        self.have_poly = true;
        Ok(())
    }

    /// The stage increments σ on block `b`, of `mb` states from `o`, its stage equations
    /// factored, of every parameter at once: the right-hand sides h Σ_l a_kl g_l with
    /// g_l = J_l s + ∂f/∂θ_j (Y_l), the products over J_l's nonzeros, solved in one pass. A
    /// parameter of another block (its s and ∂f/∂θ zero here) has σ = 0 here.
    fn solve_block(&mut self, b: usize, o: usize, mb: usize, h: f64) {
        let (n, m, dim) = (self.n, self.m, 3 * mb);
        self.active.clear();
        for j in 0..m {
            if self.untouched(j, o..o + mb) {
                self.sigma[j * 3 * n + 3 * o..j * 3 * n + 3 * o + dim].fill(0.0);
            } else {
                self.active.push(j);
            }
        }
        let q = self.active.len();
        if q == 0 {
            return;
        }
        let (s_block, g) = (&mut self.s_block, &mut self.g);
        s_block.resize(mb * q, 0.0);
        g.resize(3 * mb * q, 0.0);
        for (a, &j) in self.active.iter().enumerate() {
            for r in 0..mb {
                s_block[r * q + a] = self.s[j * n + o + r];
                for l in 0..3 {
                    g[(3 * r + l) * q + a] = self.stage_fp[l * n * m + j * n + o + r];
                }
            }
        }
        for (l, entries) in self.nz.iter().enumerate() {
            for &(r, c, jrc) in entries {
                let sc = &s_block[c * q..(c + 1) * q];
                if sc.iter().all(|&v| v == 0.0) {
                    continue;
                }
                let gr = &mut g[(3 * r + l) * q..(3 * r + l + 1) * q];
                for (g, &sc) in gr.iter_mut().zip(sc) {
                    *g += jrc * sc;
                }
            }
        }
        let x = &mut self.x;
        x.resize(dim * q, 0.0);
        for (r, gr) in g.chunks_exact(3 * q).enumerate() {
            let (g0, g12) = gr.split_at(q);
            let (g1, g2) = g12.split_at(q);
            for (k, a_k) in A.iter().enumerate() {
                let row = 3 * self.pos[r] + k;
                for (((xa, &g0), &g1), &g2) in
                    x[row * q..(row + 1) * q].iter_mut().zip(g0).zip(g1).zip(g2)
                {
                    *xa = h * (a_k[0] * g0 + a_k[1] * g1 + a_k[2] * g2);
                }
            }
        }
        self.lu[b].solve(x, q);
        // σ block by block, each block stage by stage
        for (a, &j) in self.active.iter().enumerate() {
            let b = &mut self.sigma[j * 3 * n + 3 * o..j * 3 * n + 3 * o + dim];
            for r in 0..mb {
                for k in 0..3 {
                    b[k * mb + r] = x[(3 * self.pos[r] + k) * q + a];
                }
            }
        }
    }

    /// The nonzeros of the block of `mb` states from `o` of each stage's Jacobian into `nz`:
    /// every product and entry of the stage equations is over them alone (a block's Jacobian
    /// is mostly zeros: an effect's states touch the actuator's few).
    fn block_entries(&mut self, o: usize, mb: usize) {
        let n = self.n;
        for (l, entries) in self.nz.iter_mut().enumerate() {
            entries.clear();
            for c in 0..mb {
                let col = &self.stage_jac[l * n * n + (o + c) * n + o..][..mb];
                entries.extend(
                    col.iter()
                        .enumerate()
                        .filter(|&(_, &v)| v != 0.0)
                        .map(|(r, &v)| (r, c, v)),
                );
            }
        }
    }

    /// The order of the block's states in its stage equations (`order`, and each state's place
    /// in it, `pos`): the states with the fewest couplings first (an effect's own, coupled only
    /// to the actuator's), whose elimination then fills in little, each state's three stages
    /// side by side.
    fn order_states(&mut self, mb: usize) {
        let linked = &mut self.linked;
        linked.clear();
        linked.resize(mb * mb, false);
        for &(r, c, _) in self.nz.iter().flatten() {
            if r != c {
                linked[c * mb + r] = true;
                linked[r * mb + c] = true;
            }
        }
        let (order, pos) = (&mut self.order, &mut self.pos);
        pos.clear();
        pos.extend(
            linked
                .chunks(mb)
                .map(|row| row.iter().filter(|&&l| l).count()),
        );
        order.clear();
        order.extend(0..mb);
        order.sort_by_key(|&c| pos[c]);
        for (q, &c) in order.iter().enumerate() {
            pos[c] = q;
        }
    }

    /// Adds `ds` (column-major n × m) to ∂y/∂θ at the current point: the jump where a
    /// discontinuity of f moves with θ (a delayed step of the input), whose size the system
    /// knows, not the method. The last step's polynomial does not end at the jumped values.
    pub fn jump(&mut self, ds: &[f64]) {
        assert_eq!(ds.len(), self.s.len(), "one jump per state and parameter");
        for (s, d) in self.s.iter_mut().zip(ds) {
            *s += d;
        }
        self.have_poly = false;
    }

    /// Do the sensitivities to parameter `j` stay zero on the states `block` over this step: are
    /// they zero there and is ∂f/∂θ_j zero there at every stage? (Each actuator's own
    /// parameters leave the others' blocks at exactly zero.)
    fn untouched(&self, j: usize, block: std::ops::Range<usize>) -> bool {
        let (n, m) = (self.n, self.m);
        let zero = |v: &[f64]| v.iter().all(|&x| x == 0.0);
        zero(&self.s[j * n + block.start..j * n + block.end])
            && (0..3).all(|l| {
                let at = l * n * m + j * n;
                zero(&self.stage_fp[at + block.start..at + block.end])
            })
    }

    /// ∂y/∂θ at `t` in the last step (dense output, as the state's), column-major n × m, of
    /// the states `states` alone (the others in `out` are left as they are: a sample's outputs
    /// read a few states).
    pub fn interpolate(&self, t: f64, states: &[usize], out: &mut [f64]) {
        let n = self.n;
        if !self.have_poly || self.h_old == 0.0 {
            for j in 0..self.m {
                for &i in states {
                    out[j * n + i] = self.s[j * n + i];
                }
            }
            return;
        }
        let u = (t - self.t) / self.h_old;
        for j in 0..self.m {
            let cont = &self.cont[3 * n * j..3 * n * (j + 1)];
            for &i in states {
                let (a1, a2, a3) = (cont[i], cont[n + i], cont[2 * n + i]);
                out[j * n + i] = self.s[j * n + i] + u * (a1 + (u - C2M1) * (a2 + (u - C1M1) * a3));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::Tolerances;

    /// A stiff nonlinear pair with parameters (a, b): ẏ1 = −a y1 + y2², ẏ2 = −b (y2 − sin t).
    struct Pair {
        a: f64,
        b: f64,
    }

    impl OdeSystem for Pair {
        fn dim(&self) -> usize {
            2
        }
        fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), RhsError> {
            dy[0] = -self.a * y[0] + y[1] * y[1];
            dy[1] = -self.b * (y[1] - t.sin());
            Ok(())
        }
        fn jacobian(&self, _t: f64, y: &[f64], j: &mut [f64]) -> Result<(), RhsError> {
            j.copy_from_slice(&[-self.a, 0.0, 2.0 * y[1], -self.b]);
            Ok(())
        }
    }

    impl ParametricSystem for Pair {
        fn n_params(&self) -> usize {
            2
        }
        fn rhs_params(&self, t: f64, y: &[f64], fp: &mut [f64]) -> Result<(), RhsError> {
            fp.copy_from_slice(&[-y[0], 0.0, 0.0, -(y[1] - t.sin())]);
            Ok(())
        }
    }

    fn solve(a: f64, b: f64, rtol: f64, times: &[f64]) -> (Vec<[f64; 2]>, Vec<[f64; 4]>) {
        let sys = Pair { a, b };
        let tol = Tolerances::scaled(rtol, &[1.0, 1.0]);
        let mut solver = Radau5::new(2, tol);
        solver.init(&sys, 0.0, &[1.0, 0.0], 1e-6).unwrap();
        let mut sens = Sensitivities::new(2, 2, 0.0, &[0.0; 4]);
        let (mut ys, mut ss) = (Vec::new(), Vec::new());
        let (mut y, mut s) = ([0.0; 2], [0.0; 4]);
        let mut k = 0;
        while k < times.len() {
            while k < times.len() && times[k] <= solver.t() {
                solver.interpolate(times[k], &mut y);
                sens.interpolate(times[k], &[0, 1], &mut s);
                ys.push(y);
                ss.push(s);
                k += 1;
            }
            if k < times.len() {
                solver.step(&sys, *times.last().unwrap()).unwrap();
                sens.follow(&solver, &sys).unwrap();
            }
        }
        (ys, ss)
    }

    #[test]
    fn sensitivities_match_central_differences() {
        let times: Vec<f64> = (0..=40).map(|k| k as f64 * 0.1).collect();
        let (a, b) = (2.0, 1e3);
        let (_, s) = solve(a, b, 1e-8, &times);
        // the reference: central differences of step 1e-3 (truncation error ~1e-6 of the
        // size) of solutions at rtol 1e-13
        for (j, da, db) in [(0, 1e-3 * a, 0.0), (1, 0.0, 1e-3 * b)] {
            let (yp, _) = solve(a + da, b + db, 1e-13, &times);
            let (ym, _) = solve(a - da, b - db, 1e-13, &times);
            let step = 2.0 * (da + db);
            for i in 0..2 {
                let fd: Vec<f64> = (0..times.len())
                    .map(|k| (yp[k][i] - ym[k][i]) / step)
                    .collect();
                let size = fd.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                for k in 0..times.len() {
                    let got = s[k][j * 2 + i];
                    if (i, j) == (1, 0) {
                        // y2 does not depend on a: exactly zero, where the central differences
                        // see only the noise of two step sequences (the step control couples
                        // the components; rtol 1e-13 is an internal tolerance of 2e-10)
                        assert_eq!(got, 0.0, "t = {}: dy1/dθ0", times[k]);
                        continue;
                    }
                    assert!(
                        (got - fd[k]).abs() <= 1e-4 * size,
                        "t = {}: dy{i}/dθ{j} = {got:e}, central differences {:e}",
                        times[k],
                        fd[k]
                    );
                }
            }
        }
    }
}
