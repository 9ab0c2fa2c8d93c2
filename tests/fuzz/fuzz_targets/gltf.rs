//! Any bytes as a glTF or GLB file (its other files looked for in a folder that does not
//! exist): raypipe's own checks run before the `gltf` crate's readers, so the loader
//! returns a mesh or a one-line error — called here without the panic guard, so that a
//! panic the checks miss is a finding — and a mesh builds into a valid image.
#![no_main]

use libfuzzer_sys::fuzz_target;
use raypipe::scene::{self, Accel, BuildOptions};

fuzz_target!(|data: &[u8]| {
    let dir = std::path::Path::new("/nonexistent-raypipe-fuzz");
    match raypipe::input::gltf::load_gltf_bytes("fuzz.gltf", data, dir) {
        Ok((mesh, _, _)) => {
            let opts = BuildOptions { accel: Accel::Bvh4, ..Default::default() };
            if let Ok(scene) = scene::build("fuzz".into(), mesh, Vec::new(), Default::default(), &opts) {
                assert!(scene.view().is_ok(), "a built image parses");
            }
        }
        Err(e) => assert!(!e.to_string().contains('\n'), "one-line error: {e}"),
    }
});
