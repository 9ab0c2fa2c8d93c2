//! Walkthrough camera paths: keyframes interpolated into frames, or an orbit.
//!
//! ```text
//! # A camera path: camera-file keys for every frame, the frame count, then keyframes.
//! fov    60
//! size   512 384
//! frames 24                    # frames in all, spread evenly over the keyframes
//! key   -14 2.5 0   10 4.5 0   # eye x y z, then look_at x y z
//! key     0 2.5 0   10 4.5 0
//! ```
//! Frame `k` of `n` sits at `k / (n − 1)` of the way along the keys (equal time per
//! segment), eye and look-at linear within a segment: the first frame is the first key
//! and the last frame the last key. One key repeated is a static camera.

use std::path::Path;

use anyhow::{anyhow, bail, Result};
use raypipe_core::image::CameraRecord;

use crate::input::camera_file::CameraSpec;

/// Most frames a path or an orbit may have.
pub const MAX_FRAMES: usize = 100_000;

/// A parsed camera path.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraPath {
    /// Keys shared by every frame (fov, size, up, background).
    pub spec: CameraSpec,
    /// Frames in all.
    pub frames: usize,
    /// Eye and look-at of each keyframe.
    pub keys: Vec<([f32; 3], [f32; 3])>,
}

impl CameraPath {
    /// Parses camera-path text; `name` is used in error messages.
    pub fn parse(name: &str, text: &str) -> Result<CameraPath> {
        let mut frames = None;
        let mut keys = Vec::new();
        let mut shared = String::new();
        for (n, raw) in text.lines().enumerate() {
            let line = raw.split('#').next().unwrap_or("").trim();
            let mut words = line.split_whitespace();
            let at = || format!("{name}:{}", n + 1);
            match words.next() {
                Some("frames") => {
                    let v: Vec<&str> = words.collect();
                    let count = match v.as_slice() {
                        [c] => c.parse::<usize>().map_err(|_| anyhow!("{}: '{c}' is not a frame count", at()))?,
                        _ => bail!("{}: 'frames' takes one count", at()),
                    };
                    if count == 0 || count > MAX_FRAMES {
                        bail!("{}: frames must be 1 to {MAX_FRAMES} (got {count})", at());
                    }
                    frames = Some(count);
                    shared.push('\n');
                }
                Some("key") => {
                    let v = words
                        .map(|w| match w.parse::<f32>() {
                            Ok(f) if f.is_finite() => Ok(f),
                            _ => Err(anyhow!("{}: '{w}' is not a finite number", at())),
                        })
                        .collect::<Result<Vec<f32>>>()?;
                    if v.len() != 6 {
                        bail!("{}: 'key' takes eye x y z and look_at x y z (6 numbers), found {}", at(), v.len());
                    }
                    let (eye, look) = ([v[0], v[1], v[2]], [v[3], v[4], v[5]]);
                    if eye == look {
                        bail!("{}: the key's eye and look_at are the same point", at());
                    }
                    keys.push((eye, look));
                    shared.push('\n');
                }
                Some("eye") | Some("look_at") | Some("lookat") => {
                    bail!("{}: a camera path gives eye and look_at in its 'key' lines", at())
                }
                _ => {
                    shared.push_str(raw);
                    shared.push('\n');
                }
            }
        }
        let spec = CameraSpec::parse(name, &shared)?;
        if keys.is_empty() {
            bail!("{name}: a camera path needs at least one 'key' line");
        }
        let frames = frames.ok_or_else(|| anyhow!("{name}: a camera path needs a 'frames' line"))?;
        Ok(CameraPath { spec, frames, keys })
    }

    /// Reads and parses a camera path file.
    pub fn load(path: &Path) -> Result<CameraPath> {
        let text = crate::input::read_file::read_text(path, crate::input::read_file::TEXT_LIMIT)?;
        CameraPath::parse(&path.display().to_string(), &text)
    }

