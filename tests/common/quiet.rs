//! Panics caught quietly on the threads that ask for it, and reported as usual elsewhere.
//!
//! The tests that run generated or mutated scenes catch the library's panics as
//! findings. They share one process with every other test (tests/suite.rs), so the
//! panic hook stays quiet only on the threads that called [`on_this_thread`], and
//! hands every other panic to the hook it replaced: a failing assertion elsewhere keeps
//! its message.

use std::cell::{Cell, RefCell};
use std::sync::Once;

thread_local! {
    static QUIET: Cell<bool> = const { Cell::new(false) };
    static LAST: RefCell<Option<String>> = const { RefCell::new(None) };
}

/// From now on, a panic on this thread is kept (for [`take`]) instead of printed.
pub fn on_this_thread() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let before = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !QUIET.with(Cell::get) {
                return before(info);
            }
            let msg = if let Some(s) = info.payload().downcast_ref::<&str>() {
                s.to_string()
            } else if let Some(s) = info.payload().downcast_ref::<String>() {
                s.clone()
            } else {
                "(a panic without a message)".to_string()
            };
            let place = info
                .location()
                .map(|l| format!(" at {}:{}", l.file(), l.line()))
                .unwrap_or_default();
            LAST.with(|p| *p.borrow_mut() = Some(format!("{msg}{place}")));
        }));
    });
    QUIET.with(|q| q.set(true));
}

/// The message and place of this thread's last quiet panic.
pub fn take() -> Option<String> {
    LAST.with(|p| p.borrow_mut().take())
}

/// Runs `f` on this thread, quietly, turning a panic into its message.
pub fn caught<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    on_this_thread();
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(f))
        .map_err(|_| take().unwrap_or_else(|| "(no message)".to_string()))
}
