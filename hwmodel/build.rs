//! With the `dramsim3` feature, finds the configuration files DRAMsim3 ships (in the
//! `dramsim3` crate's source, which cargo unpacked into its registry) so that
//! `memory.dramsim3.config` can name them; `RAYPIPE_DRAMSIM3_CONFIGS` overrides this at
//! build or run time (a vendored or offline build).

use std::path::PathBuf;

fn main() {
    println!("cargo::rerun-if-env-changed=RAYPIPE_DRAMSIM3_CONFIGS");
    if std::env::var_os("CARGO_FEATURE_DRAMSIM3").is_none() {
        return;
    }
    if let Some(dir) = std::env::var_os("RAYPIPE_DRAMSIM3_CONFIGS") {
        println!("cargo::rustc-env=RAYPIPE_DRAMSIM3_CONFIGS={}", PathBuf::from(dir).display());
        return;
    }
    let home = std::env::var_os("CARGO_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cargo")));
    let Some(registry) = home.map(|h| h.join("registry").join("src")) else { return };
    let Ok(indexes) = std::fs::read_dir(&registry) else { return };
    // Newest version of the crate in any index folder.
    let mut found: Vec<PathBuf> = indexes
        .flatten()
        .flat_map(|index| std::fs::read_dir(index.path()).into_iter().flatten().flatten())
        .map(|e| e.path())
        .filter(|p| p.file_name().and_then(|n| n.to_str()).is_some_and(|n| n.starts_with("dramsim3-")))
        .map(|p| p.join("DRAMsim3").join("configs"))
        .filter(|p| p.is_dir())
        .collect();
    found.sort();
    if let Some(dir) = found.last() {
        println!("cargo::rustc-env=RAYPIPE_DRAMSIM3_CONFIGS={}", dir.display());
    }
}
