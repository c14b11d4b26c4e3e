//! The missing-effect workflow on data with hidden mechanisms (the reduced suite of CI; the
//! full one with its confusion matrix is `hasel bench --diagnose`): each effect of the library
//! hidden in another form, with the base parameters off by up to 20 % and 0.5–2 % noise, must be
//! named exactly with the fit after it at the noise floor; a second form of a family (a tilt
//! spring, retention across the film) must be named as its family, with a form that holds it
//! reported; data without an effect must give `none`; mechanisms outside the library
//! `unexplained`; lab artifacts (sensor lag and resolution, outliers, dropped rows) must not
//! name an effect nor hide one; two mechanisms at once must both be named.

use hasel_fmu::diagnose::hidden::{self, Truth};
use hasel_fmu::diagnose::{self, FIT_TOLERANCE, Options, Verdict, floor_fit};
use hasel_fmu::identify::conditions::{self, Choice};
use hasel_fmu::identify::synth::Columns;
use hasel_fmu::identify::{Options as IdOptions, Weighting};
use hasel_fmu::model::effects::{FittedLaw, prony};
use hasel_fmu::model::{Effect, Params};

/// The seed of the random-law cases below that pin no path: the decision rule's thresholds were
/// tuned on seeds 1–8 of `hasel bench --diagnose` and checked on 9–16; none was tuned on seed 17
/// (book/src/hidden-effects.md, "Seeds no rule was tuned on"). A test that pins a path names
/// the seed of the case that showed it.
const UNTUNED: u64 = 17;

fn diagnose_case(truth: Truth, columns: Columns, seed: u64) -> diagnose::Diagnosis {
    diagnose_hidden(hidden::hide(truth, seed).unwrap(), columns, seed)
}

fn diagnose_hidden(case: hidden::Hidden, columns: Columns, seed: u64) -> diagnose::Diagnosis {
    let exps = case.experiments(columns, seed).unwrap();
    diagnose::diagnose(&Params::default(), exps, &Options::default()).unwrap()
}

/// The effect is named exactly and the held-out fit after it is at the noise floor.
fn named(effect: Effect, seed: u64) {
    named_from(Truth::Effect(effect), Columns::Heights, seed);
}

fn named_from(truth: Truth, columns: Columns, seed: u64) -> diagnose::Diagnosis {
    let effect = truth.effect().unwrap();
    let d = diagnose_case(truth, columns, seed);
    assert_named(effect, &d);
    d
}

fn assert_named(effect: Effect, d: &diagnose::Diagnosis) {
    assert_eq!(
        d.verdict,
        Verdict::Effect,
        "{effect}: {:?} {:?}",
        d.verdict,
        d.ambiguous_between
    );
    assert_eq!(d.effects, vec![effect]);
    at_the_noise_floor(effect.name(), d);
    // the effect's magnitude was estimated and its interval excludes the neutral value
    let round = &d.rounds[0];
    let c = round
        .candidates
        .iter()
        .find(|c| c.effect == effect)
        .unwrap();
    assert!(c.refit.as_ref().unwrap().interval_excludes_neutral);
    // the estimation data weigh it most, and the weights are a distribution
    assert_eq!(round.evidence[0].0, Some(effect), "{:?}", round.evidence);
    let total: f64 = round.evidence.iter().map(|e| e.1).sum();
    assert!((total - 1.0).abs() < 1e-9, "{:?}", round.evidence);
}

/// Every held-out fit of the final model is within [`FIT_TOLERANCE`] of its noise floor.
fn at_the_noise_floor(case: &str, d: &diagnose::Diagnosis) {
    near_the_noise_floor(case, d, FIT_TOLERANCE);
}

/// Every held-out fit of the final model is within `tolerance` points of its noise floor.
fn near_the_noise_floor(case: &str, d: &diagnose::Diagnosis, tolerance: f64) {
    for (exp, fits) in d.experiments[1..].iter().zip(&d.last.validation) {
        // (the 2-D tip fit has no noise floor of its own: its coordinates are checked)
        for (name, fit) in fits.fits.iter().filter(|(n, _)| n != "tip_xy") {
            let floor = floor_fit(exp, name).unwrap();
            assert!(
                fit >= &(floor - tolerance),
                "{case}: held-out {name} fit {fit:.2} % below the noise floor {floor:.2} %"
            );
        }
    }
}

