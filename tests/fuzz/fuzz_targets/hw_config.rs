//! Any text as a hardware configuration (TOML) and `--set` assignments: parsed and
//! validated, or a one-line error; never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use raypipe_hw::HwConfig;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    if let Ok(cfg) = HwConfig::from_toml(text) {
        let _ = cfg.validate();
        let _ = cfg.modelled_bytes();
    }
    // Each line as a `--set key=value` on the defaults.
    let mut cfg = HwConfig::default();
    for line in text.lines().take(8) {
        if let Err(e) = cfg.set(line) {
            assert!(!e.contains('\n'), "one-line error");
        }
    }
    let _ = cfg.validate();
});
