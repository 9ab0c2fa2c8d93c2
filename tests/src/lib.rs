//! Cross-crate suites for raypipe (see `tests/`): the grid-vs-brute-force property
//! suite, the scene-image corruption suite and the golden images. This library holds
//! the helpers they share. The command-line suite lives in `host/tests/cli.rs`, because
//! cargo tells only the binary's own package where the built `raypipe` is.

use raypipe::grid_builder::GridResolution;
use raypipe::mesh::Mesh;
use raypipe::scene::{self, Accel, BuildOptions, Scene};

/// Builds a scene image with Wald's precomputed triangles as well.
pub fn build_soup_wald(positions: Vec<[f32; 3]>, triangles: Vec<[u32; 3]>, accel: Accel) -> Scene {
    let mesh = Mesh { positions, triangles, ..Default::default() };
    let opts = BuildOptions { accel, triangles: raypipe::scene::TriangleLayout::Wald, ..Default::default() };
    scene::build("soup".into(), mesh, Vec::new(), Default::default(), &opts).expect("soup builds")
}

/// Builds a scene image (any structure) from raw triangles.
pub fn build_soup(positions: Vec<[f32; 3]>, triangles: Vec<[u32; 3]>, accel: Accel, min_dim: u32) -> Scene {
    let mesh = Mesh { positions, triangles, ..Default::default() };
    let opts = BuildOptions { accel, grid: GridResolution::MinDim(min_dim), ..Default::default() };
    scene::build("soup".into(), mesh, Vec::new(), Default::default(), &opts).expect("soup builds")
}

/// Recomputes the checksum after a test has edited an image on purpose, so the
/// structural check behind the checksum is what gets exercised.
pub fn reseal(bytes: &mut [u8]) {
    bytes[28..32].copy_from_slice(&[0; 4]);
    let c = raypipe_core::image::crc32(bytes);
    bytes[28..32].copy_from_slice(&c.to_le_bytes());
}