/// A further form of a family (its `variant`-th): named as the family, in one of `forms`
/// (reported in the JSON).
fn named_in_form(effect: Effect, variant: usize, forms: &[&str], seed: u64) -> diagnose::Diagnosis {
    let d = named_from(Truth::Variant(effect, variant), Columns::Heights, seed);
    assert_eq!(d.forms.len(), 1, "{effect}");
    assert!(
        forms.contains(&d.forms[0].name),
        "{effect}: {}",
        d.forms[0].name
    );
    let json = diagnose::report::to_json(&d);
    assert_eq!(json["forms"][0], d.forms[0].name);
    // the named candidate's refit says how far its fit went before it was judged
    let named = d.rounds[0].candidates.iter().find(|c| c.effect == effect);
    let refit = named
        .and_then(|c| c.refit.as_ref())
        .expect("the named family was refitted");
    let shown = json["rounds"][0]["candidates"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["effect"] == effect.name())
        .unwrap();
    assert_eq!(shown["iterations"], refit.id.iterations);
    assert_eq!(shown["stopped_at_budget"], refit.id.out_of_budget);
    d
}

/// The named effect's fitted law and the name of the textbook form nearest it, as the JSON
/// shows them.
fn law_shown(d: &diagnose::Diagnosis) -> (&FittedLaw, &'static str) {
    assert_eq!(d.laws.len(), 1, "{}", d.answer());
    let law = d.laws[0].as_ref().expect("the family has a fitted law");
    let json = diagnose::report::to_json(d);
    assert_eq!(json["laws"][0]["effect"], d.effects[0].name());
    let nearest = law.textbook[law.nearest].name;
    assert_eq!(json["laws"][0]["nearest"], nearest);
    (law, nearest)
}

#[test]
fn coupling_is_named() {
    named(Effect::Coupling, UNTUNED);
}

#[test]
fn charge_drift_is_named() {
    named(Effect::ChargeDrift, UNTUNED);
}

/// Two trapping stages in series (seed 3: at 0.13 and 1.1 s), which the one series stage held
/// 0.51 points below the noise floor: the series spectrum, its stages' resistances summing to
/// the truth's, within half a point of the floor.
#[test]
fn two_traps_in_series_are_charge_drift_in_its_series_spectrum() {
    let d = named_from(Truth::Effect(Effect::ChargeDrift), Columns::Heights, 3);
    assert_eq!(d.forms[0].name, "series_spectrum", "{}", d.answer());
    near_the_noise_floor("charge_drift", &d, 0.5);
    let fitted: f64 = d.last.params.effects.charge_drift.series.iter().sum();
    let truth = hidden::hide(Truth::Effect(Effect::ChargeDrift), 3).unwrap();
    let truth = truth.params.effects.charge_drift.r3;
    assert!(
        (fitted / truth).ln().abs() < 0.3f64.ln_1p(),
        "fitted {fitted} Ohm in all, truly {truth} Ohm"
    );
    // measured: 1.12 times the truth's, spread over the grid's 0.1 … 3 s
    let (law, _) = law_shown(&d);
    assert!(law.what.starts_with("retention spectrum"), "{}", law.what);
}

#[test]
fn creep_is_named() {
    named(Effect::Creep, UNTUNED);
}

/// A hidden kernel of `truth`'s family off the grid (seed `seed` draws one, a `kernel`): named
/// as its family, in the form of its spectrum, which the JSON shows weight by weight on the
/// grid with every textbook kernel's distance, the nearest among them.
fn a_kernel_is_its_spectrum(truth: Truth, seed: u64, kernel: &str) -> diagnose::Diagnosis {
    assert!(
        hidden::hide(truth, seed)
            .unwrap()
            .description
            .contains(kernel)
    );
    let d = named_from(truth, Columns::Heights, seed);
    assert_eq!(d.forms[0].name, "spectrum");
    law_shown(&d);
    let json = diagnose::report::to_json(&d);
    let law = &json["laws"][0];
    let taus: Vec<f64> = law["points"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p[0].as_f64().unwrap())
        .collect();
    assert_eq!(taus, prony::GRID, "{law}");
    let textbook = law["textbook"].as_array().unwrap();
    assert_eq!(textbook.len(), 4, "{law}");
    d
}

/// A creep of a power-law (fractional) kernel, which neither the grid nor the library's one
/// time contains (issue 29: a creep of a kernel unlike the library's was named `hysteresis`):
/// named `creep` with its spectrum. Seed 9 draws a power law (alpha 0.34); it was chosen before
/// it was first diagnosed, and tunes nothing.
#[test]
fn a_creep_of_a_fractional_kernel_is_creep_with_its_law() {
    a_kernel_is_its_spectrum(Truth::Effect(Effect::Creep), 9, "power-law");
}

