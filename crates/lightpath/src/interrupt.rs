//! SIGINT and SIGTERM, caught once for the whole process (the `ctrlc` crate allows one
//! handler): while a render runs a signal stops it after the rows in flight and a second
//! exits at once; otherwise signals are counted, and [`wait`] returns after one (the
//! viewer's "press Ctrl-C to stop").

use crate::Error;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex, Once, PoisonError};

/// Exit status of a render stopped by SIGINT or SIGTERM (128 + SIGINT, as shells report).
pub const EXIT_INTERRUPTED: u8 = 130;

/// The running render's cancel flag, if one runs.
static RENDERING: Mutex<Option<Arc<AtomicBool>>> = Mutex::new(None);
/// Signals that came while no render ran.
static SIGNALS: Mutex<u32> = Mutex::new(0);
static SIGNALLED: Condvar = Condvar::new();

/// Installs the handler (once); an error says why signals cannot be caught.
pub fn catch() -> Result<(), Error> {
    static ONCE: Once = Once::new();
    static FAILED: Mutex<Option<String>> = Mutex::new(None);
    ONCE.call_once(|| {
        if let Err(e) = ctrlc::set_handler(on_signal) {
            *FAILED.lock().unwrap_or_else(PoisonError::into_inner) = Some(e.to_string());
        }
    });
    match FAILED
        .lock()
        .unwrap_or_else(PoisonError::into_inner)
        .clone()
    {
        Some(e) => Err(Error::Interrupts(e)),
        None => Ok(()),
    }
}

/// From now until [`render_finished`], a signal sets `cancel` (a second exits).
pub fn render_started(cancel: Arc<AtomicBool>) -> Result<(), Error> {
    *RENDERING.lock().unwrap_or_else(PoisonError::into_inner) = Some(cancel);
    catch()
}

pub fn render_finished() {
    *RENDERING.lock().unwrap_or_else(PoisonError::into_inner) = None;
}

/// Blocks until a signal has come while no render ran (one that came before the call
/// counts: a signal is never missed between installing the handler and waiting).
pub fn wait() -> Result<(), Error> {
    catch()?;
    let mut n = SIGNALS.lock().unwrap_or_else(PoisonError::into_inner);
    while *n == 0 {
        n = SIGNALLED.wait(n).unwrap_or_else(PoisonError::into_inner);
    }
    *n -= 1;
    Ok(())
}

fn on_signal() {
    let rendering = RENDERING
        .lock()
        .unwrap_or_else(PoisonError::into_inner)
        .clone();
    if let Some(cancel) = rendering {
        if cancel.swap(true, Ordering::SeqCst) {
            crate::output::atomic::remove_temporary_files();
            eprintln!("interrupted again: exiting without writing");
            std::process::exit(EXIT_INTERRUPTED as i32);
        }
        eprintln!(
            "\ninterrupted: finishing the rows in flight, then writing the rows done and a \
             checkpoint (interrupt again to quit at once)"
        );
        return;
    }
    *SIGNALS.lock().unwrap_or_else(PoisonError::into_inner) += 1;
    SIGNALLED.notify_all();
}
