//! Ctrl-C (SIGINT) and SIGTERM as a request to stop: a long command polls [`requested`]
//! between frames and ends cleanly (outputs finished and valid) instead of dying mid-write.
//!
//! The handler is installed once per process ([`install`]); a second signal ends the process
//! at once with [`EXIT_INTERRUPTED`], so a user who presses Ctrl-C twice is never kept waiting.

use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, Ordering};

static REQUESTED: AtomicBool = AtomicBool::new(false);
static INSTALLED: OnceLock<bool> = OnceLock::new();

/// The exit code of a command that stopped on a signal: 128 + SIGINT, as shells report it.
pub const EXIT_INTERRUPTED: u8 = 130;

/// Installs the handler (once); returns whether it is in place (a process that cannot install
/// one keeps the default behaviour).
pub fn install() -> bool {
    *INSTALLED.get_or_init(|| {
        ctrlc::set_handler(|| {
            if REQUESTED.swap(true, Ordering::SeqCst) {
                std::process::exit(i32::from(EXIT_INTERRUPTED));
            }
        })
        .is_ok()
    })
}

/// Whether a stop was asked for since the handler was installed.
pub fn requested() -> bool {
    REQUESTED.load(Ordering::SeqCst)
}