/// Dielectric absorption across the film of a stretched-exponential kernel (beta 0.30, tau
/// 1.91 s), which neither the grid nor one absorption branch contains (issue 29: charge
/// retention as a Prony series): named `charge_drift` with its absorption spectrum, capacitance
/// by capacitance, the held-out fits at the noise floor. Seed 4 was chosen after
/// `hasel bench --diagnose --only charge_drift_kernel --seeds 6`: seeds 1-4 named
/// `charge_drift` alone (the spectrum on 1 and 4, one branch on 2 and 3, both two times off the
/// grid), seeds 5 and 6 (power laws) `charge_drift` with a first-order `amplifier_lag` beside it
/// (effects.md, "charge_drift"): seed 4 is the one named right whose kernel is no two times.
#[test]
fn dielectric_absorption_of_a_stretched_kernel_is_charge_drift_with_its_law() {
    let truth = Truth::Variant(Effect::ChargeDrift, 1);
    assert_eq!(truth.name(), "charge_drift_kernel");
    let d = a_kernel_is_its_spectrum(truth, 4, "stretched-exponential");
    assert_eq!(d.laws[0].as_ref().unwrap().axes[1], "C [F]");
}

#[test]
fn hysteresis_is_named() {
    named(Effect::Hysteresis, UNTUNED);
}

#[test]
fn amplifier_lag_is_named() {
    named(Effect::AmplifierLag, UNTUNED);
}

#[test]
fn delay_is_named() {
    named(Effect::Delay, UNTUNED);
}

#[test]
fn saturation_is_named() {
    named(Effect::Saturation, UNTUNED);
}

/// The suite's `saturation_unequal` seed 2: a refit holds a parameter alone, and the rounding of
/// what the held directions leave lends it the variance of one the data leave undetermined
/// beside it; found again, it was held again without end (`worst_direction` in
/// src/identify/group.rs no longer judges a parameter held alone, and `next_to_hold` holds
/// nothing already held).
#[test]
fn unequal_limits_whose_refit_holds_parameters_in_turn_are_named() {
    named_in_form(Effect::Saturation, 0, &["unequal", "shaped"], 2);
}

#[test]
fn stiffening_is_named() {
    named(Effect::Stiffening, UNTUNED);
}

#[test]
fn preload_is_named() {
    named(Effect::Preload, UNTUNED);
}

/// The suite's `preload` seed 2: the base fit took the load up with four parameters at a bound
/// of their range, and the screening scores it fourth (0.008) on a residual 33 % over the noise;
/// a screening that blind refits every score near its best (book/src/diagnose.md, "Screening").
#[test]
fn a_load_the_screening_hardly_sees_is_named() {
    named(Effect::Preload, 2);
}

#[test]
fn an_effect_is_named_from_a_single_record() {
    // a single record: its first two thirds estimate, and the model is judged on predicting
    // the last third from where the fit left it
    let mut one = hidden::Protocol::PAPER;
    one.records = 1;
    let case = hidden::hide(Truth::Effect(Effect::Coupling), 1)
        .unwrap()
        .with_protocol(one);
    let d = diagnose_hidden(case, Columns::Heights, 1);
    let [estimation, held] = &d.experiments[..] else {
        panic!("{} records", d.experiments.len());
    };
    assert_eq!(held.lead_in, estimation.t.len());
    let span = |t: &[f64]| t[t.len() - 1] - t[0];
    let dt = held.t[1] - held.t[0];
    assert!((span(&held.t[held.lead_in..]) - span(&held.t) / 3.0).abs() <= dt);
    assert_named(Effect::Coupling, &d);
}

#[test]
fn stiffening_is_named_from_the_tip_alone() {
    // the paper's laser: tip X and Y only, the heave unobserved
    named_from(Truth::Effect(Effect::Stiffening), Columns::TipXy, 1);
}

#[test]
fn a_tilt_spring_is_coupling_with_pair_stiffnesses() {
    named_in_form(Effect::Coupling, 0, &["pairs"], 1);
}

#[test]
fn retention_across_the_film_is_charge_drift_as_an_absorption_branch() {
    // across the film or across C2 alone differ by the branch bypassing C1 || R1, whose
    // R1 ~ 100 Ohm holds almost no voltage: either branch form, never the series stage
    named_in_form(Effect::ChargeDrift, 0, &["electrode", "film"], 1);
}

