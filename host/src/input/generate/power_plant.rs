//! A stand-in for the UNC power plant that Wald & Slusallek 2001 §6 render (12.5 M
//! triangles; "80 meter high and 40 by 50 meters on either side"), generated as a stream
//! so that scenes of any size can be bricked without ever being held in memory: an open
//! steel frame of columns and beams around eight storeys of grated floors, a full-height
//! boiler hall with three large boilers and nothing else (the large empty space), stairs
//! up one corner, machinery on every floor, and dense pipework — horizontal runs on each
//! floor and risers through the floors — that grows until the requested triangle count
//! is reached. The same parameters give the same triangles in the same order.

use anyhow::Result;
use glam::Vec3;
use raypipe_core::image::MaterialRecord;

use crate::input::camera_file::CameraSpec;
use crate::input::generate::shapes::Lcg;

/// Width (x), depth (z) and height (y) of the building, in metres (the paper's).
const SIZE: Vec3 = Vec3::new(50.0, 80.0, 40.0);
/// Storeys of the floored part.
const STOREYS: u32 = 8;
/// The boiler hall takes x below this, from the ground to the roof.
const HALL: f32 = 16.0;
/// Distance between a pipe's rings (their side is cut into this many metres).
const RING: f32 = 0.25;

// Materials.
const CONCRETE: u32 = 0;
const STEEL: u32 = 1;
const PIPE: u32 = 2; // 2..=4: red, green, blue pipes
const YELLOW: u32 = 5;
const BOILER: u32 = 6;

/// Generator parameters.
pub struct PowerPlant {
    /// At least this many triangles (pipework is added until it is reached).
    pub triangles: u64,
    /// Placement seed.
    pub seed: u32,
}

/// Hands triangles on with their material.
type Emit<'a> = dyn FnMut([Vec3; 3], u32) -> Result<()> + 'a;

impl PowerPlant {
    /// The materials.
    pub fn materials() -> Vec<MaterialRecord> {
        let c = |r: f32, g: f32, b: f32| MaterialRecord { diffuse: [r, g, b], ..MaterialRecord::DEFAULT };
        vec![
            c(0.6, 0.6, 0.58),
            c(0.45, 0.5, 0.55),
            c(0.7, 0.15, 0.1),
            c(0.15, 0.55, 0.2),
            c(0.15, 0.3, 0.7),
            c(0.85, 0.7, 0.1),
            c(0.7, 0.55, 0.4),
        ]
    }

    /// The outside and inside views.
    pub fn views() -> Vec<(&'static str, CameraSpec)> {
        let centre = SIZE * 0.5;
        let outside = CameraSpec {
            eye: Some([-45.0, 95.0, -70.0]),
            look_at: Some(centre.to_array()),
            up: Some([0.0, 1.0, 0.0]),
            fov: Some(45.0),
            ..CameraSpec::default()
        };
        let inside = CameraSpec {
            eye: Some([1.5, 30.0, 13.5]),
            look_at: Some([45.0, 20.0, 22.0]),
            up: Some([0.0, 1.0, 0.0]),
            fov: Some(60.0),
            ..CameraSpec::default()
        };
        vec![("outside", outside), ("inside", inside)]
    }

    /// Emits every triangle, in order.
    pub fn stream(&self, emit: &mut Emit<'_>) -> Result<()> {
        let mut n = 0u64;
        let mut count = |t: [Vec3; 3], m: u32| {
            n += 1;
            emit(t, m)
        };
        frame(&mut count)?;
        hall(&mut count)?;
        floors(&mut count)?;
        stairs(&mut count)?;
        let mut rng = Lcg::new(self.seed);
        machinery(&mut rng, &mut count)?;
        let mut rng = Lcg::new(self.seed ^ 0x9e37_79b9);
        let mut emitted = n;
        while emitted < self.triangles {
            emitted += pipe(&mut rng, emit)?;
        }
        Ok(())
    }
}

