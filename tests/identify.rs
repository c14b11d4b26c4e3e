//! The identification protocol of the paper on synthetic data: start 20 % off on every free
//! parameter, estimate at 3π rad/s, validate at 11 rad/s, 1 % measurement noise.

use hasel_fmu::identify::synth::{self, Columns, Spec};
use hasel_fmu::identify::{
    Experiment, Identification, Options, Weighting, fits, identify, simulate,
};
use hasel_fmu::model::Params;
use nalgebra::{DMatrix, DVector};

fn experiment(name: &str, omega: f64, columns: Columns, seed: u64, truth: &Params) -> Experiment {
    synth::experiment(&Spec::paper(truth, omega, columns, 0.01, seed), name).unwrap()
}

/// The paper's excitation of `truth` at 3π rad/s, heights with 1 % noise.
fn heights_at_3pi(truth: &Params, seed: u64) -> Spec {
    Spec::paper(
        truth,
        3.0 * std::f64::consts::PI,
        Columns::Heights,
        0.01,
        seed,
    )
}

/// 99.9 % quantiles of χ² with k degrees of freedom, k = 0..12.
const CHI2_999: [f64; 13] = [
    0.0, 10.83, 13.82, 16.27, 18.47, 20.52, 22.46, 24.32, 26.12, 27.88, 29.59, 31.26, 32.91,
];

/// Every free parameter 20 % off, alternately up and down.
fn offset_start(truth: &Params) -> Params {
    synth::offset(truth, &Options::default().free, 0.2).unwrap()
}

/// The protocol on three independent noise realisations. A 95 % interval misses the truth one
/// time in twenty, and Kb, b and gamma1 of an actuator correlate to 0.999, so they miss
/// together: "every parameter inside its interval" fails for about half of all seeds by
/// construction. The test asks what an honest covariance must give: the estimation error of
/// all parameters jointly inside the 99.9 % confidence ellipsoid of the reported covariance
/// (Mahalanobis distance in log-parameters against χ², where nothing is held), each miss of a
/// single interval a near miss (within 1.5 half-widths), no interval absurdly wide, and every
/// fit at the noise floor.
/// (A Monte Carlo run of 16 seeds on actuator 2 gave empirical standard deviations 0.95–0.99
/// times the reported standard errors.)
fn check_protocol(columns: Columns) -> Vec<Identification> {
    let truth = Params::default();
    let start = offset_start(&truth);
    let (mut inside, mut total) = (0, 0);
    let mut runs = Vec::new();
    for seed in [11, 13, 15] {
        let est = vec![experiment(
            "w3pi.csv",
            3.0 * std::f64::consts::PI,
            columns,
            seed,
            &truth,
        )];
        let val = vec![experiment("w11.csv", 11.0, columns, seed + 1, &truth)];
        let id = identify(&start, &est, &val, &Options::default()).unwrap();
        println!(
            "{columns:?}, seed {seed}: {} iterations, {} simulations, {:.2} s",
            id.iterations, id.simulations, id.seconds
        );
        println!("  not identifiable: {:?}", id.not_identifiable);
        // the truth, moved along each held combination to where the estimate is held (the
        // start's value of that combination): what the data can recover
        let mut reachable = truth.clone();
        for dir in &id.held_combinations {
            let shift: f64 = dir
                .iter()
                .map(|(n, w)| w * (start.get(n).unwrap() / truth.get(n).unwrap()).ln())
                .sum();
            for (n, w) in dir {
                reachable
                    .set(n, reachable.get(n).unwrap() * (w * shift).exp())
                    .unwrap();
            }
        }
        for e in id.estimates.iter().filter(|e| e.free) {
            let want = reachable.get(&e.name).unwrap();
            assert!(e.estimated, "{} was not estimated", e.name);
            let (lo, hi) = e.ci95.unwrap();
            let half = 0.5 * (hi - lo);
            let covered = lo <= want && want <= hi;
            println!(
                "  {:<9} {:.5} in [{:.5}, {:.5}], true {want:.5}{}",
                e.name,
                e.value,
                lo,
                hi,
                if covered { "" } else { "  MISSED" }
            );
            total += 1;
            inside += covered as usize;
            assert!(
                (e.value - want).abs() <= 1.5 * half + (e.value - 0.5 * (lo + hi)).abs(),
                "{}: {want} far outside [{lo}, {hi}]",
                e.name
            );
            // not absurdly wide: within ±15 % of the estimate
            assert!(
                hi - lo < 0.3 * e.value,
                "{}: interval [{lo}, {hi}] too wide",
                e.name
            );
        }
        // jointly, in log-parameters: (θ̂ − θ)ᵀ C⁺ (θ̂ − θ) within the 99.9 % quantile of χ² with
        // rank(C) degrees of freedom (the held combination removes one)
        let (names, corr) = &id.correlation;
        let se_log: Vec<f64> = names
            .iter()
            .map(|n| {
                let e = id.estimates.iter().find(|e| &e.name == n).unwrap();
                e.std_error.unwrap() / e.value
            })
            .collect();
        let cov = DMatrix::from_fn(names.len(), names.len(), |a, b| {
            corr[(a, b)] * se_log[a] * se_log[b]
        });
        let err = DVector::from_iterator(
            names.len(),
            names
                .iter()
                .map(|n| (id.params.get(n).unwrap() / reachable.get(n).unwrap()).ln()),
        );
        let rank = names.len() - id.held_combinations.len();
        let tol = 1e-12 * cov.amax();
        let d2 = (err.transpose() * cov.pseudo_inverse(tol).unwrap() * &err)[(0, 0)];
        println!(
            "  Mahalanobis distance² {d2:.2} with {rank} degrees of freedom (99.9 % quantile {})",
            CHI2_999[rank]
        );
        // With a held combination the recoverable point is the truth moved along the model's own
        // near-null direction, which the estimated direction only approximates; the thinnest
        // directions magnify that difference, so the joint check applies where nothing is held.
        if id.held_combinations.is_empty() {
            assert!(
                d2 <= CHI2_999[rank],
                "estimation error outside the 99.9 % confidence ellipsoid: {d2}"
            );
        }
        // both fits at the noise floor: as good as the true parameters on the same noisy data
        for (exps, got) in [(&est, &id.estimation), (&val, &id.validation)] {
            for (exp, fit) in exps.iter().zip(got.iter()) {
                let floor = fits(exp, &simulate(&truth, exp, 1e-9).unwrap());
                for ((c, f), (_, f0)) in fit.fits.iter().zip(&floor.fits) {
                    println!("  {} {c}: fit {f:.3} %, noise floor {f0:.3} %", exp.name);
                    assert!(
                        *f >= f0 - 0.1,
                        "{} {c}: fit {f} below the noise floor {f0}",
                        exp.name
                    );
                }
            }
        }
        runs.push(id);
    }
    println!("{columns:?}: {inside} of {total} intervals cover the truth");
    runs
}