#[test]
fn an_output_stage_with_unequal_limits_is_named_saturation() {
    // random limits 6–14 V apart with a random tanh knee, which no form contains exactly
    let d = named_in_form(Effect::Saturation, 0, &["unequal", "shaped"], 8);
    let s = d.last.params.effects.saturation;
    let truth = hidden::hide(Truth::Variant(Effect::Saturation, 0), 8).unwrap();
    let truth = truth.params.effects.saturation;
    // the fitted limits are apart on the same side as the truth's
    let apart = s.u_max - s.negative_limit();
    assert!(
        apart * (truth.u_max - truth.u_max_neg) > 0.0 && apart.abs() > 3.0,
        "fitted +{} / -{}, truly +{} / -{}",
        s.u_max,
        s.negative_limit(),
        truth.u_max,
        truth.u_max_neg
    );
    let (law, nearest) = law_shown(&d);
    assert_eq!(nearest, "unequal clamp", "{}: {law:?}", law.what);
}

#[test]
fn a_slewing_amplifier_is_named_amplifier_lag() {
    // a slew limit whose transition is a random Rapp curve, which no sharpness of the fitted
    // transition contains exactly
    let d = named_in_form(Effect::AmplifierLag, 1, &["slew"], 8);
    let a = d.last.params.effects.amplifier_lag;
    let truth = hidden::hide(Truth::Variant(Effect::AmplifierLag, 1), 8).unwrap();
    let truth = truth.params.effects.amplifier_lag;
    assert!(
        (a.slew / truth.slew).ln().abs() < 0.2f64.ln_1p(),
        "slew {} V/s, truly {} V/s",
        a.slew,
        truth.slew
    );
    // the fitted rate law is the truth's over the errors the sines reach (RMS over ±60 V)
    let errors = (-600..=600).map(|k| 0.1 * f64::from(k));
    let (mut diff, mut norm) = (0.0, 0.0);
    for e in errors {
        diff += (a.rate(e).0 - truth.rate(e).0).powi(2);
        norm += truth.rate(e).0.powi(2);
    }
    let rms = (diff / norm).sqrt();
    assert!(
        rms < 0.01,
        "the fitted law {a:?} is {rms:.4} off the truth's {truth:?}"
    );
    // measured: 0.25 % off, of sharpness 1.52 beside a Rapp curve of exponent 4.68
    let (law, nearest) = law_shown(&d);
    assert_eq!(nearest, "tanh slew", "{}: {law:?}", law.what);
}

/// A slewing amplifier (seed 1) whose first round the amplifier lag leads in its first-order
/// form (ΔBIC −46,143, against a charge drift's −44,785; the slew's screening worth was under 0.8
/// of the lag's, so the slew was not refitted): that leaves h1 101.7 points below its noise floor,
/// nothing passes in round 2, and the slew tried in the lag's place lowers the BIC by 58,052 more
/// and ends at the noise floor (measured 0.08 points below on average).
#[test]
fn a_form_its_screening_misjudged_takes_its_place() {
    let d = diagnose_case(Truth::Variant(Effect::AmplifierLag, 1), Columns::Heights, 1);
    assert_eq!(d.verdict, Verdict::Effect, "{}", d.answer());
    assert_eq!(d.effects, vec![Effect::AmplifierLag]);
    assert_eq!(d.forms[0].name, "slew");
    let swapped = d
        .rounds
        .iter()
        .flat_map(|r| &r.revisits)
        .find(|v| v.swapped)
        .expect("a revisit swapped");
    assert_eq!(swapped.replaced, Effect::AmplifierLag);
    assert_eq!(swapped.by.map(|f| f.name), Some("slew"));
    let json = diagnose::report::to_json(&d);
    let revisits = json["rounds"][1]["revisits"].as_array().unwrap();
    let shown = revisits.iter().find(|v| v["swapped"] == true).unwrap();
    assert_eq!(shown["by_form"], "slew", "{json}");
    assert!(shown["delta_bic"].as_f64().unwrap() <= -diagnose::BIC_MARGIN);
    at_the_noise_floor("amplifier_lag_slew", &d);
}

/// A hardening of a power no series term has (7.37, seed 1; seeds 2–4 draw exponential
/// hardening): stiffening in its convex series, its law nearest the power law of that exponent.
/// The quartic alone leaves the held-out fit short of the noise floor.
#[test]
fn a_random_hardening_is_stiffening_in_its_convex_series() {
    let d = named_in_form(Effect::Stiffening, 0, &["convex"], 1);
    let (law, nearest) = law_shown(&d);
    assert_eq!(nearest, "power law", "{}: {law:?}", law.what);
    let fitted = &law.textbook[law.nearest].values;
    let n: f64 = fitted[4..fitted.find(',').unwrap()].parse().unwrap();
    assert!((n - 7.37).abs() < 1.0, "{fitted}");
}

