//! Warnings on stderr, as many as the user asked for: by default a scene's long list
//! folds into one line (Sponza's missing textures and ignored MTL features are 15
//! lines otherwise), `--verbose` lists every one, `--quiet` prints none. Errors are never
//! hidden.

use std::sync::atomic::{AtomicU8, Ordering};

/// How much the command says besides its results.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Verbosity {
    /// No warnings.
    Quiet = 0,
    /// Short lists as they are, long ones folded.
    Normal = 1,
    /// Every warning.
    Verbose = 2,
}

/// A list longer than this folds into one line.
pub const FOLD_AFTER: usize = 3;

static LEVEL: AtomicU8 = AtomicU8::new(Verbosity::Normal as u8);

/// Sets the process's verbosity (from `--quiet` / `--verbose`).
pub fn set_verbosity(v: Verbosity) {
    LEVEL.store(v as u8, Ordering::Relaxed);
}

/// The process's verbosity.
pub fn verbosity() -> Verbosity {
    match LEVEL.load(Ordering::Relaxed) {
        0 => Verbosity::Quiet,
        2 => Verbosity::Verbose,
        _ => Verbosity::Normal,
    }
}

/// One warning (none with `--quiet`).
pub fn warning(message: &str) {
    if verbosity() != Verbosity::Quiet {
        eprintln!("warning: {message}");
    }
}

/// A hint: advice about what the user asked for, not a problem with the input (none
/// with `--quiet`).
pub fn hint(message: &str) {
    if verbosity() != Verbosity::Quiet {
        eprintln!("hint: {message}");
    }
}

/// The lines a list of warnings about `source` prints at verbosity `v`.
pub fn lines(source: &str, list: &[String], v: Verbosity) -> Vec<String> {
    match v {
        Verbosity::Quiet => Vec::new(),
        Verbosity::Normal if list.len() > FOLD_AFTER => {
            let first = list[0].strip_prefix(&format!("{source}: ")).unwrap_or(&list[0]);
            vec![format!(
                "warning: {source}: {} warnings, the first: {first} (--verbose lists them, --quiet hides them)",
                list.len()
            )]
        }
        _ => list.iter().map(|w| format!("warning: {w}")).collect(),
    }
}

/// A list of warnings about `source` (each already naming it), folded unless verbose.
pub fn warnings(source: &str, list: &[String]) {
    for l in lines(source, list, verbosity()) {
        eprintln!("{l}");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_lists_fold_into_one_line_unless_verbose() {
        let list: Vec<String> = (0..15).map(|i| format!("s.obj: problem {i}")).collect();
        let folded = lines("s.obj", &list, Verbosity::Normal);
        assert_eq!(folded.len(), 1);
        assert!(folded[0].contains("15 warnings, the first: problem 0"), "{}", folded[0]);
        assert_eq!(lines("s.obj", &list, Verbosity::Verbose).len(), 15);
        assert!(lines("s.obj", &list, Verbosity::Quiet).is_empty());
        assert_eq!(
            lines("s.obj", &list[..2], Verbosity::Normal),
            ["warning: s.obj: problem 0", "warning: s.obj: problem 1"]
        );
    }
}
