use super::charge_drift::DriftSite;
use super::hysteresis::HysteresisLaw;
use super::preload::PreloadLaw;
use super::*;
use crate::model::platform::BlockState;
use crate::model::platform::tests::assert_jacobian_matches;
use crate::model::{Params, Platform};

/// Every effect on, in library form or in the other forms.
fn all_on(other_forms: bool) -> Params {
    let mut p = Params::default();
    let f = &mut p.effects;
    f.coupling.k_c = 40.0;
    f.charge_drift.r3 = 2e4;
    f.charge_drift.tau3 = 0.5;
    f.creep.k_v = 0.05;
    f.creep.tau_v = 0.3;
    f.hysteresis.k_h = 0.04;
    f.hysteresis.theta_h = 2e-3;
    f.amplifier_lag.tau_a = 0.02;
    f.saturation.u_max = 50.0;
    f.stiffening.k3 = 30.0;
    f.preload.tau0 = [1e-4, -2e-4, 3e-4];
    if other_forms {
        f.coupling.weights = [1.0, 0.5, 1.5];
        f.coupling.series = [30.0, 0.0, 200.0, 100.0];
        f.coupling.hidden = super::coupling::HiddenTilt {
            law: super::convex::Hardening::Power { k: 300.0, n: 4.6 },
            axis: [2.0, -1.0, -1.0].map(|x| x / 3.0),
        };
        f.charge_drift.two_stages = true;
        // the absorption spectrum with capacitances at 0 among its branches, and a synthetic
        // branch
        f.charge_drift.grid = [1e-9, 0.0, 3e-9, 0.0, 2e-9, 1e-9];
        f.charge_drift.spread[5] = super::prony::Branch {
            weight: 2e-9,
            tau: 0.7,
        };
        // the series spectrum with resistances at 0 among its stages
        f.charge_drift.series = [0.0, 1e4, 0.0, 3e4, 2e4, 0.0];
        // a spectrum with weights at 0 among its branches, and a synthetic branch
        f.creep.grid = [0.02, 0.0, 0.01, 0.0, 0.03, 0.01];
        f.creep.spread[3] = super::prony::Branch {
            weight: 0.01,
            tau: 0.7,
        };
        f.hysteresis.r_h = 3.0;
        f.hysteresis.law = HysteresisLaw::Dahl;
        // plays with weights at 0 among them, and a synthetic element
        f.hysteresis.grid = [0.01, 0.0, 0.02, 0.0, 0.01];
        f.hysteresis.spread[2] = super::hysteresis::Element {
            k: 0.01,
            theta: 3e-3,
        };
        f.amplifier_lag.tau_a2 = 0.004;
        // slewing for errors beyond S tau_a = 20 V: the busy state's reach that far
        f.amplifier_lag.slew = 1000.0;
        f.amplifier_lag.sharpness = 2.5;
        f.saturation.u_max_neg = 35.0;
        f.saturation.knee = 0.3;
        f.saturation.u_dead = 2.0;
        f.stiffening.series = [0.02, 0.0, 0.01, 0.005];
        f.stiffening.hidden = super::convex::Hardening::Exponential { k: 0.01, x_s: 0.01 };
        f.preload.law = PreloadLaw::Weight;
    }
    p
}

/// The other forms with the input path's synthetic shapes: a tanh knee, a Rapp slew transition.
fn synthetic_input_path() -> Params {
    let mut p = all_on(true);
    p.effects.saturation.tanh_knee = 0.2;
    p.effects.amplifier_lag.rapp_rate = 3.0;
    p
}

/// The library form, the other forms (the absorption spectrum among them), the input path's
/// synthetic shapes, and the other forms with the drift element across the zipping capacitor and
/// across the film.
fn configurations() -> Vec<(String, Params)> {
    let mut out = vec![
        ("library forms".to_string(), all_on(false)),
        ("other forms".to_string(), all_on(true)),
        ("synthetic input path".to_string(), synthetic_input_path()),
    ];
    for site in [DriftSite::Electrode, DriftSite::Film] {
        let mut p = all_on(true);
        p.effects.charge_drift.site = site;
        p.effects.charge_drift.c3 = 2e-9;
        out.push((format!("other forms, drift {site:?}"), p));
    }
    out
}

