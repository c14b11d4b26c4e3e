use std::path::Path;

use serde_json::{Value, json};

use super::bands::{self, Settings, quantile};
use super::*;
use crate::simulation::Input;

/// An identification of Kb_1 and b_1 (ln coordinates) and tau0_1 (linear), with a held
/// combination ln Kb_1 - ln b_1 when `held`.
fn identification(held: bool) -> Value {
    let p = Params::default();
    let (kb, b) = (p.get("Kb_1").unwrap(), p.get("b_1").unwrap());
    let mut params = serde_json::Map::new();
    for d in crate::model::params::parameters() {
        let est = ["Kb_1", "b_1", "tau0_1"].contains(&d.name);
        params.insert(
            d.name.into(),
            json!({"value": (d.get)(&p), "prior": (d.get)(&p), "free": est, "estimated": est,
                   "std_error": null, "ci95": null}),
        );
    }
    // variances: 0.01² in ln Kb_1 and ln b_1, correlated 0.5 (or 1 along (1,1) when held), 1e-4²
    // in tau0_1
    let (s, r) = (0.01_f64, if held { 1.0 } else { 0.5 });
    let matrix = vec![
        vec![s * s, r * s * s, 0.0],
        vec![r * s * s, s * s, 0.0],
        vec![0.0, 0.0, 1e-8],
    ];
    let _ = (kb, b);
    json!({
        "parameters": params,
        "held_combinations": if held { json!([{"Kb_1": 1.0, "b_1": -1.0}]) } else { json!([]) },
        "covariance": {"parameters": ["Kb_1", "b_1", "tau0_1"], "coordinates": ["ln", "ln", "linear"],
                       "matrix": matrix},
    })
}

fn posterior(v: &Value) -> Result<Posterior, UncertaintyError> {
    Posterior::from_json(Path::new("fit/identification.json"), v)
}

#[test]
fn draws_follow_the_covariance_in_the_fit_coordinates() {
    let p = posterior(&identification(false)).unwrap();
    assert_eq!(p.rank(), 3);
    let n = 4000;
    let xs: Vec<Vec<f64>> = (0..n).map(|k| p.draw_coordinates(7, k)).collect();
    let mean = |i: usize| xs.iter().map(|x| x[i]).sum::<f64>() / n as f64;
    let cov = |i: usize, j: usize| {
        let (mi, mj) = (mean(i), mean(j));
        xs.iter().map(|x| (x[i] - mi) * (x[j] - mj)).sum::<f64>() / (n - 1) as f64
    };
    for i in 0..3 {
        assert!((mean(i) - p.mean[i]).abs() < 4.0 * cov(i, i).sqrt() / (n as f64).sqrt());
    }
    assert!((cov(0, 0) / 1e-4 - 1.0).abs() < 0.1, "{}", cov(0, 0));
    assert!((cov(0, 1) / cov(0, 0) - 0.5).abs() < 0.05);
    assert!((cov(2, 2) / 1e-8 - 1.0).abs() < 0.1);
    // the parameters: ln coordinates give positive values around the identified ones
    let q = p.draw(7, 3).unwrap();
    let x = p.draw_coordinates(7, 3);
    assert_eq!(q.get("Kb_1").unwrap(), x[0].exp());
    assert_eq!(q.get("tau0_1").unwrap(), x[2]);
    assert_eq!(q.get("K_1").unwrap(), p.center.get("K_1").unwrap());
}

#[test]
fn a_sample_depends_on_the_seed_and_its_index_alone() {
    let p = posterior(&identification(false)).unwrap();
    assert_eq!(p.draw_coordinates(3, 10), p.draw_coordinates(3, 10));
    assert_ne!(p.draw_coordinates(3, 10), p.draw_coordinates(3, 11));
    assert_ne!(p.draw_coordinates(3, 10), p.draw_coordinates(4, 10));
}

#[test]
fn held_combinations_stay_held() {
    let p = posterior(&identification(true)).unwrap();
    assert_eq!(p.rank(), 2);
    for k in 0..200 {
        let x = p.draw_coordinates(1, k);
        let along = (x[0] - p.mean[0]) - (x[1] - p.mean[1]);
        assert!(along.abs() < 1e-15, "{along}");
        assert!((x[0] - p.mean[0]).abs() > 0.0);
    }
    // a covariance that is not singular along a held combination is refused
    let mut v = identification(false);
    v["held_combinations"] = json!([{"Kb_1": 1.0, "b_1": -1.0}]);
    let e = posterior(&v).unwrap_err().to_string();
    assert!(
        e.starts_with("fit/identification.json: covariance: variance")
            && e.contains("held_combinations[0]"),
        "{e}"
    );
}

