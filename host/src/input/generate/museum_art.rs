//! The museum's animated art at any size (BART's museum6–8 need `animart6…8.aff`,
//! which the benchmark's public mirror lacks). Written in the format of `animart5.aff`:
//! `4^level` triangles, each a `tpa` record with five keys at times 0…4, which the
//! museum's animation (`a -1 5 …`) plays through. The keys follow the shapes of the
//! published file: a cloud of small triangles near the floor (time 0), an explosion
//! (1), a tetrahedron subdivided `level − 1` times (2), the same triangles pushed onto
//! a sphere (3), and a rippled sheet (4). A fixed seed gives the same file every time.

use std::fmt::Write;

use glam::DVec3;

/// The deepest level written (4^10 triangles, a 200 MB file).
pub const MAX_LEVEL: u32 = 10;

/// A small deterministic generator (PCG-style LCG; the file needs no statistics).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    fn in_ball(&mut self, r: f64) -> DVec3 {
        loop {
            let p = DVec3::new(self.next(), self.next(), self.next()) * 2.0 - DVec3::ONE;
            if p.length_squared() <= 1.0 {
                return p * r;
            }
        }
    }
}

/// The triangles of a regular tetrahedron about `centre`, each face split into four
/// `depth` times.
fn tetrahedron(centre: DVec3, depth: u32) -> Vec<[DVec3; 3]> {
    let v = [
        DVec3::new(0.5, 0.5, 0.5),
        DVec3::new(-0.5, -0.5, 0.5),
        DVec3::new(-0.5, 0.5, -0.5),
        DVec3::new(0.5, -0.5, -0.5),
    ]
    .map(|p| p + centre);
    let mut tris = vec![[v[0], v[1], v[2]], [v[0], v[3], v[1]], [v[0], v[2], v[3]], [v[1], v[3], v[2]]];
    for _ in 0..depth {
        tris = tris
            .iter()
            .flat_map(|&[a, b, c]| {
                let (ab, bc, ca) = ((a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5);
                [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
            })
            .collect();
    }
    tris
}

/// The art of `4^level` animated triangles as AFF text.
pub fn museum_art(level: u32, seed: u64) -> String {
    let level = level.clamp(1, MAX_LEVEL);
    let n = 4usize.pow(level);
    let centre = DVec3::new(0.0, 2.5, 0.0);
    let solid = tetrahedron(centre, level - 1);
    let mut g = Lcg(seed ^ 0x9e37_79b9_7f4a_7c15);
    // The sheet: a grid of 2^level × 2^(level−1) quads, two triangles each.
    let (nx, nz) = (1usize << level, 1usize << (level - 1));
    let sheet = |i: usize, j: usize| {
        let (x, z) = (i as f64 / nx as f64 - 0.5, j as f64 / nz as f64 - 0.5);
        DVec3::new(x, 1.5 + 0.05 * (9.0 * x).sin() * (7.0 * z).cos(), z * 0.5)
    };
    let mut out = format!(
        "% BART museum art: {n} animated triangles (4^{level}), written by `raypipe museum-art --level {level} --seed {seed}`\n"
    );
    for (k, tri) in solid.iter().enumerate() {
        let cloud = DVec3::new(0.0, 1.5, 0.0) + g.in_ball(0.5);
        let blast = centre + g.in_ball(1.5);
        let q = k / 2;
        let (i, j) = (q % nx, q / nx);
        let quad = [sheet(i, j), sheet(i + 1, j), sheet(i + 1, j + 1), sheet(i, j + 1)];
        let flat = if k % 2 == 0 { [quad[0], quad[1], quad[2]] } else { [quad[0], quad[2], quad[3]] };
        let small = |p: DVec3, g: &mut Lcg| [p, p + g.in_ball(0.03), p + g.in_ball(0.03)];
        let keys = [
            small(cloud, &mut g),
            small(blast, &mut g),
            *tri,
            tri.map(|p| centre + (p - centre).normalize() * 0.8),
            flat,
        ];
        let _ = writeln!(out, "tpa 5");
        for (time, v) in keys.iter().enumerate() {
            let normal = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
            let _ = writeln!(out, "  {time}");
            for p in v {
                let _ = writeln!(
                    out,
                    "  {:.6} {:.6} {:.6}  {:.6} {:.6} {:.6}",
                    p.x, p.y, p.z, normal.x, normal.y, normal.z
                );
            }
        }
    }
    debug_assert_eq!(solid.len(), n);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_art_has_four_to_the_level_triangles_of_five_keys() {
        let text = museum_art(3, 1);
        assert_eq!(text.matches("tpa 5").count(), 64);
        assert_eq!(text, museum_art(3, 1));
        assert_ne!(text, museum_art(3, 2));
        let parsed = crate::input::aff::load_aff_text(
            std::path::Path::new("/nonexistent/art.aff"),
            &format!("v\nfrom 0 2 -6\nat 0 2 0\nup 0 1 0\nangle 45\nhither 0.1\nresolution 8 8\na 0 4 5\n{text}"),
        )
        .expect("the art reads as AFF");
        assert_eq!(parsed.scene.bottoms[0].triangles.len(), 64);
        assert!(parsed.deforming[0]);
    }
}