/// A state away from rest: charges, momentum, a zipped electrode, effect states off rest.
fn busy_state(m: &Platform) -> Vec<f64> {
    let mut x = m.rest_state().unwrap();
    let names = m.state_names();
    for (k, name) in names.iter().enumerate() {
        let i: f64 = name[name.len() - 1..].parse().unwrap();
        let base = name.rsplit_once('_').unwrap().0;
        let a = &m.actuators[i as usize - 1];
        let theta = 0.004 * i;
        x[k] = match base {
            "theta" => theta,
            "l_p" => a.l_p_on_curve(theta).unwrap(),
            "p" => 3e-8 * (i - 2.0) + 1e-9,
            "Q1" => 2e-9,
            "Q2" => 3e-8,
            // an absorption branch's charge at tens of volts, none where its C is 0
            b if b.starts_with("Q3") => {
                let cd = &m.params().effects.charge_drift;
                match b[2..].parse::<usize>().map_or(0, |n| n - 1) {
                    s @ 1..=6 => 40.0 * i * cd.grid[s - 1],
                    s @ 8.. => 40.0 * i * cd.spread[s - 8].weight,
                    _ => 1e-7 * i,
                }
            }
            b if b.starts_with("z_v") => theta * 0.7,
            "z_h" => 4e-4 * (i - 1.5),
            _ => 20.0 * i, // amplifier stages
        };
    }
    x
}

fn check_jacobian(p: Params, u: [f64; 3]) {
    let m = Platform::new(p).unwrap();
    assert_jacobian_matches(&m, &busy_state(&m), u);
}

#[test]
fn neutral_by_default() {
    let m = Platform::new(Params::default()).unwrap();
    assert_eq!(m.n_states(), crate::model::platform::N_STATES);
    assert!(Params::default().effects.active().is_empty());
    assert_eq!(m.jacobian_blocks(), vec![5, 5, 5]);
}

#[test]
fn jacobian_matches_finite_differences_with_every_effect() {
    // U inside the clipping range (the hard clamp has no derivative at its corners)
    for (_, p) in configurations().into_iter().chain(without_amplifier()) {
        check_jacobian(p, [40.0, 25.0, -30.0]);
    }
    check_jacobian(all_on(false), [70.0, 25.0, -80.0]);
    // beyond the map's limits and in its dead zone, of either sign
    for (_, p) in without_amplifier() {
        check_jacobian(p, [70.0, 1.0, -80.0]);
    }
}

/// The configurations with the amplifier off as well: the output map then reads the command
/// itself, of either sign.
fn without_amplifier() -> Vec<(String, Params)> {
    let mut out = configurations();
    for (name, p) in &mut out {
        name.push_str(", no amplifier");
        p.effects.switch_off(Effect::AmplifierLag);
    }
    out
}

#[test]
fn the_output_map_is_monotone_and_its_slope_exact() {
    use super::saturation::Saturation;
    let maps = [all_on(false), all_on(true), synthetic_input_path()]
        .map(|p| p.effects.saturation)
        .into_iter()
        .chain([Saturation {
            u_max: 40.0,
            knee: 1e-3,
            ..Saturation::default()
        }]);
    for s in maps {
        let mut last = f64::NEG_INFINITY;
        for k in -1000..=1000 {
            let v = 0.1 * f64::from(k) + 0.0123;
            let (u, slope) = s.map(v);
            assert!(u >= last && slope >= 0.0, "{s:?} at {v}");
            last = u;
            let h = 1e-6;
            let fd = (s.map(v + h).0 - s.map(v - h).0) / (2.0 * h);
            assert!((fd - slope).abs() < 1e-6, "{s:?} at {v}: {slope} vs {fd}");
        }
    }
}

#[test]
fn the_rate_law_is_monotone_and_its_slope_exact() {
    let rates = [all_on(true), synthetic_input_path()].map(|p| p.effects.amplifier_lag);
    for a in rates {
        let mut last = f64::NEG_INFINITY;
        for k in -1000..=1000 {
            let e = 0.1 * f64::from(k) + 0.0123;
            let (r, slope) = a.rate(e);
            assert!(r >= last && slope > 0.0, "{a:?} at {e}");
            last = r;
            let h = 1e-6;
            let fd = (a.rate(e + h).0 - a.rate(e - h).0) / (2.0 * h);
            assert!((fd - slope).abs() < 1e-6 * slope.max(1.0), "{a:?} at {e}");
        }
        // linear at small errors, slewing at S for large ones
        assert!((a.rate(1e-6).0 * a.tau_a / 1e-6 - 1.0).abs() < 1e-6);
        assert!((a.rate(1e4).0 / a.slew - 1.0).abs() < 1e-3);
    }
}

