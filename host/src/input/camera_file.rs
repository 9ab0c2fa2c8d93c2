//! Camera files: a few `key values…` lines, `#` starts a comment.
//!
//! ```text
//! # Cornell box, as published (camera at z = -800 looking down +z)
//! eye        278 273 -800
//! look_at    278 273 0
//! up         0 1 0
//! fov        39.3         # vertical, degrees
//! size       512 512      # width height, pixels
//! background 0 0 0        # linear RGB of rays that hit nothing
//! ```
//! Every key is optional; a missing one keeps the scene's default.

use std::path::Path;

use anyhow::{anyhow, bail, Result};
use raypipe_core::image::CameraRecord;

/// Camera settings, each optional, applied over a base camera.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CameraSpec {
    /// Eye position.
    pub eye: Option<[f32; 3]>,
    /// Point looked at.
    pub look_at: Option<[f32; 3]>,
    /// Up vector.
    pub up: Option<[f32; 3]>,
    /// Vertical field of view in degrees.
    pub fov: Option<f32>,
    /// Image width and height.
    pub size: Option<(u32, u32)>,
    /// Background colour.
    pub background: Option<[f32; 3]>,
}

impl CameraSpec {
    /// Parses camera-file text; `name` is used in error messages.
    pub fn parse(name: &str, text: &str) -> Result<CameraSpec> {
        let mut spec = CameraSpec::default();
        for (n, raw) in text.lines().enumerate() {
            let line = raw.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let mut words = line.split_whitespace();
            let key = words.next().unwrap_or("");
            let vals: Vec<&str> = words.collect();
            let at = || format!("{name}:{}", n + 1);
            let floats = |k: usize| -> Result<Vec<f32>> {
                if vals.len() != k {
                    bail!("{}: '{key}' takes {k} numbers, found {}", at(), vals.len());
                }
                vals.iter()
                    .map(|v| match v.parse::<f32>() {
                        Ok(f) if f.is_finite() => Ok(f),
                        _ => Err(anyhow!("{}: '{v}' is not a finite number", at())),
                    })
                    .collect()
            };
            let v3 = |k| -> Result<[f32; 3]> { floats(k).map(|v| [v[0], v[1], v[2]]) };
            match key {
                "eye" => spec.eye = Some(v3(3)?),
                "look_at" | "lookat" => spec.look_at = Some(v3(3)?),
                "up" => spec.up = Some(v3(3)?),
                "fov" => spec.fov = Some(floats(1)?[0]),
                "background" => spec.background = Some(v3(3)?),
                "size" => {
                    let parse = |v: &str| v.parse::<u32>().map_err(|_| anyhow!("{}: '{v}' is not a pixel count", at()));
                    match vals.as_slice() {
                        [w, h] => spec.size = Some((parse(w)?, parse(h)?)),
                        _ => bail!("{}: 'size' takes width and height", at()),
                    }
                }
                other => bail!("{}: unknown camera key '{other}' (eye, look_at, up, fov, size, background)", at()),
            }
        }
        Ok(spec)
    }

    /// Reads and parses a camera file.
    pub fn load(path: &Path) -> Result<CameraSpec> {
        let text = crate::input::read_file::read_text(path, crate::input::read_file::TEXT_LIMIT)?;
        let name = path.display().to_string();
        let spec = CameraSpec::parse(&name, &text)?;
        spec.check(&name)?;
        Ok(spec)
    }

    /// Overrides the fields this spec sets; `other`'s set fields win over `self`'s.
    pub fn merged(self, other: CameraSpec) -> CameraSpec {
        CameraSpec {
            eye: other.eye.or(self.eye),
            look_at: other.look_at.or(self.look_at),
            up: other.up.or(self.up),
            fov: other.fov.or(self.fov),
            size: other.size.or(self.size),
            background: other.background.or(self.background),
        }
    }

    /// Fails with one line naming `name` (the file the spec came from) if what the spec
    /// sets cannot make rays: a field of view outside (0°, 180°), an eye on the point it
    /// looks at, an up along the view, a zero size, a non-finite value. What it leaves
    /// unset comes from the scene later and is checked then.
    pub fn check(&self, name: &str) -> Result<()> {
        use raypipe_core::camera::{Camera, EyeRays};
        use raypipe_core::Vec3;
        let (eye, look_at) = match (self.eye.map(Vec3::from), self.look_at.map(Vec3::from)) {
            (Some(e), Some(l)) => (e, l),
            (Some(e), None) => (e, e - Vec3::Z),
            (None, Some(l)) => (l + Vec3::Z, l),
            (None, None) => (Vec3::Z, Vec3::ZERO),
        };
        let view = (look_at - eye).normalize_or_zero();
        let up = match self.up.map(Vec3::from) {
            Some(u) if self.eye.is_some() && self.look_at.is_some() => u,
            // Without both ends the view is the scene's: an up that is no vector at all
            // is all that can be told now.
            Some(u) if u == Vec3::ZERO || !u.is_finite() => u,
            _ if view.cross(Vec3::Y).length() > 1e-3 => Vec3::Y,
            _ => Vec3::X,
        };
        let (width, height) = self.size.unwrap_or((1, 1));
        let camera = Camera { eye, look_at, up, vfov_deg: self.fov.unwrap_or(45.0), width, height };
        EyeRays::new(&camera).map(drop).map_err(|e| anyhow!("{name}: camera: {e}"))?;
        if let Some(b) = self.background.filter(|b| b.iter().any(|c| !c.is_finite() || *c < 0.0)) {
            bail!("{name}: camera: background {b:?} must be finite and not negative");
        }
        Ok(())
    }

    /// Applies the spec to a camera record.
    pub fn apply(&self, base: &CameraRecord) -> CameraRecord {
        let mut c = *base;
        if let Some(v) = self.eye {
            c.eye = v;
        }
        if let Some(v) = self.look_at {
            c.look_at = v;
        }
        if let Some(v) = self.up {
            c.up = v;
        }
        if let Some(v) = self.fov {
            c.vfov_deg = v;
        }
        if let Some((w, h)) = self.size {
            c.width = w;
            c.height = h;
        }
        if let Some(v) = self.background {
            c.background = v;
        }
        c
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_every_key_and_reports_bad_lines_with_their_number() {
        let s = CameraSpec::parse("c", "eye 1 2 3\nlook_at 0 0 0 # target\nup 0 1 0\nfov 45\nsize 64 32\n").unwrap();
        assert_eq!(s.eye, Some([1.0, 2.0, 3.0]));
        assert_eq!(s.size, Some((64, 32)));
        assert_eq!(s.fov, Some(45.0));
        let e = CameraSpec::parse("c", "\n\neye 1 2\n").unwrap_err().to_string();
        assert_eq!(e, "c:3: 'eye' takes 3 numbers, found 2");
        let e = CameraSpec::parse("c", "fov nan\n").unwrap_err().to_string();
        assert!(e.contains("not a finite number"), "{e}");
        assert!(CameraSpec::parse("c", "zoom 2\n").unwrap_err().to_string().contains("unknown camera key"));
    }
}
