//! Helpers any FMI shell needs whatever the version: the message of a caught panic, and the
//! comparison of an importer's communication point with the FMU's time.

/// The message of a caught panic.
pub fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    match (
        payload.downcast_ref::<&str>(),
        payload.downcast_ref::<String>(),
    ) {
        (Some(s), _) => (*s).to_string(),
        (_, Some(s)) => s.clone(),
        _ => "(no message)".into(),
    }
}

/// Whether the importer's time `tc` and the FMU's time `t` agree up to rounding: always within
/// 1e-12 relative, and within up to 1e-9 relative as long as that is below a thousandth of the
/// step `h` (an importer that accumulates `t += h`); a skipped or repeated step never passes.
pub fn same_time(t: f64, tc: f64, h: f64) -> bool {
    const RTOL: f64 = 1e-12;
    let scale = t.abs().max(tc.abs());
    (t - tc).abs() <= (RTOL * scale).max((1e3 * RTOL * scale).min(1e-3 * h))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accumulated_rounding_passes_a_skipped_step_does_not() {
        let mut tc = 0.0;
        for _ in 0..10_000 {
            tc += 1e-3;
        }
        assert!(same_time(10.0, tc, 1e-3));
        assert!(!same_time(10.0, 10.0 - 1e-3, 1e-3));
        assert!(!same_time(0.0, 1e-3, 1e-3));
    }

    #[test]
    fn panic_messages_of_both_kinds() {
        let text = std::panic::catch_unwind(|| panic!("plain")).unwrap_err();
        assert_eq!(panic_message(&*text), "plain");
        let formatted = std::panic::catch_unwind(|| panic!("x = {}", 1)).unwrap_err();
        assert_eq!(panic_message(&*formatted), "x = 1");
    }
}