/// The fitted law shown beside the textbook forms: a law that is one of them is at distance 0
/// from it and named nearest, with its values.
#[test]
fn a_textbook_law_is_nearest_itself() {
    let mut p = Params::default();
    p.effects.saturation.u_max = 54.5;
    p.effects.saturation.u_max_neg = 88.0;
    let law = (Effect::Saturation.family().law)(&p, 60.0).unwrap();
    let nearest = &law.textbook[law.nearest];
    assert_eq!(nearest.name, "unequal clamp", "{law:?}");
    assert_eq!(nearest.values, "+54.5 V / -none", "{law:?}");
    assert!(nearest.distance < 1e-6, "{law:?}");
    let mut p = Params::default();
    p.effects.amplifier_lag.tau_a = 0.02;
    let law = (Effect::AmplifierLag.family().law)(&p, 60.0).unwrap();
    let nearest = &law.textbook[law.nearest];
    assert_eq!(nearest.name, "linear lag", "{law:?}");
    assert_eq!(nearest.values, "tau 20.00 ms", "{law:?}");
    assert!(nearest.distance < 1e-6, "{law:?}");
    // a slew far below the fastest error: nearest the hard slew limit
    p.effects.amplifier_lag.slew = 100.0;
    let law = (Effect::AmplifierLag.family().law)(&p, 60.0).unwrap();
    let nearest = &law.textbook[law.nearest];
    assert_eq!(nearest.name, "tanh slew", "{law:?}");
    assert!(nearest.values.starts_with("100 V/s"), "{law:?}");
    assert!(nearest.distance < 1e-6, "{law:?}");
    // …and as sharp a transition: nearest the hard slew limit
    p.effects.amplifier_lag.sharpness = 20.0;
    let law = (Effect::AmplifierLag.family().law)(&p, 60.0).unwrap();
    let nearest = &law.textbook[law.nearest];
    assert_eq!(nearest.name, "hard slew limit", "{law:?}");
    assert!(nearest.values.starts_with("100 V/s"), "{law:?}");
    assert!(nearest.distance < 0.05, "{law:?}");
}

/// The slew's transition φ_p: the tanh at p = 1, the hard limit min(x, 1) as p grows, softer
/// below 1, increasing with the slope its differences give at every p.
#[test]
fn the_slew_transition_spans_the_tanh_and_the_hard_limit() {
    let mut a = super::amplifier_lag::AmplifierLag {
        tau_a: 0.01,
        slew: 100.0,
        ..Default::default()
    };
    let x = |e: f64| e / (a.slew * a.tau_a);
    for e in [0.0, 1e-9, 0.3, 1.0, 2.0, 7.0, 1e3] {
        let tanh = a.slew * x(e).tanh();
        assert!((a.rate(e).0 - tanh).abs() <= 1e-13 * a.slew, "at {e}");
    }
    a.sharpness = 60.0;
    for e in [0.1, 0.5, 0.9, 1.0, 1.2, 3.0] {
        let limit = a.slew * x(e).min(1.0);
        assert!((a.rate(e).0 - limit).abs() < 0.01 * a.slew, "at {e}");
    }
    for p in [0.3, 1.0, 2.5, 8.0, 60.0] {
        a.sharpness = p;
        let mut last = f64::NEG_INFINITY;
        for k in -400..=400 {
            let e = 0.01 * f64::from(k) + 1e-4;
            let (r, slope) = a.rate(e);
            assert!(r >= last && slope >= 0.0, "p {p} at {e}");
            last = r;
            let h = 1e-7;
            let fd = (a.rate(e + h).0 - a.rate(e - h).0) / (2.0 * h);
            assert!(
                (fd - slope).abs() < 1e-5 * slope.max(1.0),
                "p {p} at {e}: {slope} vs {fd}"
            );
        }
        // linear at small errors with the slope 1/τ_a at every sharpness (1 − x^(2p)(2p + 1)/3p)
        assert!((a.rate(1e-12).1 * a.tau_a - 1.0).abs() < 1e-6, "p {p}");
    }
    // a softer transition lies below the tanh, a sharper one above it
    let at = |p: f64| {
        let mut a = a;
        a.sharpness = p;
        a.rate(1.0).0
    };
    assert!(at(0.5) < at(1.0) && at(1.0) < at(3.0));
}

