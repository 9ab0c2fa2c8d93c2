//! A building interior in the spirit of Soda Hall (Purcell 2002's first million-triangle
//! scene): floors of `rooms × rooms` rooms, 4 m square and 3 m high, with doors between
//! them, each furnished with desks, chairs, a bookshelf full of books and a lamp.
//! About 870 triangles a room: the defaults (6 floors of 12 × 12 rooms) make ~0.9 million.

use glam::Vec3;

use crate::input::camera_file::CameraSpec;
use crate::input::generate::shapes::{Builder, Lcg};
use crate::input::mesh::Mesh;

const ROOM: f32 = 4.0;
const STOREY: f32 = 3.0;
const WALL: f32 = 0.1;

/// Generator parameters.
pub struct Building {
    /// Storeys.
    pub floors: u32,
    /// Rooms along each side of a floor.
    pub rooms: u32,
    /// Placement seed.
    pub seed: u32,
}

// Materials.
const FLOOR: u32 = 0;
const WALLS: u32 = 1;
const WOOD: u32 = 2;
const FABRIC: u32 = 3;
const BOOK: u32 = 4;
const LAMP: u32 = 5;

impl Building {
    /// The triangles.
    /// The most triangles [`Building::mesh`] can make: per room a floor, six wall pieces,
    /// four desks with chairs, a shelf of 24 books and a lamp (1,168); per storey the two
    /// outer walls; the roof.
    pub fn triangle_bound(&self) -> u64 {
        const ROOM_MOST: u64 = 12 + 6 * 12 + 4 * (5 + 6) * 12 + (5 + 24) * 12 + 2 * 8 + 2 * 8 * 12;
        let floors = self.floors as u64;
        floors * (self.rooms as u64).pow(2) * ROOM_MOST + floors * 2 * 12 + 12
    }

    /// The triangles.
    pub fn mesh(&self) -> Mesh {
        let mut b = Builder::new(&[
            [0.55, 0.5, 0.45],
            [0.85, 0.83, 0.78],
            [0.55, 0.35, 0.2],
            [0.25, 0.35, 0.6],
            [0.7, 0.2, 0.2],
            [0.95, 0.9, 0.6],
        ]);
        let mut rng = Lcg::new(self.seed);
        let side = self.rooms as f32 * ROOM;
        for f in 0..self.floors {
            let y = f as f32 * STOREY;
            for i in 0..self.rooms {
                for k in 0..self.rooms {
                    let o = Vec3::new(i as f32 * ROOM, y, k as f32 * ROOM);
                    self.room(&mut b, &mut rng, o);
                }
            }
            // Outer walls on the far sides.
            b.cuboid(Vec3::new(side, y, 0.0), Vec3::new(side + WALL, y + STOREY, side), WALLS);
            b.cuboid(Vec3::new(0.0, y, side), Vec3::new(side, y + STOREY, side + WALL), WALLS);
        }
        // The roof.
        let top = self.floors as f32 * STOREY;
        b.cuboid(Vec3::new(0.0, top, 0.0), Vec3::new(side + WALL, top + WALL, side + WALL), FLOOR);
        b.mesh
    }

