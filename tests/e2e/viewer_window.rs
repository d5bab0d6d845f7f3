//! The interactive window itself, on a virtual X display (Xvfb) with the software
//! adapter: it opens on the phantom, simulates and presents frames, and closes cleanly.
//! Without any display it refuses with a message that points to the capture mode.
#![allow(clippy::unwrap_used)]

use std::process::Command;
use std::time::{Duration, Instant};

use myoslice_e2e::{binary, scratch};

/// `xvfb-run`, or `None` (loudly) when it is absent and `MYOSLICE_ALLOW_NO_XVFB=1` says
/// that is expected. Without that variable a missing Xvfb fails the test: the window must
/// never go untested silently.
fn xvfb_run() -> Option<std::path::PathBuf> {
    let found = std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .map(|p| p.join("xvfb-run"))
            .find(|p| p.is_file())
    });
    if found.is_none() {
        let msg = "xvfb-run not found (apt-get install xvfb xauth; scripts/test.sh does)";
        if std::env::var("MYOSLICE_ALLOW_NO_XVFB").as_deref() == Ok("1") {
            eprintln!("SKIPPED: {msg}");
            return None;
        }
        panic!("{msg}; set MYOSLICE_ALLOW_NO_XVFB=1 to skip the window test");
    }
    found
}

#[test]
fn the_window_opens_on_the_phantom_presents_frames_and_closes() {
    let viewer = binary("myoslice-viewer", "viewer");
    let Some(xvfb) = xvfb_run() else { return };
    let dir = scratch("window");
    let (out, err) = (dir.join("stdout.txt"), dir.join("stderr.txt"));
    let mut child = Command::new(xvfb)
        .args(["-a", "-s", "-screen 0 1600x1000x24"])
        .arg(&viewer)
        .args(["--exit-after-frames", "20"])
        // Only the virtual display: never a Wayland compositor of the machine running it.
        .env_remove("WAYLAND_DISPLAY")
        .stdout(std::fs::File::create(&out).unwrap())
        .stderr(std::fs::File::create(&err).unwrap())
        .spawn()
        .unwrap();
    // A window that never presents must fail the test, not hang it.
    let deadline = Instant::now() + Duration::from_secs(300);
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            panic!("the window did not present 20 frames within 300 s");
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    let stdout = std::fs::read_to_string(&out).unwrap();
    let stderr = std::fs::read_to_string(&err).unwrap();
    assert!(
        status.success(),
        "the window failed: {status}\n{stdout}\n{stderr}"
    );
    println!("{stdout}");
    assert!(
        stdout.contains("window: 20 frames"),
        "no frame report: {stdout}\n{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn without_a_display_the_window_refuses_and_points_to_the_capture_mode() {
    let viewer = binary("myoslice-viewer", "viewer");
    let o = Command::new(viewer)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "it should fail without a display");
    assert!(stderr.contains("--capture"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}
