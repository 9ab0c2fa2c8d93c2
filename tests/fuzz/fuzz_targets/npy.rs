//! Any bytes as a NumPy ray batch: an error, or an array whose rows become rays or a
//! row-numbered error.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(a) = raypipe::input::npy::parse_f32_2d(data) {
        let _ = raypipe::render::batch::rays_from_array(&a);
    }
});
