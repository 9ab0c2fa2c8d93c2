//! Any text as a sweep spec ([fixed], [grid], [[points]]): expanded into points, each
//! a valid `simulate` command line, or a one-line error; never a panic, and never more
//! points than the limit.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    match raypipe::study::sweep::Spec::parse(text, "/nonexistent-raypipe-fuzz".into()) {
        Ok(spec) => {
            assert!(!spec.points.is_empty() && spec.points.len() <= raypipe::study::sweep::MAX_POINTS);
            let _ = spec.shard(None);
        }
        Err(e) => assert!(!format!("{e:#}").contains('\n'), "one-line error: {e:#}"),
    }
});
