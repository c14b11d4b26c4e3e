//! Shell geometry of one actuator as a function of (θ, l_p), with first and second partial
//! derivatives (book/src/model.md, "Shell geometry and C2"):
//!
//! ```text
//! δ1  = (π + θ)/2 − asin( (Lv/l_p) sin((π − θ)/2) )
//! A_s = ¼ l_p Lv sin δ1          liquid area inside the shell
//! d   = 2 A_s / l_p = ½ Lv sin δ1
//! ```
//!
//! Second derivatives are needed for the analytic Jacobian (∇²H). sin δ1 and cos δ1 come from
//! the angle-difference formulas, so the right-hand side needs no asin; sin θ and cos θ come
//! from the half angle's by the double-angle formulas, so one `sin_cos` serves the shell, the
//! gravity terms and the heights of one evaluation.

/// The model is defined only where the asin argument is below 1, i.e. l_p > Lv cos(θ/2).
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error(
    "shell geometry undefined at theta = {theta:e} rad, l_p = {l_p:e} m: needs l_p > Lv cos(theta/2) = {bound:e} m",
    bound = .lv * (.theta / 2.0).cos()
)]
pub struct DomainError {
    pub theta: f64,
    pub l_p: f64,
    pub lv: f64,
}

/// A_s and d at one (θ, l_p) with their first partials; subscripts `_t` = ∂/∂θ, `_l` = ∂/∂l_p.
/// Second partials come from [`Shell::curvature`], which only the Jacobian needs.
#[derive(Clone, Copy, Debug)]
pub struct Shell {
    pub a_s: f64,
    pub a_s_t: f64,
    pub a_s_l: f64,
    pub d: f64,
    l_p: f64,
    lv: f64,
    /// s = (Lv/l_p) cos(θ/2), the asin argument, and k = 1/√(1 − s²) = asin'(s)
    s: f64,
    k: f64,
    /// ∂s/∂θ, ∂s/∂l_p
    s_t: f64,
    s_l: f64,
    sin_d: f64,
    cos_d: f64,
    /// ∂δ1/∂θ, ∂δ1/∂l_p
    dl_t: f64,
    dl_l: f64,
    /// sin θ and cos θ
    pub sin_theta: f64,
    pub cos_theta: f64,
}

/// Second partials of A_s and first partials of d.
#[derive(Clone, Copy, Debug)]
pub struct Curvature {
    pub a_s_tt: f64,
    pub a_s_tl: f64,
    pub a_s_ll: f64,
    pub d_t: f64,
    pub d_l: f64,
}

impl Shell {
    #[inline]
    pub fn new(theta: f64, l_p: f64, lv: f64) -> Result<Shell, DomainError> {
        // s = (Lv/l_p) sin((π − θ)/2) = (Lv/l_p) cos(θ/2)
        let (sin_h, cos_h) = (theta / 2.0).sin_cos();
        // one division for the three quotients by l_p
        let inv_lp = 1.0 / l_p;
        let lv_lp = lv * inv_lp;
        let s = lv_lp * cos_h;
        if l_p <= 0.0 || s.abs() >= 1.0 || s.is_nan() || !theta.is_finite() {
            return Err(DomainError { theta, l_p, lv });
        }
        let cos_a = (1.0 - s * s).sqrt();
        let k = 1.0 / cos_a;
        // δ1 = (π + θ)/2 − a with sin a = s: sin δ1 and cos δ1 by the angle-difference formulas
        let sin_d = cos_h * cos_a + sin_h * s;
        let cos_d = -sin_h * cos_a + cos_h * s;
        let s_t = -0.5 * lv_lp * sin_h;
        let s_l = -s * inv_lp;
        let (dl_t, dl_l) = (0.5 - k * s_t, -k * s_l);
        let q = 0.25 * lv;
        Ok(Shell {
            a_s: q * l_p * sin_d,
            a_s_t: q * l_p * cos_d * dl_t,
            a_s_l: q * (sin_d + l_p * cos_d * dl_l),
            d: 0.5 * lv * sin_d,
            l_p,
            lv,
            s,
            k,
            s_t,
            s_l,
            sin_d,
            cos_d,
            dl_t,
            dl_l,
            sin_theta: 2.0 * sin_h * cos_h,
            cos_theta: (cos_h - sin_h) * (cos_h + sin_h),
        })
    }