/// An axis-aligned box (12 triangles).
fn cuboid(lo: Vec3, hi: Vec3, m: u32, emit: &mut Emit<'_>) -> Result<()> {
    let p = |x: bool, y: bool, z: bool| {
        Vec3::new(if x { hi.x } else { lo.x }, if y { hi.y } else { lo.y }, if z { hi.z } else { lo.z })
    };
    let faces = [
        [p(false, false, false), p(false, true, false), p(true, true, false), p(true, false, false)],
        [p(false, false, true), p(true, false, true), p(true, true, true), p(false, true, true)],
        [p(false, false, false), p(false, false, true), p(false, true, true), p(false, true, false)],
        [p(true, false, false), p(true, true, false), p(true, true, true), p(true, false, true)],
        [p(false, false, false), p(true, false, false), p(true, false, true), p(false, false, true)],
        [p(false, true, false), p(false, true, true), p(true, true, true), p(true, true, false)],
    ];
    for [a, b, c, d] in faces {
        emit([a, b, c], m)?;
        emit([a, c, d], m)?;
    }
    Ok(())
}

/// The side of a cylinder of `radius` along `axis` from `base` for `length`, in rings
/// of [`RING`] metres and `segments` around. Returns the triangles emitted.
fn cylinder(
    base: Vec3,
    axis: usize,
    radius: f32,
    length: f32,
    segments: u32,
    m: u32,
    emit: &mut Emit<'_>,
) -> Result<u64> {
    let rings = (length / RING).ceil().max(1.0) as u32;
    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
    let at = |k: u32, s: u32| {
        let a = std::f32::consts::TAU * (s % segments) as f32 / segments as f32;
        let mut p = base;
        p[axis] += length * k as f32 / rings as f32;
        p[u] += radius * a.cos();
        p[v] += radius * a.sin();
        p
    };
    for k in 0..rings {
        for s in 0..segments {
            let (a, b, c, d) = (at(k, s), at(k, s + 1), at(k + 1, s + 1), at(k + 1, s));
            emit([a, b, c], m)?;
            emit([a, c, d], m)?;
        }
    }
    Ok(2 * rings as u64 * segments as u64)
}

/// The steel frame: columns every 5 m around the outside and the roof's beams.
fn frame(emit: &mut Emit<'_>) -> Result<()> {
    let h = SIZE.y;
    let mut x = 0.0;
    while x <= SIZE.x {
        for z in [0.0, SIZE.z] {
            cuboid(Vec3::new(x - 0.3, 0.0, z - 0.3), Vec3::new(x + 0.3, h, z + 0.3), STEEL, emit)?;
        }
        cuboid(Vec3::new(x - 0.2, h - 0.8, 0.0), Vec3::new(x + 0.2, h, SIZE.z), STEEL, emit)?;
        x += 5.0;
    }
    let mut z = 5.0;
    while z < SIZE.z {
        for x in [0.0, SIZE.x] {
            cuboid(Vec3::new(x - 0.3, 0.0, z - 0.3), Vec3::new(x + 0.3, h, z + 0.3), STEEL, emit)?;
        }
        z += 5.0;
    }
    // The ground.
    cuboid(Vec3::new(-20.0, -1.0, -20.0), Vec3::new(SIZE.x + 20.0, 0.0, SIZE.z + 20.0), CONCRETE, emit)
}

/// The boiler hall: three boilers, 40 m high, in a space otherwise empty.
fn hall(emit: &mut Emit<'_>) -> Result<()> {
    for k in 0..3 {
        let z = 7.0 + 13.0 * k as f32;
        cylinder(Vec3::new(HALL * 0.5, 2.0, z), 1, 4.5, 40.0, 48, BOILER, emit)?;
        cuboid(Vec3::new(HALL * 0.5 - 5.0, 0.0, z - 5.0), Vec3::new(HALL * 0.5 + 5.0, 2.0, z + 5.0), CONCRETE, emit)?;
    }
    Ok(())
}