    fn room(&self, b: &mut Builder, rng: &mut Lcg, o: Vec3) {
        let v = |x: f32, y: f32, z: f32| o + Vec3::new(x, y, z);
        b.cuboid(v(0.0, -WALL, 0.0), v(ROOM, 0.0, ROOM), FLOOR);
        // The wall on the low-x side with a door in its middle, and the wall on the
        // low-z side with a door near its end.
        b.cuboid(v(0.0, 0.0, 0.0), v(WALL, STOREY, 1.5), WALLS);
        b.cuboid(v(0.0, 0.0, 2.5), v(WALL, STOREY, ROOM), WALLS);
        b.cuboid(v(0.0, 2.2, 1.5), v(WALL, STOREY, 2.5), WALLS);
        b.cuboid(v(0.0, 0.0, 0.0), v(2.8, STOREY, WALL), WALLS);
        b.cuboid(v(3.6, 0.0, 0.0), v(ROOM, STOREY, WALL), WALLS);
        b.cuboid(v(2.8, 2.2, 0.0), v(3.6, STOREY, WALL), WALLS);
        // Desks with a chair each.
        let desks = 2 + (rng.unit() * 3.0) as u32;
        for d in 0..desks {
            let x = 0.5 + d as f32 * 1.1 + rng.range(0.0, 0.2);
            let z = rng.range(0.4, 2.2);
            desk(b, v(x, 0.0, z));
            chair(b, v(x + 0.2, 0.0, z + 0.9));
        }
        // A bookshelf against the far wall, full of books.
        let (sx, sz) = (rng.range(0.4, 2.4), ROOM - 0.45);
        b.cuboid(v(sx, 0.0, sz), v(sx + 1.2, 0.05, sz + 0.35), WOOD);
        for s in 0..4 {
            let y = 0.45 * s as f32 + 0.05;
            b.cuboid(v(sx, y, sz), v(sx + 1.2, y + 0.03, sz + 0.35), WOOD);
            let mut x = sx + 0.02;
            for _ in 0..6 {
                let w = rng.range(0.05, 0.18);
                let h = rng.range(0.22, 0.38);
                b.cuboid(v(x, y + 0.03, sz + 0.03), v(x + w, y + 0.03 + h, sz + 0.3), BOOK);
                x += w + 0.01;
            }
        }
        // A standing lamp.
        let (lx, lz) = (ROOM - 0.5, rng.range(0.5, 1.5));
        b.cylinder(v(lx, 0.0, lz), 0.03, 1.5, 8, WOOD);
        b.sphere(v(lx, 1.65, lz), 0.18, 8, 12, LAMP);
    }

    /// The views: outside (the building from above a corner) and inside (a room on a
    /// middle floor, looking through the doors).
    pub fn views(&self) -> Vec<(&'static str, CameraSpec)> {
        let side = self.rooms as f32 * ROOM;
        let height = self.floors as f32 * STOREY;
        let centre = [side * 0.5, height * 0.5, side * 0.5];
        let outside = CameraSpec {
            eye: Some([-0.55 * side, height + 0.6 * side, -0.7 * side]),
            look_at: Some(centre),
            up: Some([0.0, 1.0, 0.0]),
            fov: Some(40.0),
            ..CameraSpec::default()
        };
        let (i, f) = (self.rooms / 2, self.floors / 2);
        let o = [i as f32 * ROOM, f as f32 * STOREY, i as f32 * ROOM];
        let inside = CameraSpec {
            eye: Some([o[0] + 3.5, o[1] + 1.6, o[2] + 2.0]),
            look_at: Some([o[0] - 2.0 * ROOM, o[1] + 1.3, o[2] + 2.0]),
            up: Some([0.0, 1.0, 0.0]),
            fov: Some(60.0),
            ..CameraSpec::default()
        };
        vec![("outside", outside), ("inside", inside)]
    }
}

fn desk(b: &mut Builder, p: Vec3) {
    let v = |x: f32, y: f32, z: f32| p + Vec3::new(x, y, z);
    b.cuboid(v(0.0, 0.72, 0.0), v(0.9, 0.76, 0.6), WOOD);
    for (x, z) in [(0.0, 0.0), (0.85, 0.0), (0.0, 0.55), (0.85, 0.55)] {
        b.cuboid(v(x, 0.0, z), v(x + 0.05, 0.72, z + 0.05), WOOD);
    }
}

fn chair(b: &mut Builder, p: Vec3) {
    let v = |x: f32, y: f32, z: f32| p + Vec3::new(x, y, z);
    b.cuboid(v(0.0, 0.42, 0.0), v(0.45, 0.47, 0.45), FABRIC);
    b.cuboid(v(0.0, 0.47, 0.4), v(0.45, 0.95, 0.45), FABRIC);
    for (x, z) in [(0.0, 0.0), (0.41, 0.0), (0.0, 0.41), (0.41, 0.41)] {
        b.cuboid(v(x, 0.0, z), v(x + 0.04, 0.42, z + 0.04), WOOD);
    }
}
