//! A backstop around third-party readers (the `gltf`, `tobj` and PLY crates): raypipe
//! checks what they would fail on before calling them, and if one panics all the same,
//! the user gets one line naming the file instead of a crash with a backtrace.

use std::cell::Cell;
use std::panic::AssertUnwindSafe;
use std::sync::Once;

use anyhow::{anyhow, Result};

thread_local! {
    /// True while this thread runs a guarded reader: its panics are reported as errors.
    static GUARDED: Cell<bool> = const { Cell::new(false) };
}

/// Runs `read` (the `what` reader on the file `name`); a panic inside becomes an error.
pub fn guarded<T>(name: &str, what: &str, read: impl FnOnce() -> Result<T>) -> Result<T> {
    static QUIET_HOOK: Once = Once::new();
    QUIET_HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !GUARDED.with(Cell::get) {
                previous(info);
            }
        }));
    });
    let was = GUARDED.with(|g| g.replace(true));
    let result = std::panic::catch_unwind(AssertUnwindSafe(read));
    GUARDED.with(|g| g.set(was));
    result.unwrap_or_else(|payload| {
        let message = payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "no message".into());
        let line = message.lines().next().unwrap_or_default().to_string();
        Err(anyhow!("{name}: the {what} reader failed on this file: {line}"))
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_panic_becomes_one_line_and_other_errors_pass() {
        let e = super::guarded::<()>("x.gltf", "glTF", || panic!("internal error: entered unreachable code\nmore"));
        assert_eq!(
            e.unwrap_err().to_string(),
            "x.gltf: the glTF reader failed on this file: internal error: entered unreachable code"
        );
        let e = super::guarded::<()>("x.gltf", "glTF", || Err(anyhow::anyhow!("plain")));
        assert_eq!(e.unwrap_err().to_string(), "plain");
        assert_eq!(super::guarded("x", "y", || Ok(3)).unwrap(), 3);
    }
}