#[test]
fn heights_identify_every_free_parameter_at_the_noise_floor() {
    for id in check_protocol(Columns::Heights) {
        // the gravity sag of the rest state fixes the scale: nothing is held
        assert!(id.not_identifiable.is_empty(), "{:?}", id.not_identifiable);
    }
}

#[test]
fn tip_xy_alone_identifies_all_but_the_unobservable_common_scale() {
    for id in check_protocol(Columns::TipXy) {
        // From X, Y alone a common scale of Kb, b and gamma1² of all three actuators only moves the
        // heave: exactly that one combination is reported and held, no single parameter.
        assert_eq!(id.held_combinations.len(), 1, "{:?}", id.not_identifiable);
        assert_eq!(id.not_identifiable.len(), 1, "{:?}", id.not_identifiable);
        let dir = &id.held_combinations[0];
        let weight = |n: &str| dir.iter().find(|(m, _)| m == n).unwrap().1;
        let sign = weight("Kb_1").signum();
        for i in 1..=3 {
            let (kb, b, g1, g2) = (
                sign * weight(&format!("Kb_{i}")),
                sign * weight(&format!("b_{i}")),
                sign * weight(&format!("gamma1_{i}")),
                weight(&format!("gamma2_{i}")),
            );
            assert!(
                kb > 0.2 && b > 0.2 && g1 > 0.08 && g1 < kb && g2.abs() < 0.05,
                "{dir:?}"
            );
        }
    }
}

