//! What each reader of a user's file promises, as one check per fuzz target: the fuzz targets
//! (tests/fuzz/fuzz_targets, libFuzzer) and their replay in the ordinary suite
//! (tests/fuzz_replay.rs, every file of tests/fuzz/corpus/<target>/) call the same function.
//!
//! A check returns normally when the reader gave a value that keeps its promises or an error
//! that names the file; anything else (a panic, a broken promise) panics, which libFuzzer
//! reports as a crash and the replay as a failed test. Time and memory per input are bounded by
//! libFuzzer's -timeout and -rss_limit_mb (ci/fuzz.sh).

use std::path::Path;

use hasel_fmu::fmi_common::fmu_state::{Format, Snapshot, seal};
use hasel_fmu::fmi_common::model_api::{FmuCore, InstanceKind};
use hasel_fmu::fmi2::Fmi2;
use hasel_fmu::fmi3::Fmi3;
use hasel_fmu::fmu::HaselCore;
use hasel_fmu::fmu::inverse::InverseCore;
use hasel_fmu::identify::experiment::Experiment;
use hasel_fmu::io::csv::{Table, format_row};
use hasel_fmu::io::file::FileError;
use hasel_fmu::io::{input_file, params_file};
use hasel_fmu::model::Params;
use hasel_fmu::simulation::Interpolation;
use hasel_fmu::uncertainty::Posterior;

/// The file name every reader is given, which each error must name first.
const NAME: &str = "fuzz.in";

/// A check: the fuzzer's bytes in, a panic for a broken promise.
pub type Check = fn(&[u8]);

/// The fuzz targets and their checks, for the replay.
pub const TARGETS: &[(&str, Check)] = &[
    ("csv_input", csv_input),
    ("csv_experiment", csv_experiment),
    ("params_toml", params_toml),
    ("heights_toml", heights_toml),
    ("identification_json", identification_json),
    ("fmi2_state", fmi2_state),
    ("fmi3_state", fmi3_state),
];

/// The bytes as the text a reader gets (`read_to_string` refuses other bytes before any
/// reader sees them).
fn text(data: &[u8]) -> Option<&str> {
    std::str::from_utf8(data).ok()
}

/// An error of a file reader: it names the file first, then says something.
fn named(e: &FileError) {
    let shown = e.to_string();
    assert!(
        shown.starts_with(NAME) && e.message.trim().len() > 3,
        "unclear error: {shown}"
    );
}

/// A table read, then written by the CSV writer's row formatter and read again: the same
/// header and the same numbers, bit for bit.
fn table(text: &str) -> Option<Table> {
    let table = match Table::parse(Path::new(NAME), text) {
        Ok(t) => t,
        Err(e) => {
            named(&e);
            return None;
        }
    };
    let mut written = table.header.join(",").into_bytes();
    written.push(b'\n');
    let mut number = zmij::Buffer::new();
    for row in &table.rows {
        format_row(&mut written, &mut number, row);
    }
    let back = Table::parse(Path::new(NAME), std::str::from_utf8(&written).unwrap())
        .unwrap_or_else(|e| panic!("the written table does not read back: {e}"));
    assert_eq!(back.header, table.header);
    let bits = |t: &Table| -> Vec<Vec<u64>> {
        t.rows
            .iter()
            .map(|r| r.iter().map(|v| v.to_bits()).collect())
            .collect()
    };
    assert_eq!(
        bits(&back),
        bits(&table),
        "numbers changed in the round trip"
    );
    Some(table)
}

/// `simulate --input FILE`: the first byte picks the interpolation, the rest is the file. An
/// input read gives a finite voltage at every sample time.
pub fn csv_input(data: &[u8]) {
    let Some((&pick, rest)) = data.split_first() else {
        return;
    };
    let Some(table) = text(rest).and_then(table) else {
        return;
    };
    let how = [
        Interpolation::ZeroOrderHold,
        Interpolation::Linear,
        Interpolation::Pchip,
        Interpolation::Spline,
        Interpolation::Measured,
    ][usize::from(pick) % 5];
    match input_file::from_table(&table, how) {
        Ok(input) => {
            for t in table.column("t").unwrap() {
                let u = input.value(t);
                assert!(
                    u.iter().all(|v| v.is_finite()),
                    "{how:?} input at t = {t}: {u:?}"
                );
            }
        }
        Err(e) => named(&e),
    }
}

