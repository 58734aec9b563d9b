//! Ctrl-C (SIGINT) and SIGTERM as a flag: the run loop polls it after every
//! step, stops, and finalises the log and `summary.json`. A second signal
//! while the first is being handled exits at once (status 130), as a user
//! pressing Ctrl-C twice expects; the chunks written so far stay readable.

use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, Ordering};

static STOP: AtomicBool = AtomicBool::new(false);
static INSTALLED: OnceLock<Result<(), String>> = OnceLock::new();

/// Installs the handler (once per process) and clears the flag.
///
/// # Errors
/// When another handler was installed first (the message says so).
pub fn arm() -> Result<(), String> {
    let r = INSTALLED.get_or_init(|| {
        ctrlc::set_handler(|| {
            if STOP.swap(true, Ordering::SeqCst) {
                std::process::exit(130);
            }
        })
        .map_err(|e| format!("cannot handle Ctrl-C/SIGTERM: {e}"))
    });
    STOP.store(false, Ordering::SeqCst);
    r.clone()
}

/// True once Ctrl-C or SIGTERM arrived since [`arm`].
pub fn requested() -> bool {
    STOP.load(Ordering::Relaxed)
}

/// Clears the flag (after a run handled it).
pub fn clear() {
    STOP.store(false, Ordering::SeqCst);
}