#[test]
fn parameters_the_data_cannot_determine_are_reported_not_fitted() {
    let truth = Params::default();
    let est = vec![experiment(
        "w3pi.csv",
        3.0 * std::f64::consts::PI,
        Columns::Heights,
        21,
        &truth,
    )];
    let mut opts = Options::default();
    opts.free.extend(["K_1".to_string(), "C1_1".to_string()]);
    let start = offset_start(&truth);
    let id = identify(&start, &est, &[], &opts).unwrap();
    let flagged: Vec<&str> = id
        .not_identifiable
        .iter()
        .map(|(n, _)| n.as_str())
        .collect();
    println!("not identifiable: {:?}", id.not_identifiable);
    assert!(
        flagged.contains(&"K_1") && flagged.contains(&"C1_1"),
        "{flagged:?}"
    );
    for name in ["K_1", "C1_1"] {
        let e = id.estimates.iter().find(|e| e.name == name).unwrap();
        assert!(e.free && !e.estimated && e.ci95.is_none());
        assert_eq!(
            e.value,
            start.get(name).unwrap(),
            "{name} must stay at its start value"
        );
    }
    // the identifiable ones are still estimated
    let kb = id.estimates.iter().find(|e| e.name == "Kb_1").unwrap();
    assert!(
        kb.estimated && (kb.value - 0.305).abs() < 0.05 * 0.305,
        "{kb:?}"
    );
}

/// `iteration_budget` bounds a group's Levenberg–Marquardt iterations over all its runs; the fit
/// then ends where it got to, still a fit with its fits and covariance.
#[test]
fn an_iteration_budget_ends_each_group_fit_where_it_got_to() {
    let truth = Params::default();
    let start = offset_start(&truth);
    let est = [experiment(
        "w3pi.csv",
        3.0 * std::f64::consts::PI,
        Columns::Heights,
        11,
        &truth,
    )];
    let free_run = identify(&start, &est, &[], &Options::default()).unwrap();
    let budget = 2;
    let cut = identify(
        &start,
        &est,
        &[],
        &Options {
            iteration_budget: Some(budget),
            ..Options::default()
        },
    )
    .unwrap();
    // one group per actuator: the heights are measured apart
    assert!(
        cut.iterations <= 3 * budget,
        "{} iterations",
        cut.iterations
    );
    assert!(free_run.iterations > cut.iterations);
    assert!(cut.out_of_budget && !free_run.out_of_budget);
    let total = |fits: &[hasel_fmu::identify::ExperimentFit]| -> f64 {
        fits[0].fits.iter().map(|(_, f)| f).sum()
    };
    // it got somewhere, and not as far as the fit without a budget
    assert!(total(&cut.estimation) > total(&cut.estimation_before) + 1.0);
    assert!(total(&cut.estimation) <= total(&free_run.estimation) + 1e-6);
}

/// A fit from a guess (a diagnosis's refit) holds a direction the data do not determine where
/// the fit had taken it: on data the paper's model cannot fit (a tilt spring and creep it
/// lacks) the misfit widens the intervals until directions are held, and holding them at the
/// start gives back part of what the fit had gained along them; holding them where the fit got
/// to keeps it, and the parameters held are reported all the same.
#[test]
fn a_direction_held_where_the_fit_reached_keeps_what_it_gained() {
    use hasel_fmu::diagnose::hidden::{self, Truth};
    use hasel_fmu::identify::Hold;
    let case = hidden::hide(Truth::from_name("coupling_tilt+creep").unwrap(), 1).unwrap();
    let exps = case.experiments(Columns::Heights, 1).unwrap();
    let start = Params::default();
    let run = |hold: Hold| {
        identify(
            &start,
            &exps[..1],
            &exps[1..],
            &Options {
                hold,
                ..Options::default()
            },
        )
        .unwrap()
    };
    let (at_start, reached) = (run(Hold::Start), run(Hold::Reached));
    let total = |id: &Identification| -> f64 { id.estimation[0].fits.iter().map(|(_, f)| f).sum() };
    println!(
        "held at the start: {:?}, fits {:.2}; where reached: {:?}, fits {:.2}",
        at_start.not_identifiable,
        total(&at_start),
        reached.not_identifiable,
        total(&reached)
    );
    assert!(!at_start.not_identifiable.is_empty());
    assert!(!reached.not_identifiable.is_empty());
    assert!(total(&reached) > total(&at_start) + 1.0);
}