/// A tilt spring hardening about its stiffer axis in a law outside the series (exponential,
/// a_s = 21 µm, seed 1, chosen before it was run): coupling in its convex series, which holds
/// the hardening (a weight of a power above the linear spring's above 0), its law nearer a
/// hardening spring than a linear one (a Duffing spring 1.4 % from it, the linear spring 14 %).
/// The series leaves the held-out fits 0.05 points below their floors; the pairs' linear springs
/// alone (the series' probe removed) left the farthest 0.80 below.
#[test]
fn a_hardening_tilt_spring_is_coupling_in_its_convex_series() {
    let d = named_in_form(Effect::Coupling, 1, &["convex"], 1);
    near_the_noise_floor("coupling_hardening_tilt", &d, 0.25);
    let series = d.last.params.effects.coupling.series;
    assert!(series[1..].iter().any(|&w| w > 0.0), "{series:?}");
    let (law, nearest) = law_shown(&d);
    assert_ne!(nearest, "linear spring", "{}: {law:?}", law.what);
}

/// Hysteresis of a density of yield angles off the plays' grid (log-normal about 1.4 mrad, seed
/// 1; `hasel bench --diagnose --only hysteresis_plays --seeds 3` named all three in `plays`):
/// named in its plays, the law shown.
#[test]
fn a_density_of_yield_angles_is_hysteresis_in_its_plays() {
    let d = named_in_form(Effect::Hysteresis, 1, &["plays", "plays_rate"], 1);
    let (law, _) = law_shown(&d);
    assert_eq!(law.points.len(), 201, "{}", law.what);
}

/// Two mechanisms at once: both named, in either order, each with its form in the JSON, and
/// the held-out fit after them at the noise floor.
fn both_named(case: &str, seed: u64) -> diagnose::Diagnosis {
    let truth = Truth::from_name(case).unwrap();
    let exps = hidden::hide(truth, seed)
        .unwrap()
        .experiments(Columns::Heights, seed)
        .unwrap();
    let d = diagnose::diagnose(&Params::default(), exps, &Options::default()).unwrap();
    let (mut want, mut got) = (truth.effects(), d.effects.clone());
    want.sort();
    got.sort();
    assert_eq!(d.verdict, Verdict::Effect, "{case}: {}", d.answer());
    assert_eq!(got, want, "{case}: {}", d.answer());
    at_the_noise_floor(case, &d);
    let json = diagnose::report::to_json(&d);
    for (k, (e, f)) in d.effects.iter().zip(&d.forms).enumerate() {
        assert_eq!(f.effect, *e);
        assert_eq!(json["effects"][k], e.name());
        assert_eq!(json["forms"][k], f.name);
    }
    d
}

#[test]
#[ignore = "long (115 s on one core): ci/bench.sh runs it"]
fn a_tilt_spring_and_creep_are_both_named() {
    // on this device rate-dependent hysteresis fits the creep best until the coupling is in:
    // the first effect is revisited once the second explains its share
    both_named("coupling_tilt+creep", 2);
}

#[test]
fn a_tilt_spring_and_creep_on_an_untuned_seed_are_both_named() {
    // (the other pairs on this seed: `amplifier_lag+stiffening` both named in 26.9 s, too long
    // for this suite; `charge_drift_film+hysteresis` one of the misses the bench counts, its film
    // drift worth 0.10 points beside the hysteresis)
    both_named("coupling_tilt+creep", UNTUNED);
}

#[test]
fn film_retention_and_hysteresis_are_both_named() {
    // on this device neither closes half of the held-out gap alone: hysteresis is added
    // provisionally and kept once the charge drift beside it closes the rest
    let d = both_named("charge_drift_film+hysteresis", 2);
    let provisional = d.rounds[0].provisional.unwrap();
    assert!(provisional.kept);
    assert_eq!(provisional.form.effect, d.effects[0]);
}

#[test]
fn an_amplifier_lag_and_stiffening_are_both_named() {
    // on this device a delay passes beside the lag in the first round; once the stiffening is
    // added, the revisit tries the delay in the lag's place, and the lag stays
    let d = both_named("amplifier_lag+stiffening", 3);
    assert_eq!(d.effects[0], Effect::AmplifierLag);
    let revisits = &d.rounds[1].revisits;
    assert!(
        revisits
            .iter()
            .any(|v| v.by.is_some_and(|f| f.effect == Effect::Delay))
            && revisits.iter().all(|v| !v.swapped),
        "{revisits:?}"
    );
    // and the stiffening, the round's own, against the model without it: kept, by far
    let own = revisits
        .iter()
        .find(|v| v.replaced == Effect::Stiffening && v.by.is_none())
        .expect("the round's own effect revisited");
    assert!(
        own.delta_bic
            .as_ref()
            .is_ok_and(|b| *b > diagnose::BIC_MARGIN),
        "{own:?}"
    );
}

