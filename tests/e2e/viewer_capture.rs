//! The viewer's off-screen capture on the software adapter: size, coverage, colours and a
//! golden image of the rest pose.
#![allow(clippy::unwrap_used)]

use std::process::Command;

use myoslice_e2e::{Image, binary, json_numbers, read_png, root, scratch};

fn capture(args: &[&str], name: &str) -> Image {
    capture_to(args, &scratch(name).join("out.png"))
}

fn capture_to(args: &[&str], out: &std::path::Path) -> Image {
    let o = Command::new(binary("myoslice-viewer", "viewer"))
        .args(["--capture", out.to_str().unwrap()])
        .args(args)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "viewer failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    read_png(out)
}

const BACKGROUND: [u8; 3] = [36, 40, 46];

fn is_background(p: &[u8]) -> bool {
    p.iter()
        .zip(BACKGROUND)
        .all(|(a, b)| (i32::from(*a) - i32::from(b)).abs() <= 6)
}

/// Counts pixels of the leg (not background) that are blue-ish, red-ish and white-ish,
/// excluding the legend strip at the right edge.
fn classify(img: &Image) -> (usize, usize, usize, usize) {
    classify_where(img, |_, _| true)
}

/// As [`classify`], over the pixels (x, y) that `keep` accepts.
fn classify_where(img: &Image, keep: impl Fn(f32, f32) -> bool) -> (usize, usize, usize, usize) {
    let (mut leg, mut blue, mut red, mut white) = (0, 0, 0, 0);
    let legend_x = (img.width as f32 * 0.9) as u32;
    for y in 0..img.height {
        for x in (0..legend_x).filter(|&x| keep(x as f32, y as f32)) {
            let i = 3 * (y * img.width + x) as usize;
            let p = &img.rgb[i..i + 3];
            if is_background(p) {
                continue;
            }
            leg += 1;
            let (r, g, b) = (i32::from(p[0]), i32::from(p[1]), i32::from(p[2]));
            if b > r + 40 && b > g + 20 {
                blue += 1;
            } else if r > 120 && r > g + 40 && r > b + 40 {
                red += 1;
            } else if r > 190 && g > 190 && b > 190 {
                white += 1;
            }
        }
    }
    (leg, blue, red, white)
}

#[test]
fn a_capture_has_the_requested_size_and_the_leg_fills_a_plausible_part_of_it() {
    let img = capture(
        &["--width", "320", "--height", "240", "--color", "none"],
        "size",
    );
    assert_eq!((img.width, img.height), (320, 240));
    let (leg, ..) = classify(&img);
    let frac = leg as f64 / f64::from(320 * 240);
    assert!(
        (0.05..0.6).contains(&frac),
        "leg covers {frac:.3} of the frame"
    );
}

#[test]
fn area_colours_after_a_flexion_show_growth_and_shrinkage_and_none_shows_neither() {
    let args = [
        "--width",
        "480",
        "--height",
        "360",
        "--preset",
        "flexion",
        "--time",
        "0.12",
        "--camera",
        "medial",
        "--skin-opacity",
        "1",
        "--layers",
        "skin",
    ];
    let dir = scratch("area");
    let meta = dir.join("meta.json");
    let area = capture_to(
        &[
            &args[..],
            &["--color", "area", "--meta", meta.to_str().unwrap()],
        ]
        .concat(),
        &dir.join("out.png"),
    );
    // Where the knee is in the picture, as the capture reports it.
    let json = std::fs::read_to_string(&meta).unwrap();
    let number = |key: &str| json_numbers(&json, key);
    let (knee, px_per_m) = (number("knee_px"), number("px_per_m")[0]);
    assert_eq!(knee.len(), 2, "{json}");
    assert!(
        number("knee_angle_deg")[0] > 20.0,
        "the knee has flexed: {json}"
    );
    let dist_m = |x: f32, y: f32| (x - knee[0]).hypot(y - knee[1]) / px_per_m;
    // Near the knee (10 cm): the surface grew somewhere and shrank somewhere.
    let (near, blue, red, _) = classify_where(&area, |x, y| dist_m(x, y) < 0.10);
    assert!(
        blue > 30,
        "blue-ish (grown) pixels near the knee: {blue} of {near}"
    );
    assert!(
        red > 30,
        "red-ish (shrunk) pixels near the knee: {red} of {near}"
    );
    // Away from it (beyond 15 cm) thigh and shank are nearly unchanged: white-ish.
    let (far, blue, red, white) = classify_where(&area, |x, y| dist_m(x, y) > 0.15);
    assert!(far > 1000, "the leg away from the knee: {far} pixels");
    assert!(
        white * 4 > far * 3 && (blue + red) * 100 < far * 3,
        "away from the knee: white {white}, blue {blue}, red {red} of {far}"
    );
    let none = capture(&[&args[..], &["--color", "none"]].concat(), "none");
    let (leg, blue, red, _) = classify(&none);
    assert!(
        blue < leg / 200 && red < leg / 200,
        "no metric colours expected: blue {blue}, red {red} of {leg}"
    );
}