/// The storeys' floor slabs, each with a stairwell opening.
fn floors(emit: &mut Emit<'_>) -> Result<()> {
    let storey = SIZE.y / STOREYS as f32;
    for f in 1..STOREYS {
        let y = storey * f as f32;
        cuboid(Vec3::new(HALL, y - 0.3, 0.0), Vec3::new(SIZE.x - 5.0, y, SIZE.z), CONCRETE, emit)?;
        cuboid(Vec3::new(SIZE.x - 5.0, y - 0.3, 5.0), Vec3::new(SIZE.x, y, SIZE.z), CONCRETE, emit)?;
    }
    Ok(())
}

/// A flight of 25 steps per storey in the corner stairwell.
fn stairs(emit: &mut Emit<'_>) -> Result<()> {
    let storey = SIZE.y / STOREYS as f32;
    for f in 0..STOREYS - 1 {
        for s in 0..25 {
            let y = storey * f as f32 + storey * s as f32 / 25.0;
            let z = 0.2 * s as f32;
            cuboid(Vec3::new(SIZE.x - 4.5, y, z), Vec3::new(SIZE.x - 0.5, y + storey / 25.0, z + 0.25), YELLOW, emit)?;
        }
    }
    Ok(())
}

/// Pumps, tanks and cabinets on every floor.
fn machinery(rng: &mut Lcg, emit: &mut Emit<'_>) -> Result<()> {
    let storey = SIZE.y / STOREYS as f32;
    for f in 0..STOREYS - 1 {
        let y = storey * f as f32;
        for _ in 0..40 {
            let (x, z) = (rng.range(HALL + 1.0, SIZE.x - 7.0), rng.range(1.0, SIZE.z - 3.0));
            let (w, h, d) = (rng.range(0.5, 3.0), rng.range(0.8, 4.0), rng.range(0.5, 2.5));
            cuboid(Vec3::new(x, y, z), Vec3::new(x + w, y + h, z + d), STEEL, emit)?;
            if rng.unit() < 0.4 {
                let r = rng.range(0.4, 1.2);
                cylinder(Vec3::new(x + w * 0.5, y + h, z + d * 0.5), 1, r, rng.range(1.0, 3.0), 24, BOILER, emit)?;
            }
        }
    }
    Ok(())
}

/// One pipe: a horizontal run across a storey or a riser through several; returns the
/// triangles emitted.
fn pipe(rng: &mut Lcg, emit: &mut Emit<'_>) -> Result<u64> {
    let storey = SIZE.y / STOREYS as f32;
    let f = (rng.unit() * (STOREYS - 1) as f32) as u32;
    let m = PIPE + (rng.unit() * 3.0) as u32 % 3;
    let radius = 0.03 + 0.35 * rng.unit() * rng.unit();
    let segments = if radius > 0.2 { 16 } else { 8 };
    let kind = rng.unit();
    if kind < 0.2 {
        // A riser through one to four storeys.
        let (x, z) = (rng.range(HALL + 0.5, SIZE.x - 6.0), rng.range(0.5, SIZE.z - 0.5));
        let len = storey * (1.0 + (rng.unit() * 4.0).floor());
        let y0 = storey * f as f32;
        return cylinder(Vec3::new(x, y0, z), 1, radius, len.min(SIZE.y - y0), segments, m, emit);
    }
    let y = storey * f as f32 + rng.range(2.5, storey - 0.6);
    let along_x = kind < 0.6;
    let len = rng.range(3.0, 20.0);
    let base = if along_x {
        Vec3::new(rng.range(HALL, SIZE.x - len), y, rng.range(0.5, SIZE.z - 0.5))
    } else {
        Vec3::new(rng.range(HALL + 0.5, SIZE.x - 0.5), y, rng.range(0.0, SIZE.z - len))
    };
    cylinder(base, if along_x { 0 } else { 2 }, radius, len, segments, m, emit)
}
