//! Cross-crate suites for raypipe (see `tests/`): the grid-vs-brute-force property
//! suite, the scene-image corruption suite and the golden images. This library holds
//! the helpers they share. The command-line suite lives in `host/tests/cli.rs`, because
//! cargo tells only the binary's own package where the built `raypipe` is.

pub mod hw_configs;
pub mod instanced_soup;
pub mod soup_rays;

use std::path::{Path, PathBuf};

use raypipe::build::grid::GridResolution;
use raypipe::input::mesh::Mesh;
use raypipe::platform::aligned::AlignedBytes;
use raypipe::render::Frame;
use raypipe::scene::{self, Accel, BuildOptions, Scene, TriangleLayout};
use raypipe_core::image::{SectionEntry, SectionKind};
use raypipe_core::{SceneError, SceneView};

/// Builds a scene image with a triangle layout besides the indexed one (Wald's
/// precomputed triangles, or leaf blocks).
pub fn build_soup_layout(
    positions: Vec<[f32; 3]>,
    triangles: Vec<[u32; 3]>,
    accel: Accel,
    layout: TriangleLayout,
) -> Scene {
    let mesh = Mesh { positions, triangles, ..Default::default() };
    let opts = BuildOptions { accel, triangles: layout, ..Default::default() };
    scene::build("soup".into(), mesh, Vec::new(), Default::default(), &opts).expect("soup builds")
}

/// Builds a scene image (any structure) from raw triangles.
pub fn build_soup(positions: Vec<[f32; 3]>, triangles: Vec<[u32; 3]>, accel: Accel, min_dim: u32) -> Scene {
    let mesh = Mesh { positions, triangles, ..Default::default() };
    let opts = BuildOptions { accel, grid: GridResolution::MinDim(min_dim), ..Default::default() };
    scene::build("soup".into(), mesh, Vec::new(), Default::default(), &opts).expect("soup builds")
}

/// The section table of an image (its entries in file order).
pub fn section_table(bytes: &[u8]) -> Vec<SectionEntry> {
    let n = u32::from_le_bytes(bytes[20..24].try_into().unwrap()) as usize;
    bytes[64..64 + 16 * n]
        .chunks_exact(16)
        .map(|e| {
            let w = |k: usize| u32::from_le_bytes(e[4 * k..4 * k + 4].try_into().unwrap());
            SectionEntry { kind: w(0), offset: w(1), size: w(2), count: w(3) }
        })
        .collect()
}

/// Where the table entry of section `kind` is in the image, and the entry.
pub fn section_entry(bytes: &[u8], kind: SectionKind) -> (usize, SectionEntry) {
    let (i, e) = section_table(bytes).into_iter().enumerate().find(|(_, e)| e.kind == kind as u32).unwrap();
    (64 + 16 * i, e)
}

/// Writes a little-endian `u32` at byte `at`.
pub fn put_u32(bytes: &mut [u8], at: usize, v: u32) {
    bytes[at..at + 4].copy_from_slice(&v.to_le_bytes());
}

/// The built-in Cornell box's image with structure `accel`.
pub fn cornell_with(accel: Accel) -> AlignedBytes {
    AlignedBytes::from_slice(&scene::load_default(&BuildOptions { accel, ..Default::default() }).unwrap().image)
}

/// `base` edited by `edit`, resealed, and the error `parse` must give it.
pub fn corrupt_image(base: &[u8], edit: impl FnOnce(&mut [u8])) -> SceneError {
    let mut b = AlignedBytes::from_slice(base);
    edit(&mut b);
    reseal(&mut b);
    SceneView::parse(&b).expect_err("corruption must be rejected")
}

/// Recomputes the checksum after a test has edited an image on purpose, so the
/// structural check behind the checksum is what gets exercised.
pub fn reseal(bytes: &mut [u8]) {
    bytes[28..32].copy_from_slice(&[0; 4]);
    let c = raypipe_core::image::crc32(bytes);
    bytes[28..32].copy_from_slice(&c.to_le_bytes());
}

/// The repository root (for fixtures).
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Reads an 8-bit RGB PNG.
pub fn decode_png(path: &Path) -> Frame {
    let file = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut reader = png::Decoder::new(std::io::BufReader::new(file)).read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    buf.truncate(info.buffer_size());
    let pixels = buf.chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
    Frame { width: info.width, height: info.height, pixels, radiance: Vec::new() }
}

/// Compares `frame` with `fixtures/golden/<name>` pixel for pixel (rendering is
/// deterministic). With `RAYPIPE_BLESS` set, writes the golden image instead: look at it.
pub fn check_golden(name: &str, frame: &Frame) {
    let path = root().join("fixtures/golden").join(name);
    if std::env::var_os("RAYPIPE_BLESS").is_some() {
        raypipe::output::write_png(&path, frame.width, frame.height, &frame.pixels).unwrap();
        return;
    }
    let golden = decode_png(&path);
    assert_eq!((frame.width, frame.height), (golden.width, golden.height), "{name}: size");
    let differing = frame.pixels.iter().zip(&golden.pixels).filter(|(a, b)| a != b).count();
    assert_eq!(differing, 0, "{name}: {differing} pixels differ from the golden image");
}