#[test]
fn the_rest_pose_matches_its_golden_image() {
    let args = [
        "--width", "320", "--height", "240", "--camera", "front", "--color", "none",
    ];
    let golden_path = root().join("tests/golden/rest_front_320x240.png");
    if std::env::var("MYOSLICE_UPDATE_GOLDEN").as_deref() == Ok("1") {
        capture_to(&args, &golden_path);
    }
    let img = capture(&args, "golden");
    let golden = read_png(&golden_path);
    assert_eq!((golden.width, golden.height), (img.width, img.height));
    // Compared where either image shows the leg: the background would hide a difference.
    let (mut leg, mut silhouette, mut sum) = (0usize, 0usize, 0.0f64);
    for (a, b) in img.rgb.chunks_exact(3).zip(golden.rgb.chunks_exact(3)) {
        let (ba, bb) = (is_background(a), is_background(b));
        if ba && bb {
            continue;
        }
        leg += 1;
        silhouette += usize::from(ba != bb);
        sum += a
            .iter()
            .zip(b)
            .map(|(x, y)| f64::from((i32::from(*x) - i32::from(*y)).abs()))
            .sum::<f64>()
            / 3.0;
    }
    assert!(leg > 1000, "only {leg} leg pixels");
    let mean = sum / leg as f64;
    let outline = silhouette as f64 / leg as f64;
    assert!(
        mean < 8.0 && outline < 0.03,
        "leg pixels differ from the golden image by {mean:.2} (of 255) on average; \
         {:.1} % of them are leg in one image and background in the other",
        100.0 * outline
    );
}

#[test]
fn bad_input_fails_with_a_clear_message() {
    let viewer = binary("myoslice-viewer", "viewer");
    let dir = scratch("bad");
    let out = dir.join("x.png");
    let cases: [(&[&str], &str); 4] = [
        (
            &["--scenario", "/nonexistent/scenario.toml"],
            "/nonexistent/scenario.toml",
        ),
        (
            &[
                "--volume",
                "/nonexistent/v.nii.gz",
                "--labels",
                "/nonexistent/l.json",
            ],
            "does not exist",
        ),
        (&["--color", "rainbow"], "rainbow"),
        (&["--camera", "sky"], "sky"),
    ];
    for (args, needle) in cases {
        let o = Command::new(&viewer)
            .args(["--capture", out.to_str().unwrap()])
            .args(args)
            .output()
            .unwrap();
        assert!(!o.status.success(), "{args:?} should fail");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?} panicked: {err}");
    }
    let bad = dir.join("broken.toml");
    std::fs::write(&bad, "[simulation]\nduration_s = 1\nwhoops = 2\n").unwrap();
    let o = Command::new(&viewer)
        .args([
            "--capture",
            out.to_str().unwrap(),
            "--scenario",
            bad.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("whoops"), "{err}");
}
