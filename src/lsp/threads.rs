//! What the server's loop and the analysis worker share: dropping a large value off
//! their threads, and the message of a caught panic.

/// Drops `value` on a thread of its own: the analysis of a large document takes
/// milliseconds to free, which the server's loop should not wait for.
pub(super) fn discard<T: Send + 'static>(value: T) {
    type Garbage = Box<dyn Send>;
    static BIN: std::sync::OnceLock<Option<crossbeam_channel::Sender<Garbage>>> =
        std::sync::OnceLock::new();
    let bin = BIN.get_or_init(|| {
        let (tx, rx) = crossbeam_channel::unbounded::<Garbage>();
        std::thread::Builder::new()
            .name(String::from("sdfc-lsp-drop"))
            // Dropping a deep tree recurses.
            .stack_size(64 << 20)
            .spawn(move || rx.iter().for_each(drop))
            .ok()
            .map(|_| tx)
    });
    match bin {
        Some(tx) => {
            // The thread lives as long as the process; if it is gone, drop here.
            if let Err(e) = tx.send(Box::new(value)) {
                drop(e.into_inner());
            }
        }
        None => drop(value),
    }
}

/// The message of a caught panic (its `&str` or `String` payload).
pub(super) fn panic_message(panic: &Box<dyn std::any::Any + Send>) -> String {
    panic
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| panic.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| String::from("a panic"))
}