#[test]
fn input_jacobian_matches_finite_differences() {
    // the commands on the map's knee and beyond it, in its dead zone, and slewing
    let us = [[40.0, 1.0, -30.0], [70.0, -1.5, -80.0]];
    for (name, p) in configurations().into_iter().chain(without_amplifier()) {
        let m = Platform::new(p).unwrap();
        let x = busy_state(&m);
        let n = m.n_states();
        for u in us {
            let mut b = vec![0.0; 3 * n];
            m.input_jacobian(&x, u, &mut b).unwrap();
            let (mut fp, mut fm) = (vec![0.0; n], vec![0.0; n]);
            for j in 0..3 {
                let h = 1e-6 * u[j].abs().max(1.0);
                let (mut up, mut um) = (u, u);
                up[j] += h;
                um[j] -= h;
                m.rhs(&x, up, &mut fp).unwrap();
                m.rhs(&x, um, &mut fm).unwrap();
                for r in 0..n {
                    let fd = (fp[r] - fm[r]) / (2.0 * h);
                    let an = b[j * n + r];
                    // the difference's rounding: the rate's last digits over the step
                    let rounding = 1e-13 * fp[r].abs().max(fm[r].abs()) / h;
                    assert!(
                        (an - fd).abs() <= 1e-6 * fd.abs().max(an.abs()) + rounding,
                        "{name}, U = {u:?}: d{}/dU{}: analytic {an:e} vs fd {fd:e}",
                        m.state_names()[r],
                        j + 1
                    );
                }
            }
        }
    }
}

#[test]
fn power_balance_holds_with_every_effect() {
    // dH/dt along f (central difference in time) = supplied − dissipated
    for (other, p) in configurations() {
        let m = Platform::new(p).unwrap();
        let x = busy_state(&m);
        let u = [40.0, 25.0, -30.0];
        let n = m.n_states();
        let mut f = vec![0.0; n];
        m.rhs(&x, u, &mut f).unwrap();
        let eps = 1e-13;
        let at = |s: f64| {
            let y: Vec<f64> = x.iter().zip(&f).map(|(a, b)| a + s * b).collect();
            m.energy(&y).unwrap()
        };
        let dh = (at(eps) - at(-eps)) / (2.0 * eps);
        let supplied = m.supplied_power(&x, u).unwrap();
        let dissipated = m.dissipated_power(&x).unwrap();
        let scale = supplied.abs() + dissipated;
        assert!(
            (dh - (supplied - dissipated)).abs() < 1e-7 * scale,
            "{other}: dH/dt {dh:e}, supplied − dissipated {:e}",
            supplied - dissipated
        );
        let stored = m.stored_power(&x, u).unwrap();
        assert!((stored - (supplied - dissipated)).abs() < 1e-9 * scale);
    }
}

#[test]
fn rest_state_is_an_equilibrium_with_static_loads() {
    for (_, p) in configurations() {
        let m = Platform::new(p).unwrap();
        let x = m.rest_state().unwrap();
        let mut dx = vec![0.0; m.n_states()];
        m.rhs(&x, [0.0; 3], &mut dx).unwrap();
        let names = m.state_names();
        for (k, v) in dx.iter().enumerate() {
            assert!(v.abs() < 1e-13, "{} rate {v:e} at rest", names[k]);
        }
        // the preload moves the rest heights: τ0/Kb ≈ 3e-4 rad ≈ 2 µm
        let h = m.heights(&x);
        let h0 = Platform::new(Params::default()).unwrap().heights(
            &Platform::new(Params::default())
                .unwrap()
                .rest_state()
                .unwrap(),
        );
        assert!((h[2] - h0[2]).abs() > 1e-6, "{h:?} vs {h0:?}");
    }
}

#[test]
fn coupling_joins_the_blocks_and_effect_states_are_named() {
    let m = Platform::new(all_on(false)).unwrap();
    assert_eq!(m.jacobian_blocks(), vec![m.n_states()]);
    let names = m.state_names();
    for want in ["Q3_1", "z_v_2", "z_h_3", "U_amp_1"] {
        assert!(m.state_index(want).is_some(), "{want} in {names:?}");
    }
    assert_eq!(m.n_states(), 3 * 9);
}

#[test]
fn effects_have_parameters_in_the_table() {
    for e in Effect::ALL {
        for name in e.parameters() {
            assert!(Params::default().get(name).is_ok(), "{e}: {name}");
        }
        assert_eq!(Effect::from_name(e.name()), Some(e));
        assert!(!e.is_active(&EffectParams::default()));
    }
}

