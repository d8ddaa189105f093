//! SIGTERM and SIGINT as a request to stop at the next frame boundary (issue 15). A scheduler
//! (Slurm's `--signal`, a preemption, Ctrl-C) sends SIGTERM some time before SIGKILL; the run
//! finishes the frame in progress, writes a checkpoint of it and exits with
//! `cli::EXIT_INTERRUPTED`, so a wrapper requeues and `resume` (or a rerun of `batch`)
//! continues byte-identically.
//!
//! The handler only sets a flag (async-signal-safe); the run polls it after each frame. A
//! second signal while the first is pending ends the process at once (exit 1), so a user who
//! does not want to wait for the frame can insist.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};

static FLAG: OnceLock<Arc<AtomicBool>> = OnceLock::new();

/// Installs the handlers (once per process; later calls do nothing).
pub fn install() -> std::io::Result<()> {
    use signal_hook::consts::{SIGINT, SIGTERM};
    if FLAG.get().is_some() {
        return Ok(());
    }
    let flag = Arc::new(AtomicBool::new(false));
    for sig in [SIGTERM, SIGINT] {
        // Registered first, so it sees the flag as it was before this signal set it.
        signal_hook::flag::register_conditional_shutdown(sig, 1, Arc::clone(&flag))?;
        signal_hook::flag::register(sig, Arc::clone(&flag))?;
    }
    let _ = FLAG.set(flag);
    Ok(())
}

/// Whether a stop was requested (always false when `install` was not called).
pub fn requested() -> bool {
    FLAG.get().is_some_and(|f| f.load(Ordering::SeqCst))
}
