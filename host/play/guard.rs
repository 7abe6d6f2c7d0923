//! The window's event loop, kept from taking the game down with it: winit's X11 backend
//! panics when the display destroys the window under it (its focus bookkeeping unwraps the
//! X error that follows). The game lives outside winit and is intact then, so the loop's
//! end is taken as the window's closing: the report is printed and the recording written.

use std::panic::{self, AssertUnwindSafe, PanicHookInfo};
use std::sync::Arc;

/// Runs `event_loop`; `None` if winit panicked. A panic of winit's is silent (its message
/// quotes winit's source); any other still prints as before and ends the loop the same way.
pub(super) fn surviving_winit<R>(event_loop: impl FnOnce() -> R) -> Option<R> {
    let previous: Arc<dyn Fn(&PanicHookInfo<'_>) + Send + Sync> = Arc::from(panic::take_hook());
    let outer = Arc::clone(&previous);
    panic::set_hook(Box::new(move |info| {
        let in_winit = info
            .location()
            .is_some_and(|at| at.file().contains("/winit-"));
        if !in_winit {
            outer(info);
        }
    }));
    let ran = panic::catch_unwind(AssertUnwindSafe(event_loop));
    panic::set_hook(Box::new(move |info| previous(info)));
    match ran {
        Ok(result) => Some(result),
        Err(_) => {
            eprintln!("gpuwars: the window was taken away by the display; the game ends here");
            None
        }
    }
}