#[test]
fn older_files_draw_from_errors_and_rounded_correlations() {
    let mut v = identification(true);
    v.as_object_mut().unwrap().remove("covariance");
    let d = Params::default();
    for (name, se) in [("Kb_1", 0.01), ("b_1", 0.01)] {
        let value = d.get(name).unwrap();
        v["parameters"][name]["std_error"] = json!(value * se);
    }
    v["parameters"]["tau0_1"]["std_error"] = json!(1e-4);
    v["correlation"] = json!({"parameters": ["Kb_1", "b_1", "tau0_1"],
                              "matrix": [[1.0, 0.9999, 0.0], [0.9999, 1.0, 0.0], [0.0, 0.0, 1.0]]});
    let p = posterior(&v).unwrap();
    assert_eq!(p.log, [true, true, false]);
    for k in 0..50 {
        let x = p.draw_coordinates(1, k);
        let along = (x[0] - p.mean[0]) - (x[1] - p.mean[1]);
        assert!(along.abs() < 1e-12, "{along}");
    }
}

#[test]
fn bad_files_are_refused_with_the_file_and_the_reason() {
    let msg = |v: Value| posterior(&v).unwrap_err().to_string();
    assert_eq!(
        msg(json!({})),
        "fit/identification.json: no \"parameters\" object: expected the identification.json of `hasel identify`"
    );
    let mut v = identification(false);
    v["parameters"]["nope"] = json!({"value": 1.0});
    assert_eq!(
        msg(v),
        "fit/identification.json: parameters.nope: unknown parameter"
    );
    let mut v = identification(false);
    v["parameters"]["Kb_1"]["value"] = json!(-1.0);
    assert!(msg(v).starts_with("fit/identification.json: parameters.Kb_1:"));
    let mut v = identification(false);
    v["covariance"]["matrix"][0][1] = json!(1.0);
    assert!(msg(v).contains("covariance.matrix: not symmetric at (2, 1)"));
    let mut v = identification(false);
    v["covariance"]["matrix"][0][0] = json!(-1.0);
    assert!(msg(v).contains("not positive semi-definite"));
    let mut v = identification(false);
    v["covariance"]["matrix"][2] = json!([0.0, "x", 0.0]);
    assert!(msg(v).contains("covariance.matrix row 3, column 2: expected a finite number"));
    let mut v = identification(false);
    v["covariance"]["coordinates"] = json!(["ln", "log", "linear"]);
    assert!(msg(v).contains("covariance.coordinates"));
    let mut v = identification(false);
    v["parameters"]["b_1"]["estimated"] = json!(false);
    assert!(msg(v).contains("covariance: b_1 is not an estimated parameter"));
    let mut v = identification(false);
    v["covariance"] = json!({"parameters": [], "coordinates": [], "matrix": []});
    assert!(msg(v).contains("covariance: no parameter to draw"));
    // as a fuzz campaign found it: rounded correlations over no parameter, nothing estimated
    let v = json!({"correlation": {"matrix": [], "parameters": []}, "parameters": {}});
    assert!(msg(v).contains("covariance: no parameter to draw"));
    let e = Posterior::read(Path::new("/nonexistent/identification.json")).unwrap_err();
    assert!(
        e.to_string()
            .starts_with("/nonexistent/identification.json: cannot read")
    );
}

#[test]
fn quantiles_interpolate_between_order_statistics() {
    let v = [1.0, 2.0, 3.0, 4.0, 5.0];
    assert_eq!(quantile(&v, 0.5), 3.0);
    assert_eq!(quantile(&v, 0.0), 1.0);
    assert_eq!(quantile(&v, 1.0), 5.0);
    assert_eq!(quantile(&v, 0.125), 1.5);
    assert_eq!(quantile(&[2.0, 4.0], 0.5), 3.0);
}

#[test]
fn bands_do_not_depend_on_the_number_of_threads() {
    let p = posterior(&identification(false)).unwrap();
    let input = Input::sine(60.0, 3.0 * std::f64::consts::PI);
    let settings = |threads| Settings {
        samples: 6,
        seed: 5,
        threads,
        t_end: 0.2,
        dt: 1e-2,
        rtol: 1e-6,
    };
    let one = bands::run(&p, &input, &settings(1), &|| {}).unwrap();
    let two = bands::run(&p, &input, &settings(3), &|| {}).unwrap();
    assert_eq!(one.to_csv(), two.to_csv());
    assert_eq!(one.draws, two.draws);
    assert!(one.failed.is_empty());
    assert_eq!(one.t.len(), 21);
    for k in 0..one.t.len() {
        for j in 0..6 {
            assert!(one.lower[k][j] <= one.median[k][j] && one.median[k][j] <= one.upper[k][j]);
        }
    }
    // a draw that breaks a parameter's rule fails alone; too few samples are refused
    let e = bands::run(
        &p,
        &input,
        &Settings {
            samples: 1,
            ..settings(1)
        },
        &|| {},
    )
    .unwrap_err();
    assert!(matches!(e, UncertaintyError::Setting(_)));
    let e = bands::run(
        &p,
        &input,
        &Settings {
            dt: 1e-12,
            ..settings(1)
        },
        &|| {},
    )
    .unwrap_err();
    assert!(e.to_string().contains("GB of outputs"), "{e}");
}
