//! Helpers for the end-to-end tests: locating the built binaries and reading images.
#![allow(clippy::unwrap_used)]

use std::path::{Path, PathBuf};
use std::process::Command;

/// The workspace root.
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Builds (if needed) and returns the path of a workspace binary, in the same profile as
/// the tests.
pub fn binary(package: &str, bin: &str) -> PathBuf {
    let profile = if cfg!(debug_assertions) {
        "debug"
    } else {
        "release"
    };
    let mut cmd = Command::new(env!("CARGO"));
    cmd.current_dir(root())
        .args(["build", "-q", "-p", package, "--bin", bin]);
    if profile == "release" {
        cmd.arg("--release");
    }
    let status = cmd.status().expect("cargo runs");
    assert!(status.success(), "building {bin} failed");
    let target =
        std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| root().join("target"), PathBuf::from);
    target.join(profile).join(bin)
}

/// A fresh temporary folder for one test.
pub fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("myoslice-e2e-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The number, or array of numbers, under `key` in a flat JSON object (the viewer's
/// capture metadata); empty when the key is absent or not numeric.
pub fn json_numbers(json: &str, key: &str) -> Vec<f32> {
    let pat = format!("\"{key}\":");
    let Some(at) = json.find(&pat) else {
        return Vec::new();
    };
    let rest = json[at + pat.len()..].trim_start();
    let body = match rest.strip_prefix('[') {
        Some(r) => r.split(']').next().unwrap_or(""),
        None => rest.split([',', '}']).next().unwrap_or(""),
    };
    body.split(',')
        .map_while(|v| v.trim().parse().ok())
        .collect()
}

/// An RGB image.
#[derive(Debug, Clone)]
pub struct Image {
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// RGB pixels, rows top to bottom.
    pub rgb: Vec<u8>,
}

/// Reads an 8-bit RGB or RGBA PNG.
pub fn read_png(path: &Path) -> Image {
    let f = std::fs::File::open(path).unwrap();
    let mut r = png::Decoder::new(std::io::BufReader::new(f))
        .read_info()
        .unwrap();
    let mut buf = vec![0; r.output_buffer_size().unwrap()];
    let info = r.next_frame(&mut buf).unwrap();
    let ch = match info.color_type {
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
        other => panic!("unexpected colour type {other:?}"),
    };
    let rgb = buf[..(info.width * info.height) as usize * ch]
        .chunks_exact(ch)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    Image {
        width: info.width,
        height: info.height,
        rgb,
    }
}