#[test]
fn no_effect_is_named_on_data_without_one() {
    for seed in [UNTUNED, UNTUNED + 1] {
        let d = diagnose_case(Truth::Nothing, Columns::Heights, seed);
        assert_eq!(d.verdict, Verdict::None, "seed {seed}: {:?}", d.effects);
        assert!(d.effects.is_empty());
    }
}

#[test]
fn a_rippling_supply_is_unexplained() {
    let d = diagnose_case(Truth::Ripple, Columns::Heights, UNTUNED);
    assert_eq!(d.verdict, Verdict::Unexplained, "{:?}", d.effects);
}

#[test]
fn a_mechanism_outside_the_library_is_unexplained() {
    let d = diagnose_case(Truth::Outside, Columns::Heights, UNTUNED);
    assert_eq!(d.verdict, Verdict::Unexplained, "{:?}", d.effects);
    // and the analysis shows why: most of the structured residual is off the drive's harmonics
    let off: f64 = d.before.iter().map(|x| x.off_harmonic).sum::<f64>() / d.before.len() as f64;
    assert!(off > 0.5, "off-harmonic share {off}");
}

/// The outliers drawn are found and trimmed: at least half as many as the rate promises.
fn outliers_reported(case: &hidden::Hidden, d: &diagnose::Diagnosis) {
    let art = case.artifacts.as_ref().unwrap();
    let samples: usize = d
        .experiments
        .iter()
        .map(|e| e.t.len() * e.channels.len())
        .sum();
    let found: usize = d.outliers.iter().map(|o| o.times.len()).sum();
    let drawn = art.outlier_rate * samples as f64;
    assert!(
        found as f64 >= 0.5 * drawn && (found as f64) < 2.0 * drawn + 3.0,
        "{found} outliers found, about {drawn:.0} drawn"
    );
}

#[test]
fn no_effect_is_named_on_lab_data() {
    for seed in [UNTUNED, UNTUNED + 1] {
        let case = hidden::hide(Truth::Nothing, seed)
            .unwrap()
            .with_artifacts(seed);
        let d = diagnose_hidden(case.clone(), Columns::Heights, seed);
        assert_eq!(d.verdict, Verdict::None, "seed {seed}: {:?}", d.effects);
        outliers_reported(&case, &d);
    }
}

#[test]
fn an_effect_is_named_on_lab_data() {
    let case = hidden::hide(Truth::Effect(Effect::Creep), UNTUNED)
        .unwrap()
        .with_artifacts(UNTUNED);
    let d = diagnose_hidden(case.clone(), Columns::Heights, UNTUNED);
    assert_named(Effect::Creep, &d);
    outliers_reported(&case, &d);
}

/// A diagnosis of heights with the records' conditions estimated as by default: the start
/// detected, the sensor's lag fitted (`--start auto --lag estimate`).
fn diagnose_lab(case: hidden::Hidden, seed: u64) -> diagnose::Diagnosis {
    let exps = case.experiments(Columns::Heights, seed).unwrap();
    diagnose::diagnose(&Params::default(), exps, &Options::default()).unwrap()
}

/// Twins of one device (issue: lab protocols): recorded from rest and `after` seconds into the
/// drive, the same verdict, and the mid-run records' start found, not taken for rest.
fn same_verdict_mid_run(truth: Truth, seed: u64, after: f64) -> [diagnose::Diagnosis; 2] {
    let case = hidden::hide(truth, seed).unwrap();
    let from_rest = diagnose_lab(case.clone(), seed);
    let mid_run = diagnose_lab(case.mid_run(after), seed);
    assert_eq!(
        (from_rest.verdict, &from_rest.effects),
        (mid_run.verdict, &mid_run.effects),
        "{}: from rest {}, mid-run {}",
        truth.name(),
        from_rest.answer(),
        mid_run.answer()
    );
    for f in &from_rest.base.conditions {
        assert_eq!(f.start_how, "rest", "{}: {f:?}", truth.name());
    }
    for f in &mid_run.base.conditions {
        assert_eq!(f.start_how, "detected mid-run, estimated", "{f:?}");
    }
    [from_rest, mid_run]
}

