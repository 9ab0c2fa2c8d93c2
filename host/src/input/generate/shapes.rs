//! Triangle shapes the generators are built from: boxes, cylinders, spheres, leaves.

use glam::Vec3;

use crate::input::mesh::Mesh;

/// A small deterministic random generator (PCG-style LCG) for placements.
pub struct Lcg(u64);

impl Lcg {
    /// Seeded.
    pub fn new(seed: u32) -> Lcg {
        Lcg(0x853c_49e6_748f_ea9b ^ seed as u64)
    }

    /// Uniform in `[0, 1)`.
    pub fn unit(&mut self) -> f32 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((self.0 >> 40) as f32) / (1u64 << 24) as f32
    }

    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }
}

/// Appends shapes to a mesh, each with a material index.
pub struct Builder {
    /// The mesh so far.
    pub mesh: Mesh,
}

impl Builder {
    /// An empty mesh with `materials` (diffuse colours).
    pub fn new(colors: &[[f32; 3]]) -> Builder {
        let mut mesh = Mesh::default();
        for (i, c) in colors.iter().enumerate() {
            mesh.materials.push(raypipe_core::image::MaterialRecord {
                diffuse: *c,
                ..raypipe_core::image::MaterialRecord::DEFAULT
            });
            mesh.material_names.push(format!("m{i}"));
        }
        Builder { mesh }
    }

    fn vertex(&mut self, p: Vec3) -> u32 {
        self.mesh.positions.push(p.to_array());
        (self.mesh.positions.len() - 1) as u32
    }

    /// One triangle.
    pub fn tri(&mut self, a: Vec3, b: Vec3, c: Vec3, material: u32) {
        let (a, b, c) = (self.vertex(a), self.vertex(b), self.vertex(c));
        self.mesh.triangles.push([a, b, c]);
        self.mesh.tri_materials.push(material);
    }

    /// A quad `a b c d` (counter-clockwise) as two triangles.
    pub fn quad(&mut self, a: Vec3, b: Vec3, c: Vec3, d: Vec3, material: u32) {
        self.tri(a, b, c, material);
        self.tri(a, c, d, material);
    }

    /// An axis-aligned box from `lo` to `hi`: 12 triangles.
    pub fn cuboid(&mut self, lo: Vec3, hi: Vec3, material: u32) {
        let p = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
        let (a, b) = (lo, hi);
        self.quad(p(a.x, a.y, a.z), p(b.x, a.y, a.z), p(b.x, a.y, b.z), p(a.x, a.y, b.z), material);
        self.quad(p(a.x, b.y, a.z), p(a.x, b.y, b.z), p(b.x, b.y, b.z), p(b.x, b.y, a.z), material);
        self.quad(p(a.x, a.y, a.z), p(a.x, b.y, a.z), p(b.x, b.y, a.z), p(b.x, a.y, a.z), material);
        self.quad(p(a.x, a.y, b.z), p(b.x, a.y, b.z), p(b.x, b.y, b.z), p(a.x, b.y, b.z), material);
        self.quad(p(a.x, a.y, a.z), p(a.x, a.y, b.z), p(a.x, b.y, b.z), p(a.x, b.y, a.z), material);
        self.quad(p(b.x, a.y, a.z), p(b.x, b.y, a.z), p(b.x, b.y, b.z), p(b.x, a.y, b.z), material);
    }

    /// A vertical cylinder (open ends) of `segments` sides.
    pub fn cylinder(&mut self, base: Vec3, radius: f32, height: f32, segments: u32, material: u32) {
        let n = segments.max(3);
        let at = |i: u32, y: f32| {
            let a = i as f32 / n as f32 * core::f32::consts::TAU;
            base + Vec3::new(radius * a.cos(), y, radius * a.sin())
        };
        for i in 0..n {
            self.quad(at(i, 0.0), at(i + 1, 0.0), at(i + 1, height), at(i, height), material);
        }
    }

    /// A UV sphere of `rings × segments` quads.
    pub fn sphere(&mut self, centre: Vec3, radius: f32, rings: u32, segments: u32, material: u32) {
        let (r, s) = (rings.max(2), segments.max(3));
        let at = |i: u32, j: u32| {
            let th = i as f32 / r as f32 * core::f32::consts::PI;
            let ph = j as f32 / s as f32 * core::f32::consts::TAU;
            centre + radius * Vec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin())
        };
        for i in 0..r {
            for j in 0..s {
                let (a, b, c, d) = (at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j));
                // The first and last rings meet at the poles: one triangle per quad.
                if i > 0 {
                    self.tri(a, b, c, material);
                }
                if i + 1 < r {
                    self.tri(a, c, d, material);
                }
            }
        }
    }
}
