//! `myoslice labels FILE`: every label of a segmentation tool's list with the structure
//! it maps to; unknown names listed, and an error unless taken as fat or background or
//! named in the user's names file.

use std::process::{Command, Output};

fn labels(file: &std::path::Path, extra: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_myoslice"))
        .arg("labels")
        .arg(file)
        .args(extra)
        .output()
        .unwrap_or_else(|e| panic!("myoslice runs: {e}"))
}

#[test]
fn the_labels_command_shows_each_mapping_and_refuses_unknown_names_unless_asked() {
    let dir = std::env::temp_dir().join(format!("myoslice-labels-cmd-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
    let file = dir.join("seg.txt");
    std::fs::write(
        &file,
        "# ITK-SnAP Label Description File\n0 0 0 0 0 0 0 \"Clear Label\"\n\
         1 1 1 1 1 1 1 \"Biceps femoris long head\"\n2 1 1 1 1 1 1 \"Os coxae\"\n\
         3 1 1 1 1 1 1 \"Sciatic nerve\"\n",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let out = labels(&file, &[]);
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert!(!out.status.success(), "{stdout}");
    for want in [
        "biceps_femoris_long",
        "hip_bone",
        "(not known)",
        "1 of 4 labels not known: Sciatic nerve",
    ] {
        assert!(stdout.contains(want), "{want}: {stdout}");
    }
    assert!(stderr.contains("label 3 'Sciatic nerve'"), "{stderr}");
    for option in ["fat", "ignore"] {
        let out = labels(&file, &["--unmapped", option]);
        assert!(
            out.status.success(),
            "{option}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    // A names file says what the nerve is, and renames the hamstring.
    let names = dir.join("names.toml");
    std::fs::write(
        &names,
        "[map]\n\"Sciatic nerve\" = \"fat\"\n\"Biceps femoris long head\" = \"semitendinosus\"\n",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let out = labels(&file, &["--names", &names.display().to_string()]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}");
    assert!(
        stdout.contains("semitendinosus") && !stdout.contains("biceps_femoris_long"),
        "{stdout}"
    );
    assert!(!stdout.contains("not known"), "{stdout}");
    std::fs::write(&names, "[map]\n\"Sciatic nerve\" = \"nervus\"\n")
        .unwrap_or_else(|e| panic!("{e}"));
    let out = labels(&file, &["--names", &names.display().to_string()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("map.\"Sciatic nerve\" = \"nervus\""),
        "{stderr}"
    );
    let out = labels(&dir.join("absent.txt"), &[]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("absent.txt"));
    std::fs::remove_dir_all(dir).unwrap_or_else(|e| panic!("{e}"));
}
