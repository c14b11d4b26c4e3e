//! Many instances in several threads: no shared state.

use super::*;

fn simulate(tau: f64, n: usize) -> Vec<u64> {
    let fmu = Fmu::in_init(0.0);
    assert_eq!(fmu.set(TAU, tau), Fmi2Status::Ok);
    assert_eq!(
        unsafe { toy::fmi2ExitInitializationMode(fmu.c) },
        Fmi2Status::Ok
    );
    (0..n)
        .map(|i| {
            assert_eq!(fmu.set(U, (i % 7) as f64), Fmi2Status::Ok);
            assert_eq!(fmu.step(i as f64 * 1e-3, 1e-3), Fmi2Status::Ok);
            fmu.get(Y).to_bits()
        })
        .collect()
}

#[test]
fn instances_in_threads_are_independent() {
    let taus: Vec<f64> = (1..=8).map(|k| 0.01 * k as f64).collect();
    let serial: Vec<Vec<u64>> = taus.iter().map(|&tau| simulate(tau, 2000)).collect();
    let parallel: Vec<Vec<u64>> = std::thread::scope(|s| {
        let handles: Vec<_> = taus
            .iter()
            .map(|&tau| {
                s.spawn(move || {
                    // two instances per thread, interleaved
                    let a = simulate(tau, 2000);
                    let b = simulate(tau, 2000);
                    assert_eq!(a, b);
                    a
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    assert_eq!(serial, parallel);
}
