//! The threads the core's parallel loops run on, per process.
//!
//! Rayon's global pool does not survive `fork`: a child (Gymnasium's `AsyncVectorEnv`,
//! `multiprocessing` with its default start method on Linux) inherits the pool's state but
//! not its threads, and its first parallel loop waits forever. So every call into the
//! core that may run in parallel goes through [`detach`]: in the process that imported
//! the module it runs on the global pool (no cost added to a call), in a forked child on
//! a pool of the child's own.

use std::sync::{Arc, Mutex, OnceLock};

use pyo3::marker::Ungil;
use pyo3::prelude::*;

/// The process that imported the module (a forked child inherits the value, not the pid).
static ORIGIN: OnceLock<u32> = OnceLock::new();

/// Notes the importing process; called by the module's initialisation.
pub(crate) fn note_origin() {
    ORIGIN.get_or_init(std::process::id);
}

static POOL: Mutex<Option<(u32, Arc<rayon::ThreadPool>)>> = Mutex::new(None);

fn pool() -> Option<Arc<rayon::ThreadPool>> {
    let pid = std::process::id();
    let mut slot = POOL.lock().unwrap_or_else(|e| e.into_inner());
    match slot.as_ref() {
        Some((owner, p)) if *owner == pid => Some(p.clone()),
        _ => {
            // A parent's pool (after fork) has no threads here: leave it alone, never
            // drop it, and build this process's own.
            if let Some(old) = slot.take() {
                std::mem::forget(old);
            }
            let p = Arc::new(rayon::ThreadPoolBuilder::new().build().ok()?);
            *slot = Some((pid, p.clone()));
            Some(p)
        }
    }
}

/// Runs `f` with the GIL released, on threads that exist in this process (see the
/// module's docs).
pub(crate) fn detach<T, F>(py: Python<'_>, f: F) -> T
where
    F: Ungil + FnOnce() -> T + Send,
    T: Ungil + Send,
{
    if ORIGIN.get().is_none_or(|&pid| pid == std::process::id()) {
        return py.detach(f);
    }
    py.detach(|| match pool() {
        Some(p) => p.install(f),
        // No thread could be started for a pool: run on the calling thread alone (a
        // one-thread scope: rayon runs the loops in place).
        None => match rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .use_current_thread()
            .build()
        {
            Ok(p) => p.install(f),
            Err(_) => f(),
        },
    })
}