    /// The frames' cameras over `base` (the scene's camera with the command line's
    /// flags; the path's shared keys win over it).
    pub fn cameras(&self, base: &CameraRecord) -> Vec<CameraRecord> {
        let base = self.spec.apply(base);
        let segments = self.keys.len() - 1;
        (0..self.frames)
            .map(|k| {
                let s = if self.frames > 1 { k as f32 / (self.frames - 1) as f32 * segments as f32 } else { 0.0 };
                let i = (s.floor() as usize).min(segments.saturating_sub(1));
                let f = if segments == 0 { 0.0 } else { s - i as f32 };
                let (a, b) = (self.keys[i], self.keys[(i + 1).min(segments)]);
                let lerp = |p: [f32; 3], q: [f32; 3]| [0, 1, 2].map(|c| p[c] + (q[c] - p[c]) * f);
                CameraRecord { eye: lerp(a.0, b.0), look_at: lerp(a.1, b.1), ..base }
            })
            .collect()
    }
}

/// `n` frames around `base`'s look-at point, about its up axis, at the eye's distance and
/// height: frame `k` turned by `2πk/n` from the eye.
pub fn orbit(base: &CameraRecord, n: usize) -> Result<Vec<CameraRecord>> {
    if n == 0 || n > MAX_FRAMES {
        bail!("--orbit must be 1 to {MAX_FRAMES} frames (got {n})");
    }
    let (eye, look, up) =
        (glam::Vec3::from(base.eye), glam::Vec3::from(base.look_at), glam::Vec3::from(base.up).normalize_or_zero());
    if up == glam::Vec3::ZERO {
        bail!("--orbit: the camera's up vector is zero");
    }
    let offset = eye - look;
    Ok((0..n)
        .map(|k| {
            let angle = std::f32::consts::TAU * k as f32 / n as f32;
            let turned = glam::Quat::from_axis_angle(up, angle) * offset;
            CameraRecord { eye: (look + turned).to_array(), ..*base }
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn base() -> CameraRecord {
        crate::scene::framing_camera([0.0; 3], [1.0; 3])
    }

    #[test]
    fn frames_run_from_the_first_key_to_the_last() {
        let p = CameraPath::parse("p", "size 32 16\nframes 5\nkey 0 0 0 0 0 -1\nkey 4 0 0 4 0 -1\nkey 4 8 0 4 8 -1\n")
            .unwrap();
        let cams = p.cameras(&base());
        assert_eq!(cams.len(), 5);
        let eyes: Vec<[f32; 3]> = cams.iter().map(|c| c.eye).collect();
        assert_eq!(eyes, [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [4.0, 0.0, 0.0], [4.0, 4.0, 0.0], [4.0, 8.0, 0.0]]);
        assert!(cams.iter().all(|c| (c.width, c.height) == (32, 16)));
        // One key: a static camera.
        let still = CameraPath::parse("p", "frames 3\nkey 1 2 3 0 0 0\n").unwrap().cameras(&base());
        assert!(still.iter().all(|c| c.eye == [1.0, 2.0, 3.0] && c.look_at == [0.0; 3]));
    }

    #[test]
    fn bad_paths_are_refused_with_their_line() {
        for (text, needle) in [
            ("frames 2\n", "at least one 'key'"),
            ("key 0 0 0 1 1 1\n", "'frames' line"),
            ("frames 0\nkey 0 0 0 1 1 1\n", "frames must be"),
            ("frames 2\nkey 0 0 0 1 1\n", "p:2: 'key' takes"),
            ("frames 2\nkey 0 0 NaN 1 1 1\n", "not a finite number"),
            ("frames 2\nkey 1 1 1 1 1 1\n", "same point"),
            ("frames 2\neye 0 0 0\nkey 0 0 0 1 1 1\n", "'key' lines"),
            ("frames 2\nzoom 3\nkey 0 0 0 1 1 1\n", "unknown camera key"),
        ] {
            let e = CameraPath::parse("p", text).unwrap_err().to_string();
            assert!(e.contains(needle), "{text:?}: {e}");
        }
    }

    #[test]
    fn an_orbit_keeps_distance_and_height() {
        let b = base();
        let cams = orbit(&b, 4).unwrap();
        let d0 = glam::Vec3::from(b.eye).distance(glam::Vec3::from(b.look_at));
        for c in &cams {
            let d = glam::Vec3::from(c.eye).distance(glam::Vec3::from(c.look_at));
            assert!((d - d0).abs() < 1e-3 * d0);
            assert!((c.eye[1] - b.eye[1]).abs() < 1e-3 * d0, "height kept about the up axis (y)");
        }
        assert_eq!(cams[0].eye, b.eye);
        assert!(orbit(&b, 0).is_err());
    }
}
