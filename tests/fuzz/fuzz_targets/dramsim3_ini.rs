//! Any text as a DRAMsim3 configuration file: parsed and checked, or a one-line error;
//! never a panic. (What passes is what DRAMsim3 is then given, so the check must refuse
//! everything DRAMsim3 would end the process on.)
#![no_main]

use libfuzzer_sys::fuzz_target;
use raypipe_hw::memory::dramsim3_ini::{check, Ini};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    match Ini::parse(text) {
        Ok(ini) => {
            if let Err(e) = check(&ini) {
                assert!(!e.contains('\n'), "one-line error");
            }
            assert_eq!(Ini::parse(&ini.render()).ok(), Some(ini), "render round-trips");
        }
        Err(e) => assert!(!e.contains('\n'), "one-line error"),
    }
});
