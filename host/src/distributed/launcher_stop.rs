//! The launcher ending the job. When a rank dies, mpirun (OpenMPI's and MPICH's, by
//! default) ends the whole job: it sends every other rank SIGTERM and, a second later
//! (OpenMPI's `odls_base_sigkill_timeout`), SIGKILL. Left alone, the master dies without
//! a word. Instead, every rank catches SIGTERM: workers stay alive a little longer, so
//! that the master, in the second it has, can tell the dead worker on its own host from
//! the living (its process is gone), and say which rank died and which tile it held.

use std::sync::atomic::{AtomicBool, Ordering};

static STOPPING: AtomicBool = AtomicBool::new(false);

extern "C" fn on_sigterm(_: libc::c_int) {
    // Only an atomic store: nothing else is safe in a signal handler.
    STOPPING.store(true, Ordering::SeqCst);
}

/// From now on SIGTERM sets [`stopping`] instead of ending the process.
pub fn catch_sigterm() {
    // SAFETY: the handler only stores to an atomic, which is async-signal-safe.
    unsafe {
        libc::signal(libc::SIGTERM, on_sigterm as extern "C" fn(libc::c_int) as libc::sighandler_t);
    }
}

/// True once SIGTERM arrived.
pub fn stopping() -> bool {
    STOPPING.load(Ordering::SeqCst)
}

/// True if process `pid` of this host has ended (gone, or a zombie not yet reaped).
/// Only Linux says (through `/proc`); elsewhere no process is known to have ended.
#[cfg(target_os = "linux")]
pub fn has_ended(pid: u32) -> bool {
    match std::fs::read_to_string(format!("/proc/{pid}/stat")) {
        // The state follows the command's closing parenthesis.
        Ok(stat) => {
            stat.rsplit_once(')').is_some_and(|(_, rest)| matches!(rest.trim_start().chars().next(), Some('Z' | 'X')))
        }
        Err(_) => true,
    }
}

/// Elsewhere: not known.
#[cfg(not(target_os = "linux"))]
pub fn has_ended(_: u32) -> bool {
    false
}

#[cfg(all(test, target_os = "linux"))]
mod tests {
    use super::*;

    #[test]
    fn a_living_process_has_not_ended_and_a_reaped_one_has() {
        assert!(!has_ended(std::process::id()));
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let pid = child.id();
        child.wait().unwrap();
        assert!(has_ended(pid));
    }
}
