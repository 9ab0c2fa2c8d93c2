//! Any text as a BART scene (AFF) beside the AFF fixture's files (so its includes and
//! texture can be named): a scene or a one-line error, never a panic; a scene builds,
//! animates a frame with each update and gives valid frames.
#![no_main]

use libfuzzer_sys::fuzz_target;
use raypipe::build::dynamic::{DynamicImages, DynamicState, Update};
use raypipe::scene::{Accel, BuildOptions};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/aff/fuzz.aff");
    let aff = match raypipe::input::aff::load_aff_text(&path, text) {
        Ok(a) => a,
        Err(e) => {
            assert!(!e.to_string().contains('\n'), "one-line error: {e}");
            return;
        }
    };
    let triangles: usize = aff.scene.bottoms.iter().map(|b| b.triangles.len()).sum();
    if triangles > 20_000 || aff.scene.instances.len() > 256 {
        return;
    }
    let opts = BuildOptions { accel: Accel::Bvh, ..Default::default() };
    for update in [Update::Refit, Update::Parker] {
        let Ok(images) = DynamicImages::build(&aff.scene, &aff.deforming, &opts, update) else { continue };
        let views = images.views().expect("built images parse");
        let mut state = DynamicState::new(&aff.scene, &views, &aff.deforming, update, 1.5).expect("a state");
        let t = aff.time(aff.frame_count().saturating_sub(1));
        for i in 0..aff.scene.instances.len() {
            // A keyframed map may be singular at some time: refused, never applied.
            let _ = state.set_transform(i as u32, aff.instance_transform(i, t));
        }
        for (b, verts) in aff.deformed(t) {
            // Vertices far out may round to infinity in f32: refused, never applied.
            let _ = state.set_vertices(b, &verts);
        }
        state.commit(&views);
        assert!(state.frame(&views, &state.levels()).is_ok(), "a committed frame validates");
    }
});