#[test]
fn every_form_is_in_the_table_and_neutral_until_its_magnitude() {
    for e in Effect::ALL {
        assert!(
            !e.forms().is_empty() && Form::library(e).is_library(),
            "{e}"
        );
        for f in e.forms() {
            let mut p = Params::default();
            for &(name, v) in f.settings {
                p.set(name, v).unwrap();
            }
            assert!(
                !e.is_active(&p.effects),
                "{e}/{}: on before its magnitude",
                f.name
            );
            for name in f.free {
                assert!(p.get(name).is_ok(), "{e}/{}: {name}", f.name);
            }
            // the form's magnitude switches the effect on
            p.set(f.free[0], 1e-3).unwrap();
            assert!(e.is_active(&p.effects), "{e}/{}", f.name);
        }
    }
}

#[test]
fn a_refined_form_is_nested_and_exchangeable_magnitudes_are_magnitudes() {
    for e in Effect::ALL {
        for f in e.forms() {
            if let Some(name) = f.refines {
                let simpler = e.forms().iter().find(|g| g.name == name);
                let simpler = simpler.unwrap_or_else(|| panic!("{e}/{}: no form {name}", f.name));
                assert!(simpler.name != f.name, "{e}/{}", f.name);
                for p in simpler.free {
                    assert!(f.free.contains(p), "{e}/{}: {p} of {name}", f.name);
                }
            }
            if let Some((a, b)) = f.exchangeable {
                assert!(a != b, "{e}/{}", f.name);
                for m in [a, b] {
                    assert!(f.magnitudes.contains(&m), "{e}/{}: {m}", f.name);
                }
            }
        }
    }
}

#[test]
fn state_positions_agree_with_the_names() {
    for (_, p) in configurations() {
        let m = Platform::new(p).unwrap();
        for i in 0..3 {
            for s in m.block_states() {
                let name = format!("{}_{}", s.name(), i + 1);
                assert_eq!(m.state_position(i, s), m.state_index(&name), "{name}");
                assert!(name.starts_with(s.info().name), "{name}");
            }
        }
    }
    let paper = Platform::new(Params::default()).unwrap();
    for e in terms::Extra::table_states() {
        assert_eq!(paper.state_position(0, BlockState::Extra(e)), None, "{e:?}");
    }
}

/// The registry is the one list: each family's module describes itself whole, and everything
/// that lists the families (the parameter table, the FMU's states, the documents) follows.
/// A family added to the registry and forgotten somewhere is named here.
#[test]
fn each_family_describes_itself_whole() {
    let doc = include_str!("../../../book/src/effects.md");
    let rows_of = |e: Effect| {
        let f = e.family();
        f.rows.iter().chain(f.choices).map(|d| d.name)
    };
    let mut sections = Vec::new();
    for e in Effect::ALL {
        let f = e.family();
        assert_eq!(f.effect, e, "{}: FAMILY names another effect", f.name);
        // its rows, named for it in the table, neutral by default
        for d in f.rows.iter().chain(f.choices) {
            assert!(
                d.description.starts_with(&format!("{}: ", f.name)),
                "{e}: the row {} does not name its family",
                d.name
            );
            assert!(Params::default().get(d.name).is_ok(), "{e}: {}", d.name);
        }
        // every form frees, switches on and sets rows of its own family
        for form in f.forms {
            assert_eq!(form.effect, e, "{e}/{}", form.name);
            let names = form.free.iter().chain(form.magnitudes);
            for name in names.chain(form.settings.iter().map(|s| &s.0)) {
                assert!(rows_of(e).any(|n| n == *name), "{e}/{}: {name}", form.name);
            }
        }
        // on, off, and the states the table can switch on
        let mut p = EffectParams::default();
        (f.on)(&mut p);
        assert!(e.is_active(&p), "{e}: `on` leaves it off");
        let m = Platform::new(Params {
            effects: p,
            ..Params::default()
        })
        .unwrap();
        let states = m.extra_states().iter().filter(|s| s.effect == e).count();
        assert_eq!(states, f.table_stages, "{e}: `on` and table_stages");
        assert_eq!(f.state.is_some(), f.table_stages > 0, "{e}: its state");
        p.switch_off(e);
        assert_eq!(p, EffectParams::default(), "{e}: switch_off");
        // its probes reach every form, through its own rows
        let probes = (f.probes)(&Params::default(), 60.0);
        for form in f.forms {
            assert!(
                probes.iter().any(|p| p.form == form),
                "{e}/{}: no probe",
                form.name
            );
        }
        for (probe, (name, _)) in probes
            .iter()
            .flat_map(|p| p.columns.iter().flatten().map(move |c| (p, c)))
        {
            assert!(
                rows_of(probe.form.effect).any(|n| n == *name),
                "{e}: probe of {name}"
            );
        }
        // its hidden forms switch it on
        for (name, plant) in std::iter::once((f.name, f.hidden)).chain(f.variants.iter().copied()) {
            let mut p = Params::default();
            let planted = plant(&mut p, &mut |lo, hi| 0.5 * (lo + hi));
            let delayed = planted.wandering_delay.is_some();
            assert!(
                e.is_active(&p.effects) || delayed,
                "{name}: planted nothing"
            );
            assert!(!planted.text.is_empty(), "{name}");
        }
        // the documents: its section, its row of the library's table, its parameters
        let section = format!("\n## {}\n", f.name);
        sections.push(
            doc.find(&section)
                .unwrap_or_else(|| panic!("effects.md: no {section}")),
        );
        let row = format!("\n| `{}` |", f.name);
        assert!(
            doc.contains(&row),
            "effects.md: {e} not in the library's table"
        );
        for name in rows_of(e) {
            assert!(
                doc.contains(&format!("`{name}`")),
                "effects.md: {e}'s {name}"
            );
        }
    }
    assert!(
        sections.is_sorted(),
        "effects.md: the families' sections in registry order"
    );
    // names are unique among families and hidden forms
    let mut names: Vec<&str> = Effect::ALL
        .iter()
        .flat_map(|e| std::iter::once(e.name()).chain(e.family().variants.iter().map(|v| v.0)))
        .collect();
    let n = names.len();
    names.sort();
    names.dedup();
    assert_eq!(
        names.len(),
        n,
        "a name twice among the families and their hidden forms"
    );
}

