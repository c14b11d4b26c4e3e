//! Helpers any FMI shell needs whatever the version: C strings and arrays received from the
//! importer, the debug-logging switch, the message of a caught panic, and the comparison of an importer's communication
//! point with the FMU's time.

use std::borrow::Cow;
use std::collections::HashSet;
use std::ffi::{CStr, CString, c_char};

/// A C string argument; `None` for NULL.
///
/// # Safety
/// `p` is NULL or a NUL-terminated string that outlives `'a`.
pub unsafe fn opt_str<'a>(p: *const c_char) -> Option<Cow<'a, str>> {
    (!p.is_null()).then(|| unsafe { CStr::from_ptr(p) }.to_string_lossy())
}

/// An input array of `n` elements; `None` if it is NULL although `n > 0`.
///
/// # Safety
/// `p` is NULL or points to `n` elements that outlive `'a`.
pub unsafe fn in_slice<'a, T>(p: *const T, n: usize) -> Option<&'a [T]> {
    match (n, p.is_null()) {
        (0, _) => Some(&[]),
        (_, true) => None,
        _ => Some(unsafe { std::slice::from_raw_parts(p, n) }),
    }
}

/// An output array of `n` elements; `None` if it is NULL although `n > 0`.
///
/// # Safety
/// `p` is NULL or points to `n` writable elements, used by no one else during `'a`.
pub unsafe fn out_slice<'a, T>(p: *mut T, n: usize) -> Option<&'a mut [T]> {
    match (n, p.is_null()) {
        (0, _) => Some(&mut []),
        (_, true) => None,
        _ => Some(unsafe { std::slice::from_raw_parts_mut(p, n) }),
    }
}

/// `text` as a C string for the importer's logger; an interior NUL, which would end it early,
/// is written as the escape `\0`.
pub fn c_string(text: &str) -> CString {
    CString::new(text.replace('\0', "\\0")).unwrap_or_default()
}

/// The debug-logging switch of `fmi2SetDebugLogging` / `fmi3SetDebugLogging`: on or off, for
/// all categories or some.
pub struct DebugLogging {
    on: bool,
    /// The categories switched; `None` means all.
    categories: Option<HashSet<String>>,
}

impl DebugLogging {
    pub fn new(on: bool) -> Self {
        DebugLogging {
            on,
            categories: None,
        }
    }

    /// Switches debug logging for `categories` (all when empty), which must be among `known`;
    /// the first unknown name is the error, and nothing changes then.
    pub fn set(&mut self, on: bool, categories: &[String], known: &[String]) -> Result<(), String> {
        if let Some(bad) = categories.iter().find(|c| !known.contains(c)) {
            return Err(bad.clone());
        }
        self.on = on;
        self.categories = (!categories.is_empty()).then(|| categories.iter().cloned().collect());
        Ok(())
    }

    /// Whether debug messages of `category` go out.
    pub fn enabled(&self, category: &str) -> bool {
        self.on
            && self
                .categories
                .as_ref()
                .is_none_or(|set| set.contains(category))
    }
}

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
