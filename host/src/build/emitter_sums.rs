//! What the default lights need to know of a scene's emissive triangles, summed over
//! its triangles in id order: the whole surface area, the emitters' power, their
//! power-weighted centre and their brightest colour. A mesh in memory and a streamed
//! source (a bricked build) add the same triangles in the same order, so both come to
//! the same sums, bit for bit, and so to the same lights.

use glam::{DVec3, Vec3};

use crate::build::light_distribution::{luminance, triangle_area};
use crate::input::mesh::Mesh;

/// The running sums.
#[derive(Clone, Debug, Default)]
pub struct EmitterSums {
    /// Area of every triangle.
    pub surface: f64,
    /// Power of the emitters: luminance of `Ke` times area.
    pub power: f64,
    /// Emissive triangles with a non-zero area.
    pub count: u64,
    centre: DVec3,
    weight: f64,
    brightest: Vec3,
}

impl EmitterSums {
    /// The sums over `mesh`'s triangles.
    pub fn of_mesh(mesh: &Mesh) -> EmitterSums {
        let mut sums = EmitterSums::default();
        for (i, t) in mesh.triangles.iter().enumerate() {
            let m = mesh.tri_materials.get(i).copied().unwrap_or(u32::MAX);
            let ke = mesh.materials.get(m as usize).map_or([0.0; 3], |m| m.emission);
            sums.add(t.map(|v| mesh.positions[v as usize]), ke);
        }
        sums
    }

    /// Adds the triangle `p` of emission `ke`.
    pub fn add(&mut self, p: [[f32; 3]; 3], ke: [f32; 3]) {
        let [a, b, c] = p.map(Vec3::from);
        let area = triangle_area(a, b, c);
        self.surface += area;
        if crate::build::default_lights::is_emitter(p, ke) {
            let [da, db, dc] = p.map(|v| DVec3::from(v.map(f64::from)));
            self.count += 1;
            self.power += luminance(ke) * area;
            let w = area * luminance(ke).max(1e-12);
            self.centre += (da + db + dc) / 3.0 * w;
            self.weight += w;
            self.brightest = self.brightest.max(Vec3::from(ke));
        }
    }

    /// Whether the emitters carry enough power to light the scene alone:
    /// `power ≥ strong × surface` (see [`crate::build::default_lights`]).
    pub fn strong(&self, strong: f64) -> bool {
        self.count > 0 && self.power >= strong * self.surface
    }

    /// Power per unit of surface.
    pub fn density(&self) -> f64 {
        self.power / self.surface.max(f64::MIN_POSITIVE)
    }

    /// The emitters' power-weighted centre, nudged off them towards the middle of the
    /// scene of bounds `lo..hi` by a hundredth of its diagonal.
    pub fn centre(&self, lo: Vec3, hi: Vec3) -> Vec3 {
        let middle = (lo + hi) * 0.5;
        let p = (self.centre / self.weight.max(f64::MIN_POSITIVE)).as_vec3();
        p + (middle - p).normalize_or_zero() * (hi - lo).length() * 0.01
    }

    /// The brightest emitter's colour, scaled to a maximum of one.
    pub fn colour(&self) -> Vec3 {
        self.brightest / self.brightest.max_element()
    }
}
