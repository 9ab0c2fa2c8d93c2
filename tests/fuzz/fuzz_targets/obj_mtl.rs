//! Any text as an OBJ file (and the same text's second half as the MTL file it may
//! name): the loader returns a mesh or a one-line error, and a mesh builds into a valid
//! image with every structure or fails with an error, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use raypipe::scene::{self, Accel, BuildOptions};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let split = text.char_indices().map(|(i, _)| i).find(|&i| i >= text.len() / 2).unwrap_or(text.len());
    let (obj, mtl) = text.split_at(split);
    let mtl = mtl.to_string();
    let Ok((mesh, _)) = raypipe::input::obj::load_obj_str("fuzz.obj", obj, &|_| Some(mtl.clone())) else { return };
    for accel in [Accel::Grid, Accel::Kd, Accel::Bvh4] {
        let opts = BuildOptions { accel, ..Default::default() };
        if let Ok(scene) = scene::build("fuzz".into(), mesh.clone(), Vec::new(), Default::default(), &opts) {
            assert!(scene.view().is_ok(), "a built image parses");
        }
    }
});
