//! Kinematics of the 3PS platform (book/src/model.md, "Kinematics"): forward kinematics from the
//! three actuator heights to the antenna tip, the paper's closed-form inverse, an exact inverse,
//! and the inverse from tip X, Y alone given the mean height.

use nalgebra::{Matrix3, Vector3};

use super::params::Params;

/// Anchor points and antenna length of the platform.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Kinematics {
    /// (X_i, Y_i) of the anchors \[m\].
    pub anchors: [[f64; 2]; 3],
    /// Antenna length L \[m\].
    pub length: f64,
}

/// The exact inverse did not converge (the tip is out of reach of the geometry).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum IkmError {
    /// The kinematics Jacobian is singular at the heights `h` \[m\] of a Newton step.
    #[error("singular kinematics Jacobian at h = {h:?} m")]
    SingularJacobian { h: [f64; 3] },
    /// Newton did not converge in its step limit; `h` \[m\] are the last heights.
    #[error("inverse kinematics did not converge (last h = {h:?} m)")]
    NotConverged { h: [f64; 3] },
}

/// Which inverse of the kinematics (book/src/model.md, "Inverse kinematics").
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Inverse {
    /// The paper's closed form, approximate: `Kinematics::heights_closed_form`.
    ClosedForm,
    /// Newton on the FKM: [`Kinematics::heights`].
    Exact,
    /// From the tip's X and Y and the mean height h̄ \[m\]: `Kinematics::heights_from_xy`.
    Xy { mean_height: f64 },
}

impl Kinematics {
    pub fn new(p: &Params) -> Kinematics {
        let anchor = |a: f64| [p.anchor_radius * a.cos(), p.anchor_radius * a.sin()];
        Kinematics {
            anchors: [
                anchor(p.anchor_angle[0]),
                anchor(p.anchor_angle[1]),
                anchor(p.anchor_angle[2]),
            ],
            length: p.antenna_length,
        }
    }

    fn corner(&self, i: usize, h: f64) -> Vector3<f64> {
        Vector3::new(self.anchors[i][0], self.anchors[i][1], h)
    }

    fn anchor_mean(&self) -> [f64; 2] {
        let m = |k: usize| self.anchors.iter().map(|a| a[k]).sum::<f64>() / 3.0;
        [m(0), m(1)]
    }

    /// FKM: C_p = mean(P_i); n = (P2 − P1) × (P3 − P1) / ‖…‖; Tip = C_p + L n.
    pub fn tip(&self, h: [f64; 3]) -> [f64; 3] {
        let p = [
            self.corner(0, h[0]),
            self.corner(1, h[1]),
            self.corner(2, h[2]),
        ];
        let c_p = (p[0] + p[1] + p[2]) / 3.0;
        let n = (p[1] - p[0]).cross(&(p[2] - p[0])).normalize();
        (c_p + self.length * n).into()
    }

    /// ∂Tip/∂h_j (columns j) of the FKM above, differentiated in closed form (the FKM is
    /// explicit, no iteration): ∂C_p/∂h_j = e_z/3, ∂n = (I − n nᵀ) ∂c / ‖c‖ with c = e1 × e2.
    pub fn tip_jacobian(&self, h: [f64; 3]) -> Matrix3<f64> {
        let p = [
            self.corner(0, h[0]),
            self.corner(1, h[1]),
            self.corner(2, h[2]),
        ];
        let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
        let c = e1.cross(&e2);
        let norm = c.norm();
        let n = c / norm;
        let project = (Matrix3::identity() - n * n.transpose()) / norm;
        let ez = Vector3::z();
        // ∂e1/∂h = (−ez, ez, 0), ∂e2/∂h = (−ez, 0, ez)
        let de1 = [-ez, ez, Vector3::zeros()];
        let de2 = [-ez, Vector3::zeros(), ez];
        let mut jac = Matrix3::zeros();
        for j in 0..3 {
            let dc = de1[j].cross(&e2) + e1.cross(&de2[j]);
            let col = ez / 3.0 + self.length * project * dc;
            jac.set_column(j, &col);
        }
        jac
    }

    /// The paper's closed-form IKM ("normal-aligned stick"): v = (X − mean X_i, Y − mean Y_i, Z),
    /// n = v/‖v‖, C_p = Tip − L n, h_i = C_pZ − (n_X (X_i − C_pX) + n_Y (Y_i − C_pY)) / n_Z.
    /// Approximate: about 0.25 µm error per 100 µm of mean height.
    fn heights_closed_form(&self, tip: [f64; 3]) -> [f64; 3] {
        let m = self.anchor_mean();
        let n = Vector3::new(tip[0] - m[0], tip[1] - m[1], tip[2]).normalize();
        let c_p = Vector3::from(tip) - self.length * n;
        self.anchors
            .map(|a| c_p.z - (n.x * (a[0] - c_p.x) + n.y * (a[1] - c_p.y)) / n.z)
    }