    /// δ1 \[rad\].
    #[cfg(test)]
    fn delta1(&self) -> f64 {
        self.sin_d.atan2(self.cos_d)
    }

    pub fn curvature(&self) -> Curvature {
        let Shell {
            l_p,
            lv,
            s,
            k,
            s_t,
            s_l,
            sin_d,
            cos_d,
            dl_t,
            dl_l,
            ..
        } = *self;
        let s_tt = -0.25 * s;
        let s_tl = -s_t / l_p;
        let s_ll = 2.0 * s / (l_p * l_p);
        // a = asin(s): a' = k, a'' = s k³; δ1 = (π + θ)/2 − a
        let k3s = s * k * k * k;
        let dl_tt = -(k3s * s_t * s_t + k * s_tt);
        let dl_tl = -(k3s * s_t * s_l + k * s_tl);
        let dl_ll = -(k3s * s_l * s_l + k * s_ll);
        let q = 0.25 * lv;
        Curvature {
            a_s_tt: q * l_p * (-sin_d * dl_t * dl_t + cos_d * dl_tt),
            a_s_tl: q * (cos_d * dl_t + l_p * (-sin_d * dl_t * dl_l + cos_d * dl_tl)),
            a_s_ll: q * (2.0 * cos_d * dl_l + l_p * (-sin_d * dl_l * dl_l + cos_d * dl_ll)),
            d_t: 0.5 * lv * cos_d * dl_t,
            d_l: 0.5 * lv * cos_d * dl_l,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LV: f64 = 0.012;

    #[test]
    fn partials_match_central_differences() {
        for &(th, l) in &[
            (0.0, 0.014),
            (0.02, 0.01395),
            (-0.01, 0.01401),
            (0.3, 0.0135),
        ] {
            let s = Shell::new(th, l, LV).unwrap();
            let c = s.curvature();
            let (ht, hl) = (1e-6, 1e-9);
            let pt = Shell::new(th + ht, l, LV).unwrap();
            let mt = Shell::new(th - ht, l, LV).unwrap();
            let pl = Shell::new(th, l + hl, LV).unwrap();
            let ml = Shell::new(th, l - hl, LV).unwrap();
            // δ1 as book/src/model.md writes it ("Shell geometry and C2")
            let delta1 = 0.5 * (std::f64::consts::PI + th)
                - (LV / l * (0.5 * (std::f64::consts::PI - th)).sin()).asin();
            assert!((s.delta1() - delta1).abs() < 1e-14);
            assert!((s.a_s - 0.25 * l * LV * delta1.sin()).abs() < 1e-20);
            let close = |a: f64, b: f64, what: &str| {
                assert!(
                    (a - b).abs() <= 1e-6 * b.abs().max(1e-6),
                    "{what}: {a} vs {b}"
                );
            };
            close(s.a_s_t, (pt.a_s - mt.a_s) / (2.0 * ht), "A_s_t");
            close(s.a_s_l, (pl.a_s - ml.a_s) / (2.0 * hl), "A_s_l");
            close(c.a_s_tt, (pt.a_s_t - mt.a_s_t) / (2.0 * ht), "A_s_tt");
            close(c.a_s_tl, (pl.a_s_t - ml.a_s_t) / (2.0 * hl), "A_s_tl");
            close(c.a_s_ll, (pl.a_s_l - ml.a_s_l) / (2.0 * hl), "A_s_ll");
            close(c.d_t, (pt.d - mt.d) / (2.0 * ht), "d_t");
            close(c.d_l, (pl.d - ml.d) / (2.0 * hl), "d_l");
            close(s.d, 2.0 * s.a_s / l, "d = 2 A_s / l_p");
            assert!(
                (s.sin_theta - th.sin()).abs() <= 1e-16 && (s.cos_theta - th.cos()).abs() <= 2e-16
            );
        }
    }

    #[test]
    fn outside_the_asin_domain_is_an_error() {
        let e = Shell::new(0.0, 0.0119, LV).unwrap_err();
        assert!(e.to_string().contains("needs l_p > Lv cos(theta/2)"));
        assert!(Shell::new(f64::NAN, 0.014, LV).is_err());
    }
}
