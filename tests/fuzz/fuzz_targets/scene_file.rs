//! Any text as a scene file (TOML: meshes with transforms and materials, lights, a
//! camera), every mesh it names standing for the same small tetrahedron: the merged
//! mesh or a one-line error, never a panic, and a merged mesh builds.
#![no_main]

use libfuzzer_sys::fuzz_target;
use raypipe::input::mesh::Mesh;
use raypipe::scene::{self, Accel, BuildOptions};

const TETRA: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n";

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let load = |_: &std::path::Path| -> anyhow::Result<Option<(Mesh, Vec<String>)>> {
        let (mesh, notes) = raypipe::input::obj::load_obj_str("tetra.obj", TETRA, &|_| None)?;
        Ok(Some((mesh, notes.warnings)))
    };
    let dir = std::path::Path::new("/nonexistent-raypipe-fuzz");
    match raypipe::input::scene_file::parse_scene_file("fuzz.toml", text, dir, &load) {
        Ok((mesh, _, _)) => {
            let opts = BuildOptions { accel: Accel::Bvh, ..Default::default() };
            if let Ok(scene) = scene::build("fuzz".into(), mesh, Vec::new(), Default::default(), &opts) {
                assert!(scene.view().is_ok(), "a built image parses");
            }
        }
        Err(e) => assert!(!e.to_string().contains('\n'), "one-line error: {e}"),
    }
});
