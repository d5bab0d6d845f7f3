//! `myoslice sweep`: parameter studies, run by the Python package (Ray, pyarrow).

use std::path::PathBuf;
use std::process::Command;

use anyhow::{Context, Result, bail};
use clap::Args;

/// Arguments of `myoslice sweep` (passed on to `python -m myoslice sweep`).
#[derive(Args)]
pub struct SweepArgs {
    /// Sweep file (TOML): a base scenario and the fields that vary.
    sweep_file: PathBuf,
    /// Output folder: results.parquet, runs/, sweep.json.
    #[arg(long)]
    out: PathBuf,
    /// Ray cluster to join (default: a local Ray started for the sweep).
    #[arg(long)]
    address: Option<String>,
    /// CPUs of the local Ray (default: all).
    #[arg(long)]
    workers: Option<usize>,
    /// No Ray: one run after another in one process.
    #[arg(long)]
    serial: bool,
    /// Run the runs recorded as failed again.
    #[arg(long)]
    retry_failed: bool,
    /// Run at most this many new runs, then stop.
    #[arg(long)]
    limit: Option<usize>,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

fn python() -> String {
    std::env::var("MYOSLICE_PYTHON").unwrap_or_else(|_| "python3".into())
}

/// Runs the sweep through the Python package, after checking that it can be imported.
pub fn run(a: &SweepArgs) -> Result<()> {
    let py = python();
    let probe = Command::new(&py)
        .args(["-c", "import myoslice.sweep, pyarrow"])
        .output()
        .with_context(|| format!("starting {py} (set MYOSLICE_PYTHON to another interpreter)"))?;
    if !probe.status.success() {
        bail!(
            "myoslice sweep runs on the Python package, which {py} cannot import:\n{}\n\
             install it with `pip install myoslice ray pyarrow` (or set MYOSLICE_PYTHON to \
             the interpreter that has it)",
            String::from_utf8_lossy(&probe.stderr).trim()
        );
    }
    let mut cmd = Command::new(&py);
    cmd.args(["-m", "myoslice", "sweep"])
        .arg(&a.sweep_file)
        .arg("--out")
        .arg(&a.out);
    if let Some(addr) = &a.address {
        cmd.args(["--address", addr]);
    }
    if let Some(w) = a.workers {
        cmd.args(["--workers", &w.to_string()]);
    }
    if let Some(n) = a.limit {
        cmd.args(["--limit", &n.to_string()]);
    }
    for (on, flag) in [
        (a.serial, "--serial"),
        (a.retry_failed, "--retry-failed"),
        (a.quiet, "--quiet"),
    ] {
        if on {
            cmd.arg(flag);
        }
    }
    let status = cmd
        .status()
        .with_context(|| format!("running {py} -m myoslice sweep"))?;
    if !status.success() {
        // The Python side printed what went wrong.
        std::process::exit(status.code().unwrap_or(1));
    }
    Ok(())
}
