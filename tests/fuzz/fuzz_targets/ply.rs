//! Any bytes as a PLY file (ASCII or binary): a mesh or a one-line error, never a panic
//! (the `ply-rs` parser is called without the panic guard), and a mesh builds.
#![no_main]

use libfuzzer_sys::fuzz_target;
use raypipe::scene::{self, Accel, BuildOptions};

fuzz_target!(|data: &[u8]| {
    match raypipe::input::ply::parse_ply("fuzz.ply", data) {
        Ok((mesh, _)) => {
            let opts = BuildOptions { accel: Accel::Kd, ..Default::default() };
            if let Ok(scene) = scene::build("fuzz".into(), mesh, Vec::new(), Default::default(), &opts) {
                assert!(scene.view().is_ok(), "a built image parses");
            }
        }
        Err(e) => assert!(!e.to_string().contains('\n'), "one-line error: {e}"),
    }
});