/// Where no effect links the actuators, an actuator's own parameter moves its own block of f
/// and no other, and [`Platform::actuator_rhs`] is that block of f (what the sensitivities'
/// ∂f/∂θ computes alone for such a parameter).
#[test]
fn an_actuators_own_parameter_moves_only_its_block() {
    for mut p in [all_on(false), all_on(true)] {
        p.effects.switch_off(Effect::Coupling);
        let m = Platform::new(p.clone()).unwrap();
        assert_eq!(m.jacobian_blocks().len(), 3);
        let (x, u) = (busy_state(&m), [40.0, 25.0, -30.0]);
        let nb = x.len() / 3;
        let mut f = vec![0.0; x.len()];
        m.rhs(&x, u, &mut f).unwrap();
        let own = crate::model::params::parameters().filter(|d| d.actuator.is_some());
        for def in own {
            let i = def.actuator.unwrap();
            let mut q = p.clone();
            let v = (def.get)(&p);
            q.set_param(def, if v == 0.0 { 1e-3 } else { 1.01 * v })
                .unwrap();
            let moved = Platform::new(q).unwrap();
            if moved.n_states() != m.n_states() {
                continue; // switched an effect's states on: no derivative to take
            }
            let mut g = vec![0.0; x.len()];
            moved.rhs(&x, u, &mut g).unwrap();
            for k in (0..x.len()).filter(|k| k / nb != i) {
                assert_eq!(f[k], g[k], "{}: state {k} of another block", def.name);
            }
            let mut block = vec![0.0; nb];
            moved.actuator_rhs(i, &x, u, &mut block).unwrap();
            assert_eq!(block, g[nb * i..nb * (i + 1)], "{}", def.name);
        }
    }
    // a reduction's block is its f's, which comes from the lift of all of its state
    for r in crate::model::Reduction::ALL {
        let m = Platform::reduced(all_on(false), r).unwrap();
        let (x, u) = (m.rest_state().unwrap(), [40.0, 25.0, -30.0]);
        let nb = x.len() / 3;
        let mut f = vec![0.0; x.len()];
        m.rhs(&x, u, &mut f).unwrap();
        for i in 0..3 {
            let mut block = vec![0.0; nb];
            m.actuator_rhs(i, &x, u, &mut block).unwrap();
            assert_eq!(block, f[nb * i..nb * (i + 1)], "{r:?}, actuator {}", i + 1);
        }
    }
}
