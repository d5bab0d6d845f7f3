//! The readers' fuzz corpus (`fuzz/corpus/<target>/`) and every crash the fuzzers found
//! (`fuzz/regressions/<target>/`), replayed on stable: each input is read without a
//! panic, and each seed of our own writing is accepted.

use std::path::{Path, PathBuf};

use myoslice::fuzz_targets::TARGETS;

fn fuzz_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz")
}

fn files(dir: &Path) -> Vec<PathBuf> {
    let mut out: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|r| r.filter_map(|e| e.ok().map(|e| e.path())).collect())
        .unwrap_or_default();
    out.retain(|p| p.is_file() && p.file_name().is_none_or(|n| n != ".keep"));
    out.sort();
    out
}

#[test]
fn every_kept_fuzz_input_is_read_without_a_panic() {
    for (name, target) in TARGETS {
        let corpus = files(&fuzz_dir().join("corpus").join(name));
        assert!(!corpus.is_empty(), "no corpus for the {name} target");
        let regressions = files(&fuzz_dir().join("regressions").join(name));
        for path in corpus.iter().chain(&regressions) {
            let data = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            // A panic here fails the test and names nothing: say which input first.
            eprintln!("{name}: {}", path.display());
            target(&data);
        }
    }
}

#[test]
fn the_seeds_of_each_target_are_accepted() {
    // Seeds are the files we wrote (their names say what they hold); the fuzzers' own
    // additions are named by their hash and may be refused.
    for (name, target) in TARGETS {
        for path in files(&fuzz_dir().join("corpus").join(name)) {
            let stem = path
                .file_name()
                .map(|n| n.to_string_lossy().to_string())
                .unwrap_or_default();
            let hashed = stem.len() == 40 && stem.chars().all(|c| c.is_ascii_hexdigit());
            if !hashed {
                let data = std::fs::read(&path).unwrap_or_else(|e| panic!("{e}"));
                assert!(
                    target(&data),
                    "{name}: the seed {} is refused",
                    path.display()
                );
            }
        }
    }
}