    /// The heights \[m\] that put the tip at `tip` \[m\] by `method` (the XY inverse reads only
    /// the tip's X and Y).
    pub fn inverse(&self, method: Inverse, tip: [f64; 3]) -> Result<[f64; 3], IkmError> {
        match method {
            Inverse::ClosedForm => Ok(self.heights_closed_form(tip)),
            Inverse::Exact => self.heights(tip),
            Inverse::Xy { mean_height } => self.heights_from_xy([tip[0], tip[1]], mean_height),
        }
    }

    /// Exact IKM: Newton on the FKM from the closed form, to `1e-15 m`.
    pub fn heights(&self, tip: [f64; 3]) -> Result<[f64; 3], IkmError> {
        let target = Vector3::from(tip);
        self.newton(self.heights_closed_form(tip), |k, h| {
            let jac = k.tip_jacobian(h);
            (Vector3::from(k.tip(h)) - target, jac)
        })
    }

    /// Inverse from tip X, Y and the mean height h̄ (heave is not observable from X, Y alone).
    fn heights_from_xy(&self, xy: [f64; 2], mean_height: f64) -> Result<[f64; 3], IkmError> {
        let guess = [mean_height; 3];
        self.newton(guess, |k, h| {
            let tip = k.tip(h);
            let jac = k.tip_jacobian(h);
            let mut j = jac;
            j.set_row(2, &(nalgebra::RowVector3::repeat(1.0 / 3.0)));
            let r = Vector3::new(
                tip[0] - xy[0],
                tip[1] - xy[1],
                (h[0] + h[1] + h[2]) / 3.0 - mean_height,
            );
            (r, j)
        })
    }

    fn newton(
        &self,
        mut h: [f64; 3],
        residual: impl Fn(&Self, [f64; 3]) -> (Vector3<f64>, Matrix3<f64>),
    ) -> Result<[f64; 3], IkmError> {
        for _ in 0..50 {
            let (r, jac) = residual(self, h);
            let step = jac.lu().solve(&r).ok_or(IkmError::SingularJacobian { h })?;
            for i in 0..3 {
                h[i] -= step[i];
            }
            if step.amax() <= 1e-15 {
                return Ok(h);
            }
        }
        Err(IkmError::NotConverged { h })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kin() -> Kinematics {
        Kinematics::new(&Params::default())
    }

    #[test]
    fn level_platform_points_straight_up() {
        let tip = kin().tip([1e-5; 3]);
        // level up to the rounding of the anchors' cos/sin (0.02 m × 1e-16)
        assert!(
            tip[0].abs() < 1e-17 && tip[1].abs() < 1e-17,
            "tip = {tip:?}"
        );
        assert!((tip[2] - (1e-5 + 0.05)).abs() < 1e-15);
    }

    #[test]
    fn jacobian_matches_differences() {
        let k = kin();
        let h = [3e-5, 1.2e-4, -2e-6];
        let jac = k.tip_jacobian(h);
        for j in 0..3 {
            let (mut hp, mut hm) = (h, h);
            hp[j] += 1e-9;
            hm[j] -= 1e-9;
            let (tp, tm) = (k.tip(hp), k.tip(hm));
            for i in 0..3 {
                let fd = (tp[i] - tm[i]) / 2e-9;
                assert!(
                    (jac[(i, j)] - fd).abs() < 1e-6,
                    "({i},{j}) {} vs {fd}",
                    jac[(i, j)]
                );
            }
        }
    }

    #[test]
    fn inverse_round_trips() {
        let k = kin();
        let mut worst_closed: f64 = 0.0;
        for h in [
            [-5e-6, 2e-4, 1e-4],
            [1e-4, 1e-4, 1e-4],
            [0.0, 5e-5, 1.5e-4],
            [2e-4, -5e-6, 7e-5],
        ] {
            let tip = k.tip(h);
            let exact = k.heights(tip).unwrap();
            let closed = k.heights_closed_form(tip);
            let xy = k
                .heights_from_xy([tip[0], tip[1]], (h[0] + h[1] + h[2]) / 3.0)
                .unwrap();
            for i in 0..3 {
                // the exact IKM to 1e-9 µm, the XY inverse as well
                assert!((exact[i] - h[i]).abs() < 1e-15, "exact {exact:?} vs {h:?}");
                assert!((xy[i] - h[i]).abs() < 1e-15, "xy {xy:?} vs {h:?}");
                worst_closed = worst_closed.max((closed[i] - h[i]).abs());
            }
        }
        // book/src/model.md, "Inverse kinematics": the closed form is off by up to about
        // 0.35 µm on [−5, 200] µm
        assert!(
            worst_closed > 1e-8 && worst_closed < 0.4e-6,
            "closed-form error {worst_closed}"
        );
    }
}
