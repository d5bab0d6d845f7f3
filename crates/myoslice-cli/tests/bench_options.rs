//! `myoslice bench`'s tissue options: bad values are refused with a message naming them,
//! before any case runs.

use std::process::{Command, Output};

fn bench(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_myoslice"))
        .arg("bench")
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("myoslice runs: {e}"))
}

fn refused_with(args: &[&str], message: &str) {
    let out = bench(args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{args:?} was accepted");
    assert!(stderr.contains(message), "{args:?}: {stderr}");
    // Nothing was timed: no table was printed.
    assert!(out.stdout.is_empty(), "{args:?} printed {:?}", out.stdout);
}

#[test]
fn a_bad_tissue_rate_or_iteration_count_is_refused_naming_it() {
    for rate in ["-5", "0", "NaN", "inf"] {
        refused_with(
            &["--only", "whole_leg", &format!("--tissue-rate={rate}")],
            "tissue.rate_hz",
        );
    }
    refused_with(
        &["--only", "whole_leg", "--tissue-iterations", "0"],
        "tissue.iterations",
    );
}

#[test]
fn tissue_options_without_the_whole_leg_case_are_refused() {
    refused_with(
        &["--only", "fat_kernel_840", "--tissue-rate", "10"],
        "apply to whole_leg_step",
    );
}
