//! Any text as a camera file: a camera or a one-line error naming the line; a camera
//! applied to a default record gives eye rays or a typed error.
#![no_main]

use libfuzzer_sys::fuzz_target;
use raypipe::input::camera_file::CameraSpec;
use raypipe_core::camera::{Camera, EyeRays};
use raypipe_core::image::CameraRecord;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    match CameraSpec::parse("fuzz.camera", text) {
        Ok(spec) => {
            let base = CameraRecord {
                eye: [0.0, 1.0, 3.0],
                vfov_deg: 45.0,
                look_at: [0.0; 3],
                width: 4,
                up: [0.0, 1.0, 0.0],
                height: 4,
                background: [0.0; 3],
                _pad: 0,
            };
            let _ = EyeRays::new(&Camera::from(&spec.apply(&base)));
        }
        Err(e) => assert!(!e.to_string().contains('\n'), "one-line error"),
    }
});