/// A parameter the data push against its bound is not undetermined: its column of J is
/// one-sided there, so the covariance calls it so, and held at its start it moved the point
/// back where the fit cost ten times as much. From the tip of a device with a stiffening the
/// paper's model lacks (the diagnosis's `stiffening_random`, seed 1), the fit takes gamma2_2
/// to its bound 2 × 30.5 (its 95 % interval spans a factor 1e288); held at the start, with four
/// more at their bounds after it, the residual sum of squares rose from 1.21e4 to 1.95e5. Held
/// at the bound, the fit keeps what it had reached, and says where and why; `Hold::Prior`, a
/// diagnosis's base fit, holds it at the start.
#[test]
fn a_parameter_pushed_against_its_bound_is_held_there() {
    use hasel_fmu::diagnose::hidden::{self, Truth};
    let case = hidden::hide(Truth::from_name("stiffening_random").unwrap(), 1).unwrap();
    let exps = case.experiments(Columns::TipXy, 1).unwrap();
    let start = Params::default();
    // as a diagnosis bounds the paper's model: within a factor 2 of its table
    let mut opts = Options::default();
    for name in hasel_fmu::identify::default_free() {
        let v = start.get(&name).unwrap();
        opts.bounds.insert(name, (v / 2.0, v * 2.0));
    }
    let id = identify(&start, &exps[..1], &[], &opts).unwrap();
    let (name, reason) = id
        .not_identifiable
        .iter()
        .find(|(_, r)| r.contains("at its bound"))
        .expect("a parameter held at its bound");
    let value = id.params.get(name).unwrap();
    let prior = start.get(name).unwrap();
    assert!(
        (value / prior - 2.0).abs() < 1e-9 || (value / prior - 0.5).abs() < 1e-9,
        "{name} = {value} ({reason})"
    );
    let fit = |id: &hasel_fmu::identify::Identification| {
        id.estimation[0].fits.iter().map(|(_, f)| f).sum::<f64>() / 2.0
    };
    assert!(fit(&id) > 90.0, "estimation fit {:.1} %", fit(&id));
    // a diagnosis's base fit holds it at its start: there the push is the symptom it looks for
    let prior = Options {
        hold: hasel_fmu::identify::Hold::Prior,
        ..opts
    };
    let at_prior = identify(&start, &exps[..1], &[], &prior).unwrap();
    assert_eq!(at_prior.params.get(name).unwrap(), start.get(name).unwrap());
    assert!(fit(&at_prior) < fit(&id) - 10.0, "{:.1} %", fit(&at_prior));
}

/// The weights of a series (the creep's spectrum, rule `Weight`) are fitted in their own units,
/// so that a weight the data would have negative ends at its bound 0, where the BIC of a
/// diagnosis stops counting it (book/src/identify.md, "How `hasel identify` estimates"); in log
/// coordinates no weight could reach 0. Data of one branch at 0.3 s with 1 % noise, every weight
/// started at a sixth of it.
#[test]
fn a_spectrum_s_weights_reach_zero_where_the_data_want_none() {
    use hasel_fmu::model::effects::creep::GRID_NAMES;
    let mut truth = Params::default();
    truth.effects.creep.grid[2] = 0.06;
    let spec = Spec {
        t_end: 4.0,
        ..heights_at_3pi(&truth, 7)
    };
    let est = [synth::experiment(&spec, "w3pi.csv").unwrap()];
    let mut start = truth.clone();
    start.effects.creep.grid = [0.01; 6];
    let opts = Options {
        free: GRID_NAMES.iter().map(|n| n.to_string()).collect(),
        conditions: None,
        ..Options::default()
    };
    let id = identify(&start, &est, &[], &opts).unwrap();
    let weights = id.params.effects.creep.grid;
    println!("{weights:?}, {} iterations", id.iterations);
    assert!((weights[2] - 0.06).abs() < 0.1 * 0.06, "{weights:?}");
    for (k, w) in weights.iter().enumerate().filter(|&(k, _)| k != 2) {
        assert!(*w < 0.05 * 0.06, "{}: {w}", GRID_NAMES[k]);
    }
    assert!(weights.contains(&0.0), "{weights:?}");
}