#[test]
fn a_record_that_starts_mid_run_is_judged_as_from_rest() {
    let [_, mid] = same_verdict_mid_run(Truth::Nothing, 1, 1.37);
    assert_eq!(mid.verdict, Verdict::None);
    // the start estimated where the device stood: within two noise σ of one sample of the
    // noise-free record's first (the start is fitted to the whole transient, at rest velocity)
    let mut clean = hidden::hide(Truth::Nothing, 1).unwrap().mid_run(1.37);
    clean.noise = 0.0;
    let truth = clean.experiments(Columns::Heights, 1).unwrap();
    for ((f, e), noisy) in mid.base.conditions.iter().zip(&truth).zip(&mid.experiments) {
        for (i, (c, y)) in e.channels.iter().enumerate() {
            let sigma = diagnose::analysis::noise_level(&noisy.t, &noisy.channels[i].1);
            assert!(
                (f.heights[i] - y[0]).abs() < 2.0 * sigma,
                "{}: {} at the start {:.2} um, truly {:.2} um",
                f.experiment,
                c.name(),
                f.heights[i] * 1e6,
                y[0] * 1e6
            );
        }
    }
}

#[test]
fn a_sensor_lag_neither_names_an_effect_nor_leaves_unexplained() {
    let case = hidden::hide(Truth::Nothing, 2).unwrap();
    for lag in [0.0, 3.2e-4] {
        let d = diagnose_lab(case.clone().with_sensor_lag(lag), 2);
        assert_eq!(d.verdict, Verdict::None, "lag {lag}: {}", d.answer());
    }
}

/// A hidden delay seen on a lab's tip chirp, three records of 10 s from 1.3 s into the drive (the
/// protocols' benchmark case of `Protocol::draw(6 * 7919 + 1)`): `delay`. It was `unexplained`
/// while the generator ran such a record 1.3 s past the drive it had made, then `amplifier_lag`
/// while a refit without states kept the start the model without the delay had found.
#[test]
#[ignore = "long (113 s on one core): ci/bench.sh runs it"]
fn a_delay_on_a_tip_chirp_recorded_mid_run_is_named_delay() {
    let protocol = hidden::Protocol::draw(6 * 7919 + 1);
    assert!(
        protocol.tip && protocol.drive == hidden::Drive::Chirp,
        "{protocol:?}"
    );
    let case = hidden::hide(Truth::Effect(Effect::Delay), 1)
        .unwrap()
        .with_protocol(protocol)
        .mid_run(1.3);
    let d = diagnose_lab(case, 1);
    for f in &d.base.conditions {
        assert_eq!(f.start_how, "detected mid-run, estimated", "{f:?}");
    }
    assert_named(Effect::Delay, &d);
}

/// The protocols' benchmark case `name` at `seed` as `hasel bench --diagnose --protocols --only
/// NAME` draws it, diagnosed, its start checked as its protocol has it.
fn diagnose_drawn(name: &str, seed: u64) -> diagnose::Diagnosis {
    let truth = Truth::from_name(name).unwrap();
    let case = hidden::hide(truth, seed).unwrap().in_drawn_protocol(seed);
    let mid_run = case.record_from > 0.0;
    let label = case.protocol_label();
    let d = diagnose_lab(case, seed);
    for f in &d.base.conditions {
        let how = if mid_run {
            "detected mid-run, estimated"
        } else {
            "rest"
        };
        assert_eq!(f.start_how, how, "{name} ({label}): {f:?}");
    }
    d
}

/// A rate-dependent hysteresis seen on the tip, sines at 1 ms from 1.3 s into the drive: the
/// paper's model is left 0.14 points below the noise floor on average, where no effect can gain
/// `MIN_GAIN` (0.2 points). The hysteresis closes 73 % of that gap and is named; it was
/// `unexplained` while the gain asked was 0.2 points whatever the gap.
#[test]
#[ignore = "long (51 s on one core): ci/bench.sh runs it"]
fn a_hysteresis_close_to_the_noise_floor_is_named() {
    let d = diagnose_drawn("hysteresis_rate", 1);
    assert_named(Effect::Hysteresis, &d);
}

/// A Prandtl–Ishlinskii hysteresis on a staircase at 1 ms from 1.3 s into the drive: it was
/// `unexplained` while the screening scored each form at its states settled at the start,
/// where its refit estimates them. (Named in its `rate_independent` form, the model is left
/// 3.4 points below the floor on a held-out record: the plays' form is not refitted.)
#[test]
#[ignore = "long (197 s on one core): ci/bench.sh runs it"]
fn a_hysteresis_on_a_staircase_recorded_mid_run_is_named() {
    let d = diagnose_drawn("hysteresis_plays", 1);
    assert_eq!(d.verdict, Verdict::Effect, "{}", d.answer());
    assert_eq!(d.effects, vec![Effect::Hysteresis], "{}", d.answer());
}

