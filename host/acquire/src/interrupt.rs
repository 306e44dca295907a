//! Ctrl-C, SIGTERM and SIGHUP for the whole process, in one handler: while
//! a scan listens ([`requested`]) the first one stops it through the client
//! (the head made safe, the operator told how to resume) and a second one
//! exits; a pseudo-terminal link registered with [`remove_on_exit`] is
//! removed; otherwise the process exits as the signal would have it, 130.

use anyhow::{Context, Result};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::sync::{Mutex, OnceLock};
use tokio::sync::Notify;

/// The exit code of a process stopped by its operator (128 + SIGINT).
pub const EXIT_CODE: u8 = 130;

static LISTENING: AtomicBool = AtomicBool::new(false);
static SEEN: AtomicU32 = AtomicU32::new(0);
static LINK: Mutex<Option<PathBuf>> = Mutex::new(None);

fn notify() -> &'static Notify {
    static N: OnceLock<Notify> = OnceLock::new();
    N.get_or_init(Notify::new)
}

/// Installs the handler (once, at start-up).
pub fn install() -> Result<()> {
    ctrlc::set_handler(|| {
        if let Some(link) = LINK.lock().ok().and_then(|mut l| l.take()) {
            let _ = std::fs::remove_file(&link);
            eprintln!("stopped; {} removed", link.display());
            std::process::exit(EXIT_CODE.into());
        }
        let first = SEEN.fetch_add(1, Ordering::SeqCst) == 0;
        if LISTENING.load(Ordering::SeqCst) && first {
            notify().notify_one();
        } else {
            std::process::exit(EXIT_CODE.into());
        }
    })
    .context("installing the Ctrl-C handler")
}

/// Resolves when the operator asks to stop; from this call until the
/// future is dropped, the first request does not kill the process (work
/// that does not yield meanwhile, planning a scan, sees it once it does).
pub fn requested() -> impl std::future::Future<Output = ()> {
    struct Listening;
    impl Drop for Listening {
        fn drop(&mut self) {
            LISTENING.store(false, Ordering::SeqCst);
        }
    }
    LISTENING.store(true, Ordering::SeqCst);
    let listening = Listening;
    async move {
        let _listening = listening;
        notify().notified().await;
    }
}

/// Removes `link` when the process is stopped by a signal.
pub fn remove_on_exit(link: PathBuf) {
    if let Ok(mut l) = LINK.lock() {
        *l = Some(link);
    }
}
