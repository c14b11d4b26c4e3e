//! The committed fuzz corpora (tests/fuzz/corpus/<target>/, minimized by `cargo fuzz cmin`)
//! replayed through the checks of the fuzz targets in the ordinary build: what a campaign
//! (`bash ci/fuzz.sh`) once found or reached stays checked by every `cargo test`.

#[path = "fuzz/checks.rs"]
mod checks;

use std::path::Path;

#[test]
fn every_corpus_replays_through_its_check() {
    for (target, check) in checks::TARGETS {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/fuzz/corpus")
            .join(target);
        let files = std::fs::read_dir(&dir)
            .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
            .map(|f| f.unwrap().path())
            .collect::<Vec<_>>();
        assert!(!files.is_empty(), "{target}: empty corpus");
        for file in files {
            let data = std::fs::read(&file).unwrap();
            if std::panic::catch_unwind(|| check(&data)).is_err() {
                panic!("{target}: {} fails its check", file.display());
            }
        }
    }
}
