//! The rays a frame traced, by query, in tile order (`raypipe render --ray-log DIR`): so
//! that another tracer — raypipe's own paths through `raypipe trace`, or Embree in
//! `bench/embree_harness.py` — can be timed on exactly the rays a path-traced frame asks,
//! beside the frame's own time.

use std::path::Path;

use anyhow::{Context, Result};
use raypipe_core::shade::ray_record::RayKind;
use raypipe_core::Ray;

/// One tile's rays: its eye rays (sample-major, row-major in the tile, those that entered
/// the scene's box), then the rays its shaders emitted, in the order the tile's stream
/// traced them, split by query.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TileRayLog {
    /// Eye rays (closest-hit queries).
    pub eye: Vec<Ray>,
    /// Emitted rays that ask for the closest hit (bounces, reflection, refraction).
    pub secondary: Vec<Ray>,
    /// Shadow rays (any-hit queries).
    pub shadow: Vec<Ray>,
}

impl TileRayLog {
    /// Records an emitted ray of `kind`.
    pub fn push(&mut self, kind: RayKind, ray: Ray) {
        match kind {
            RayKind::Primary => self.eye.push(ray),
            RayKind::Shadow => self.shadow.push(ray),
            _ => self.secondary.push(ray),
        }
    }
}

/// The files of a ray log, by the query their rays ask: `(file name, query)`.
pub const FILES: [(&str, &str); 3] = [("eye.npy", "closest"), ("secondary.npy", "closest"), ("shadow.npy", "any")];

/// Writes the tiles' rays, in tile order, into `dir` (created if missing) as three
/// `(N, 8)` float32 arrays — origin, direction, t_min, t_max: `raypipe trace --rays`'s
/// input. Returns how many rays each file holds.
pub fn write_ray_log(dir: &Path, tiles: &[TileRayLog]) -> Result<[usize; 3]> {
    std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create the ray log's folder", dir.display()))?;
    let parts: [fn(&TileRayLog) -> &[Ray]; 3] = [|t| &t.eye, |t| &t.secondary, |t| &t.shadow];
    let mut counts = [0; 3];
    for ((file, _), (part, count)) in FILES.iter().zip(parts.iter().zip(&mut counts)) {
        *count = tiles.iter().map(|t| part(t).len()).sum();
        crate::input::npy::write_f32_rows(&dir.join(file), *count, 8, |out| {
            for r in tiles.iter().flat_map(part) {
                let (o, d) = (r.origin, r.dir);
                out.push(&[o.x, o.y, o.z, d.x, d.y, d.z, r.t_min, r.t_max])?;
            }
            Ok(())
        })?;
    }
    Ok(counts)
}

#[cfg(test)]
mod tests {
    use super::*;
    use raypipe_core::Vec3;

    /// The files hold each query's rays, tile after tile, row for row, read back by the
    /// same reader `raypipe trace` uses.
    #[test]
    fn the_log_reads_back_as_trace_input_in_tile_order() {
        let ray = |k: f32| Ray { origin: Vec3::new(k, 1.0, 2.0), dir: Vec3::new(0.0, 0.0, -1.0), t_min: 0.0, t_max: k };
        let mut a = TileRayLog::default();
        a.push(RayKind::Primary, ray(1.0));
        a.push(RayKind::Shadow, ray(2.0));
        a.push(RayKind::Path, ray(3.0));
        let mut b = TileRayLog::default();
        b.push(RayKind::Reflection, ray(4.0));
        b.push(RayKind::Shadow, ray(5.0));
        b.push(RayKind::Glossy, ray(6.0));
        let dir = tempfile::tempdir().unwrap();
        let counts = write_ray_log(dir.path(), &[a, b]).unwrap();
        assert_eq!(counts, [1, 3, 2]);
        let read = |f: &str| {
            let bytes = std::fs::read(dir.path().join(f)).unwrap();
            let a = crate::input::npy::parse_f32_2d(&bytes).unwrap();
            assert_eq!(a.cols, 8);
            (0..a.rows).map(|i| (a.data[i * 8], a.data[i * 8 + 7])).collect::<Vec<_>>()
        };
        assert_eq!(read("eye.npy"), [(1.0, 1.0)]);
        assert_eq!(read("secondary.npy"), [(3.0, 3.0), (4.0, 4.0), (6.0, 6.0)]);
        assert_eq!(read("shadow.npy"), [(2.0, 2.0), (5.0, 5.0)]);
    }
}
