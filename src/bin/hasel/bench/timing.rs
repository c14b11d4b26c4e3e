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
