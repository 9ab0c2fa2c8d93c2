//! Small meshes the builders' tests share: strips, slivers and scattered triangles.

use crate::input::mesh::Mesh;

/// A strip of `n` thin triangles along x.
pub(crate) fn strip(n: u32) -> Mesh {
    let positions = (0..=n).flat_map(|i| [[i as f32, 0.0, 0.0], [i as f32, 1.0, 0.0]]).collect();
    let triangles = (0..n).map(|i| [2 * i, 2 * i + 2, 2 * i + 1]).collect();
    Mesh { positions, triangles, ..Default::default() }
}

/// `n` long slivers crossing the unit square diagonally, each offset a little along y:
/// their boxes all overlap, the case spatial splits are for.
pub(crate) fn slivers(n: u32) -> Mesh {
    let mut positions = Vec::new();
    for i in 0..n {
        let y = i as f32 / n as f32;
        positions.extend([[0.0, y, 0.0], [1.0, y + 1.0, 0.0], [1.0, y + 1.0, 0.01]]);
    }
    let triangles = (0..n).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
    Mesh { positions, triangles, ..Default::default() }
}

/// Random small triangles in a unit cube.
pub(crate) fn scatter(n: u32, seed: u64) -> Mesh {
    let mut x = seed;
    let mut next = move || {
        x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (x >> 40) as f32 / (1u64 << 24) as f32
    };
    let mut positions = Vec::new();
    for _ in 0..n {
        let c = [next(), next(), next()];
        for _ in 0..3 {
            positions.push([c[0] + 0.05 * next(), c[1] + 0.05 * next(), c[2] + 0.05 * next()]);
        }
    }
    let triangles = (0..n).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
    Mesh { positions, triangles, ..Default::default() }
}
