//! A forest (Purcell 2002's second million-triangle scene): trees on rolling ground,
//! each a trunk and a crown of single-triangle leaves scattered through an ellipsoid.
//! The defaults (1200 trees of 800 leaves) make ~1 million triangles.

use glam::Vec3;

use crate::input::camera_file::CameraSpec;
use crate::input::generate::shapes::{Builder, Lcg};
use crate::input::mesh::Mesh;

/// Generator parameters.
pub struct Forest {
    /// Trees.
    pub trees: u32,
    /// Leaves per tree.
    pub leaves: u32,
    /// Placement seed.
    pub seed: u32,
}

const GROUND: u32 = 0;
const BARK: u32 = 1;
const LEAF: u32 = 2;
const CELLS: u32 = 64;
const TRUNK_SIDES: u32 = 8;

impl Forest {
    /// Side of the square patch of ground: about 36 m² per tree.
    fn side(&self) -> f32 {
        (self.trees as f32).sqrt() * 6.0
    }

    /// Ground height at `(x, z)`: gentle hills.
    fn ground(&self, x: f32, z: f32) -> f32 {
        let s = self.side();
        1.5 * ((x / s * 6.0).sin() + (z / s * 5.0 + 1.0).cos()) + 0.8 * ((x + z) / s * 13.0).sin()
    }

    /// How many triangles [`Forest::mesh`] makes: the ground's 64 × 64 quads, and per
    /// tree an 8-sided trunk and its leaves.
    pub fn triangle_count(&self) -> u64 {
        (2 * CELLS * CELLS) as u64 + self.trees as u64 * (2 * TRUNK_SIDES as u64 + self.leaves as u64)
    }

    /// The triangles.
    pub fn mesh(&self) -> Mesh {
        let mut b = Builder::new(&[[0.35, 0.3, 0.2], [0.4, 0.28, 0.18], [0.2, 0.55, 0.2]]);
        let s = self.side();
        let at = |i: u32, k: u32| {
            let (x, z) = (i as f32 / CELLS as f32 * s, k as f32 / CELLS as f32 * s);
            Vec3::new(x, self.ground(x, z), z)
        };
        for i in 0..CELLS {
            for k in 0..CELLS {
                b.quad(at(i, k), at(i, k + 1), at(i + 1, k + 1), at(i + 1, k), GROUND);
            }
        }
        let mut rng = Lcg::new(self.seed);
        for _ in 0..self.trees {
            let (x, z) = (rng.range(1.0, s - 1.0), rng.range(1.0, s - 1.0));
            let base = Vec3::new(x, self.ground(x, z) - 0.2, z);
            let height = rng.range(3.0, 6.0);
            b.cylinder(base, rng.range(0.12, 0.25), height + 0.2, TRUNK_SIDES, BARK);
            let crown = base + Vec3::new(0.0, height + 1.0, 0.0);
            let (rx, ry) = (rng.range(1.2, 2.0), rng.range(1.5, 2.5));
            for _ in 0..self.leaves {
                // A point in the crown's ellipsoid, and a small triangle around it.
                let d = loop {
                    let d = Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
                    if d.length_squared() <= 1.0 {
                        break d;
                    }
                };
                let c = crown + Vec3::new(d.x * rx, d.y * ry, d.z * rx);
                let mut corner = || Vec3::new(rng.range(-0.2, 0.2), rng.range(-0.2, 0.2), rng.range(-0.2, 0.2));
                let (p, q, r) = (c + corner(), c + corner(), c + corner());
                b.tri(p, q, r, LEAF);
            }
        }
        b.mesh
    }

    /// The views: top (looking down on the canopy) and inside (among the trunks).
    pub fn views(&self) -> Vec<(&'static str, CameraSpec)> {
        let s = self.side();
        let top = CameraSpec {
            eye: Some([0.5 * s, 1.2 * s + 20.0, 0.5 * s]),
            look_at: Some([0.5 * s, 0.0, 0.5 * s]),
            up: Some([0.0, 0.0, 1.0]),
            fov: Some(45.0),
            ..CameraSpec::default()
        };
        let (x, z) = (0.3 * s, 0.3 * s);
        let inside = CameraSpec {
            eye: Some([x, self.ground(x, z) + 1.7, z]),
            look_at: Some([0.8 * s, self.ground(x, z) + 2.5, 0.7 * s]),
            up: Some([0.0, 1.0, 0.0]),
            fov: Some(60.0),
            ..CameraSpec::default()
        };
        vec![("top", top), ("inside", inside)]
    }
}
