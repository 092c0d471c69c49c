//! Ctrl-C (SIGINT): exit with code 130 at once, but never in the middle of writing output.
//!
//! [`install`] sets a handler (the `ctrlc` crate: it runs the handler on its own thread, so
//! no work happens in signal context). Every write of a result goes through [`writing`],
//! which holds a lock the handler needs before it exits: an interrupt during a write waits
//! for that write to finish (a few milliseconds; `write_atomic` makes it old-or-new anyway,
//! the lock also keeps its temporary file from being left behind), one at any other moment
//! exits immediately, long learning runs included.

use std::sync::Mutex;

static WRITE_LOCK: Mutex<()> = Mutex::new(());

/// Exit code of a run ended by SIGINT (128 + 2), as shells report it.
pub const EXIT_INTERRUPTED: u8 = 130;

/// Install the SIGINT handler (once, at start-up). Failure to install is not fatal.
pub fn install() {
    let _ = ctrlc::set_handler(|| {
        let _guard = WRITE_LOCK.lock().unwrap_or_else(|p| p.into_inner());
        eprintln!("interrupted");
        std::process::exit(EXIT_INTERRUPTED.into());
    });
}

/// Run `write` (an output write) so that Ctrl-C cannot end the process inside it.
pub fn writing<T>(write: impl FnOnce() -> T) -> T {
    let _guard = WRITE_LOCK.lock().unwrap_or_else(|p| p.into_inner());
    write()
}