/// The experiment files of `identify` and `diagnose`. An experiment read has a finite
/// command at every sample, every channel as long as its times, and keeps every other row.
pub fn csv_experiment(data: &[u8]) {
    let Some(table) = text(data).and_then(table) else {
        return;
    };
    match Experiment::from_table(&table) {
        Ok(e) => {
            for &t in &e.t {
                assert!(
                    e.input.value(t).iter().all(|v| v.is_finite()),
                    "command at t = {t}"
                );
            }
            assert!(e.channels.iter().all(|(_, v)| v.len() == e.t.len()));
            let keep: Vec<bool> = (0..e.t.len()).map(|k| k % 2 == 0).collect();
            if let Err(e) = e.rows(&keep) {
                named(&e);
            }
        }
        Err(e) => named(&e),
    }
}

/// Parameter files (`--params`): parameters read are written by the writer and read back the
/// same.
pub fn params_toml(data: &[u8]) {
    let Some(text) = text(data) else {
        return;
    };
    match params_file::parse(Path::new(NAME), text, Params::default()) {
        Ok(p) => {
            let back = params_file::parse(
                Path::new(NAME),
                &params_file::to_toml(&p),
                Params::default(),
            )
            .unwrap_or_else(|e| panic!("written parameters do not read back: {e}"));
            assert_eq!(back, p);
        }
        Err(e) => named(&e),
    }
}

/// Start files (`--start FILE`): three finite heights within ±Lv/2, which read back the same
/// when written as TOML.
pub fn heights_toml(data: &[u8]) {
    let Some(text) = text(data) else {
        return;
    };
    let params = Params::default();
    match params_file::parse_heights(Path::new(NAME), text, &params) {
        Ok(h) => {
            assert!(h.iter().all(|v| v.is_finite() && v.abs() < 0.5 * params.lv));
            let written = format!("h1 = {:?}\nh2 = {:?}\nh3 = {:?}\n", h[0], h[1], h[2]);
            let back = params_file::parse_heights(Path::new(NAME), &written, &params).unwrap();
            assert_eq!(back.map(f64::to_bits), h.map(f64::to_bits));
        }
        Err(e) => named(&e),
    }
}

/// `identification.json` (`simulate --uncertainty`, the studies): a posterior read draws
/// parameter sets, each valid or refused with a reason.
pub fn identification_json(data: &[u8]) {
    let Some(text) = text(data) else {
        return;
    };
    match Posterior::parse(Path::new(NAME), text) {
        Ok(post) => {
            assert_eq!(post.mean.len(), post.names.len());
            for k in 0..4 {
                if let Ok(p) = post.draw(1, k) {
                    assert!(p.validate().is_ok());
                }
            }
        }
        Err(e) => assert!(e.to_string().starts_with(NAME), "unclear error: {e}"),
    }
}

/// The token the states of the state targets belong to (their seeds carry it).
const TOKEN: &str = "fuzz";

/// A serialized FMU state fed to the deserializer of format `V` for a core of type `M`: byte 0
/// picks the instance kind (bit 0) and whether the rest gets a valid checksum appended (bit 1,
/// so that the fuzzer reaches the record behind the check). A state read is written again
/// and reads back to the same bytes.
fn state<V: Format, M: FmuCore>(data: &[u8]) {
    let Some((&flags, rest)) = data.split_first() else {
        return;
    };
    let kind = if flags & 1 == 0 {
        InstanceKind::CoSimulation
    } else {
        InstanceKind::ModelExchange
    };
    let Ok(core) = M::instantiate(kind, None) else {
        return; // the inverse FMU has no Model Exchange
    };
    let bytes = match rest.split_first_chunk::<8>() {
        Some((magic, record)) if flags & 2 != 0 => seal(magic, record),
        _ => rest.to_vec(),
    };
    match V::from_bytes(&bytes, TOKEN, kind, &core) {
        Ok(snapshot) => {
            let written = V::to_bytes(&snapshot);
            let again: Snapshot<M, V::Phase> = V::from_bytes(&written, TOKEN, kind, &core)
                .unwrap_or_else(|e| panic!("a written state does not read back: {e}"));
            assert!(
                V::to_bytes(&again) == written,
                "the state changed in the round trip"
            );
        }
        Err(e) => assert!(e.len() > 3, "unclear error: {e}"),
    }
}

/// FMI 2.0 states (`fmi2DeSerializeFMUstate`) of both FMUs: bit 2 of byte 0 picks the inverse's.
pub fn fmi2_state(data: &[u8]) {
    if data.first().is_some_and(|b| b & 4 != 0) {
        state::<Fmi2, InverseCore>(data)
    } else {
        state::<Fmi2, HaselCore>(data)
    }
}

/// FMI 3.0 states (`fmi3DeserializeFMUState`) of the platform.
pub fn fmi3_state(data: &[u8]) {
    state::<Fmi3, HaselCore>(data)
}
