//! Timing shared by the benchmarks.

use std::time::{Duration, Instant};

/// The fastest wall time of `repeat` runs of `f` (at least one), and the last run's result.
pub fn best<T>(repeat: usize, mut f: impl FnMut() -> T) -> (Duration, T) {
    let mut out = None;
    let mut fastest = Duration::MAX;
    for _ in 0..repeat.max(1) {
        let start = Instant::now();
        let r = f();
        fastest = fastest.min(start.elapsed());
        out = Some(r);
    }
    (fastest, out.expect("at least one repetition"))
}

/// The fastest wall time of `repeat` runs of `f` (at least one), each after `before`, which is
/// not timed; the first error ends the runs.
pub fn best_after<E>(
    repeat: usize,
    mut before: impl FnMut(),
    mut f: impl FnMut() -> Result<(), E>,
) -> Result<Duration, E> {
    let mut fastest = Duration::MAX;
    for _ in 0..repeat.max(1) {
        before();
        let start = Instant::now();
        f()?;
        fastest = fastest.min(start.elapsed());
    }
    Ok(fastest)
}
