//! One line of text to the console: the C library's `write` on the build machine,
//! semihosting on an emulated board. A line is formatted into a fixed buffer (no heap);
//! what does not fit is cut.

use core::fmt::{self, Write};

struct Line {
    buf: [u8; 200],
    len: usize,
}

impl Write for Line {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        for &b in s.as_bytes() {
            if let Some(slot) = self.buf.get_mut(self.len) {
                *slot = b;
                self.len += 1;
            }
        }
        Ok(())
    }
}

/// Writes one formatted line.
pub fn line(args: fmt::Arguments<'_>) {
    let mut l = Line { buf: [0; 200], len: 0 };
    let _ = l.write_fmt(args);
    let _ = l.write_str("\n");
    write_bytes(l.buf.get(..l.len).unwrap_or_default());
}

#[cfg(not(target_os = "none"))]
fn write_bytes(bytes: &[u8]) {
    extern "C" {
        fn write(fd: i32, buf: *const u8, count: usize) -> isize;
    }
    // SAFETY: `bytes` is a valid buffer of `bytes.len()` bytes for the call's duration.
    let _ = unsafe { write(1, bytes.as_ptr(), bytes.len()) };
}

#[cfg(target_os = "none")]
fn write_bytes(bytes: &[u8]) {
    use semihosting::io::Write as _;
    if let Ok(mut out) = semihosting::io::stdout() {
        let _ = out.write_all(bytes);
    }
}