/// A held-out record is judged from a start found at the parameters the fit ended at
/// (book/src/identify.md, "The order of estimation"). A diagnosis's refit finds the records'
/// starts with the effect's states among the unknowns and fits again, in rounds that end on a
/// fit: before, the held-out record kept the start found before that last fit, a creep's
/// branches loaded for other weights, and the true family lost held-out fit it had earned (the
/// protocols' benchmark, `creep_two_times` on sines at 2 ms mid-run: −2.19 points, then +7.40
/// with the start found again). Creep in two branches at 1 and 3 s, both 4 s records from 1.3 s
/// into the drive, the spectrum's weights started at a quarter of them; finding the held-out
/// start again at the fitted parameters must gain it nothing (with the stale start it gained h1
/// 0.24 points).
#[test]
fn a_held_out_start_is_found_at_the_fitted_parameters() {
    use hasel_fmu::identify::conditions::{self, Choice, LagChoice, StartChoice};
    use hasel_fmu::model::effects::creep::GRID_NAMES;
    let mut truth = Params::default();
    truth.effects.creep.grid[3] = 0.04;
    truth.effects.creep.grid[4] = 0.04;
    let record = |name: &str, omega: f64, seed: u64| {
        let spec = Spec {
            t_end: 4.0,
            record_from: 1.3,
            ..Spec::paper(&truth, omega, Columns::Heights, 0.01, seed)
        };
        synth::experiment(&spec, name).unwrap()
    };
    let mut start = truth.clone();
    start.effects.creep.grid = [0.01; 6];
    let rtol = Options::default().rtol;
    // as a diagnosis hands a refit its records: the angles found at the start, mid-run
    let found_at_start = |mut e: Experiment| {
        let choice = Choice {
            start: StartChoice::Estimate,
            lag: LagChoice::Stated(0.0),
        };
        e.conditions = conditions::estimate(&start, &e, choice, (rtol, Weighting::Equal))
            .unwrap()
            .conditions;
        e
    };
    let est = [found_at_start(record(
        "w3pi.csv",
        3.0 * std::f64::consts::PI,
        3,
    ))];
    let val = [found_at_start(record("w11.csv", 11.0, 4))];
    let opts = Options {
        free: GRID_NAMES.iter().map(|n| n.to_string()).collect(),
        conditions: Some(Choice {
            start: StartChoice::Refined,
            lag: LagChoice::Stated(0.0),
        }),
        ..Options::default()
    };
    let id = identify(&start, &est, &val, &opts).unwrap();
    let judged = Experiment {
        conditions: id.conditions[1].conditions.clone(),
        ..val[0].clone()
    };
    let again = conditions::estimate(
        &id.params,
        &judged,
        opts.conditions.unwrap(),
        (rtol, opts.weighting),
    )
    .unwrap();
    let refound = Experiment {
        conditions: again.conditions,
        ..val[0].clone()
    };
    let fit_of = |e: &Experiment| fits(e, &simulate(&id.params, e, rtol).unwrap()).fits;
    let (reported, best) = (&id.validation[0].fits, fit_of(&refound));
    assert_eq!(
        reported,
        &fit_of(&judged),
        "the reported fit is the one under its conditions"
    );
    for ((name, r), (_, b)) in reported.iter().zip(&best) {
        println!("{name}: reported {r:.3}, start found again {b:.3}");
        assert!(
            b - r < 0.01,
            "{name}: held-out {r:.3} %, {b:.3} % from a start found again"
        );
    }
}

/// The default bounds are around the caller's start in every fit (book/src/identify.md, "How `hasel
/// identify` estimates": [start/20, start·20] for a positive parameter). `identify` fits, finds the
/// records' conditions at the fit (here a sensor's 5 ms lag) and fits again from where the first
/// fit ended; that second fit took its bounds around the first's end, so a damping the data push
/// past 20 times its start went on to 60 times it. From a device whose actuator 1 is damped 60
/// times the table's, `b_1` ends at its bound, 20 times its start.
#[test]
fn the_default_bounds_stay_around_the_callers_start_in_every_fit() {
    use hasel_fmu::identify::synth::Sensor;
    let start = Params::default();
    let b_start = start.get("b_1").unwrap();
    let mut truth = start.clone();
    truth.set("b_1", 60.0 * b_start).unwrap();
    let spec = Spec {
        sensor: Sensor {
            lag: 0.005,
            quantum: 0.0,
        },
        ..heights_at_3pi(&truth, 5)
    };
    let est = [synth::experiment(&spec, "w3pi.csv").unwrap()];
    let opts = Options {
        free: vec!["b_1".to_string()],
        ..Options::default()
    };
    let id = identify(&start, &est, &[], &opts).unwrap();
    // a lag found after the first fit: the conditions moved, and a second fit ran
    let lag = id.conditions[0].conditions.lag;
    assert!(lag > 0.0, "{lag}");
    let b = id.params.get("b_1").unwrap();
    assert_eq!(b, 20.0 * b_start, "b_1 = {:.2} × its start", b / b_start);
}