/// An amplifier lag and a stiffening on two voltage levels at 1 ms, tip only, mid-run: a charge
/// drift's spectrum leads the first round and leaves the held-out tip fits 0.47 points below
/// their floor, with 21 % and 32 % more variance than the noise. Within `AT_FLOOR` in points, but
/// beyond `HELD_OUT_EXCESS` in variance: a second round adds the stiffening and a revisit swaps
/// the drift for the lag. The revisit's try starts from the model's base parameters, fitted with
/// the stiffening beside: from the runner-up's own (fitted without it) the lag converged 172.5
/// above the drift in BIC, from the model's 303.4 below (measured 0.07 points below the floor;
/// book/src/diagnose.md, "Two mechanisms at once").
#[test]
#[ignore = "long (228 s idle): ci/bench.sh runs it"]
fn a_second_effect_is_looked_for_where_a_fit_near_its_floor_hides_variance() {
    let d = diagnose_drawn("amplifier_lag+stiffening", 1);
    let mut got = d.effects.clone();
    got.sort();
    assert_eq!(
        got,
        [Effect::AmplifierLag, Effect::Stiffening],
        "{}",
        d.answer()
    );
    assert_eq!(d.rounds[0].added, Some(Effect::ChargeDrift));
    near_the_noise_floor("amplifier_lag+stiffening", &d, 0.5);
}

/// A record mid-run of a device with a static load the model lacks (a preload): the model is
/// off by about as much everywhere as at rest, and that offset must not hide the start (in
/// the protocols' benchmark the held-out record of this case was simulated from rest).
#[test]
fn a_start_mid_run_is_found_though_the_model_misses_a_static_load() {
    let protocol = hidden::Protocol::draw(71272).lasting(6.0);
    assert_eq!(protocol.drive, hidden::Drive::Levels);
    let case = hidden::hide(Truth::Effect(Effect::Preload), 1).unwrap();
    let exps = case
        .with_protocol(protocol)
        .mid_run(1.3)
        .experiments(Columns::Heights, 1)
        .unwrap();
    let rtol = IdOptions::default().rtol;
    for exp in &exps {
        let found = conditions::estimate(
            &Params::default(),
            exp,
            Choice::default(),
            (rtol, Weighting::Equal),
        );
        let how = found.unwrap().start_how;
        assert_eq!(how, "detected mid-run, estimated", "{}", exp.name);
    }
}

/// A weight on the platform recorded on two voltage levels from 1.3 s into the drive (the
/// protocols' benchmark case `preload` seed 1): the estimation record, a 60 V sine, does not
/// tell the device at 35 V. Its true model with its own parameters predicts the held-out record
/// at the noise floor (0.006 points measured), its start mid-run found; with the paper's
/// parameters refitted on the estimation record, as a diagnosis fits, it leaves the held-out h1
/// 201.6 points below. On the paper's two sines the same device's truth refits to its floor
/// (`preload_is_named` names it there). No effect can pass on the levels, and the answer is
/// `unexplained`, not another effect: the benchmark counts it among the misses beyond the
/// truth's reach.
#[test]
#[ignore = "long (99 s on one core): ci/bench.sh runs it"]
fn a_load_its_estimation_record_cannot_tell_is_unexplained() {
    let opts = Options::default();
    let truth_gaps = |case: &hidden::Hidden| {
        let exps = case.experiments(Columns::Heights, 1).unwrap();
        diagnose::truth_gaps(&case.true_model().unwrap(), exps, &opts).unwrap()
    };
    let paper = hidden::hide(Truth::Effect(Effect::Preload), 1).unwrap();
    let gaps = truth_gaps(&paper);
    assert!(gaps.refitted < FIT_TOLERANCE, "the paper's sines: {gaps:?}");
    let levels = paper.in_drawn_protocol(1);
    assert_eq!(levels.protocol.drive, hidden::Drive::Levels);
    let gaps = truth_gaps(&levels);
    assert!(gaps.held < 0.1, "two levels: {gaps:?}");
    assert!(gaps.refitted > 10.0 * FIT_TOLERANCE, "two levels: {gaps:?}");
    let d = diagnose_lab(levels, 1);
    assert_eq!(d.verdict, Verdict::Unexplained, "{}", d.answer());
}
