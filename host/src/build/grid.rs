//! Builds Purcell's uniform grid (Purcell 2002 §4.1, Figure 4): near-cubical voxels, each
//! cell a pointer into a list of triangle indices terminated by a null entry.
//!
//! Resolution: Purcell fixes the number of cells along the scene's shortest axis (64
//! for the 70k-triangle bunny, giving 98×64×163) and makes voxels cubical. By default we
//! derive that number from the triangle count, aiming at [`DEFAULT_CELLS_PER_TRIANGLE`]
//! cells per triangle; `--grid-min-dim` sets it directly.
//!
//! Conservativeness: a triangle is referenced by every cell whose box, grown by a margin
//! of [`CELL_MARGIN`] of a cell plus a few ulps of the coordinates, it overlaps by the
//! exact SAT test. The margin absorbs the traversal's rounding, which is what lets the
//! grid return exactly the brute-force hit.

use anyhow::{bail, Result};
use glam::DVec3;
use raypipe_core::image::{GridRecord, NULL_INDEX};

use crate::build::tri_box;
use crate::input::mesh::Mesh;

/// Default target of grid cells per triangle.
pub const DEFAULT_CELLS_PER_TRIANGLE: f64 = 2.0;
/// Margin added around each cell in the overlap test, as a fraction of the smallest cell side.
pub const CELL_MARGIN: f64 = 1e-3;
/// Largest number of cells along one axis (larger requests get bigger voxels).
pub const MAX_DIM: u32 = 4096;
/// Largest number of cells in all.
pub const MAX_CELLS: u64 = 1 << 26;

/// How to size the grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GridResolution {
    /// Derived from the triangle count (cells ≈ density × triangles).
    Auto {
        /// Target cells per triangle.
        cells_per_triangle: f64,
    },
    /// Cells along the shortest (non-flat) axis, Purcell's parameter.
    MinDim(u32),
}

impl Default for GridResolution {
    fn default() -> Self {
        GridResolution::Auto { cells_per_triangle: DEFAULT_CELLS_PER_TRIANGLE }
    }
}

/// A built grid, ready for the image writer.
#[derive(Clone, Debug)]
pub struct BuiltGrid {
    /// The GRID record.
    pub record: GridRecord,
    /// One entry per cell: list offset or null.
    pub cells: Vec<u32>,
    /// The lists, each ending with a null entry.
    pub lists: Vec<u32>,
    /// Triangle references (list entries without terminators).
    pub references: u64,
    /// Cells with at least one triangle.
    pub full_cells: u64,
}

fn next_down(x: f32) -> f32 {
    x.next_down()
}

fn next_up(x: f32) -> f32 {
    x.next_up()
}

/// The grid's box: the scene bounds grown by a small margin on every side, so that a flat
/// scene still has a thickness and geometry never lies on the boundary.
pub fn grid_bounds(lo: [f32; 3], hi: [f32; 3]) -> (DVec3, DVec3) {
    let (lo, hi) = (DVec3::from(lo.map(f64::from)), DVec3::from(hi.map(f64::from)));
    let extent = (hi - lo).max_element();
    let mag = lo.abs().max(hi.abs()).max_element();
    let pad = 1e-4 * extent + 1e-5 * mag + 1e-6;
    // Round outwards to f32 so the stored box still contains the padded box.
    let mut gmin = DVec3::ZERO;
    let mut gmax = DVec3::ZERO;
    for a in 0..3 {
        gmin[a] = next_down((lo[a] - pad) as f32) as f64;
        gmax[a] = next_up((hi[a] + pad) as f32) as f64;
    }
    (gmin, gmax)
}

/// Chooses the cells per axis for a grid box and triangle count.
pub fn choose_dims(gmin: DVec3, gmax: DVec3, triangles: usize, res: GridResolution) -> Result<[u32; 3]> {
    let ext = gmax - gmin;
    let longest = ext.max_element();
    // Axes thinner than this are "flat": one cell thick.
    let thick: Vec<usize> = (0..3).filter(|&a| ext[a] > 1e-3 * longest).collect();
    let side = match res {
        GridResolution::MinDim(0) => bail!("--grid-min-dim must be at least 1"),
        GridResolution::MinDim(n) => thick.iter().map(|&a| ext[a]).fold(f64::INFINITY, f64::min) / n as f64,
        GridResolution::Auto { cells_per_triangle } => {
            if cells_per_triangle.is_nan() || cells_per_triangle <= 0.0 || cells_per_triangle.is_infinite() {
                bail!("grid density must be positive");
            }
            let target = (cells_per_triangle * triangles as f64).max(1.0);
            let measure: f64 = thick.iter().map(|&a| ext[a]).product();
            (measure / target).powf(1.0 / thick.len() as f64)
        }
    };
    // Grow the voxels (still cubical) until the grid fits the per-axis and total limits:
    // a nearly flat scene with a large --grid-min-dim would otherwise ask for millions.
    // At most MAX_CELLS, and at most 256 cells per triangle (Purcell's bunny has 15).
    let max_cells = MAX_CELLS.min((256 * triangles as u64).max(1 << 20));
    let measure: f64 = thick.iter().map(|&a| ext[a]).product();
    let fit_axis = longest / MAX_DIM as f64;
    let fit_total = (measure / max_cells as f64).powf(1.0 / thick.len().max(1) as f64);
    let side = side.max(fit_axis).max(fit_total);
    let mut dims = [1u32; 3];
    for &a in &thick {
        dims[a] = ((ext[a] / side).round().max(1.0) as u32).min(MAX_DIM);
    }
    while dims.iter().map(|&d| d as u64).product::<u64>() > max_cells {
        // Rounding can still overshoot by a little: shave the largest axis.
        let a = (0..3).max_by_key(|&a| dims[a]).unwrap_or(0);
        dims[a] -= 1;
    }
    Ok(dims)
}

/// Builds the grid over `mesh`.
pub fn build_grid(mesh: &Mesh, res: GridResolution) -> Result<BuiltGrid> {
    let (lo, hi) = mesh.bounds();
    // A brick's grid keeps the whole scene's margin besides its own.
    let extra =
        mesh.margin_bounds.map_or(0.0, |(a, b)| 1e-5 * (0..3).map(|k| f64::from(b[k] - a[k])).fold(0.0, f64::max));
    let grow = |p: [f32; 3], s: f64| p.map(|c| (f64::from(c) + s * extra) as f32);
    let (lo, hi) = if extra > 0.0 { (grow(lo, -1.0).map(next_down), grow(hi, 1.0).map(next_up)) } else { (lo, hi) };
    let (gmin, gmax) = grid_bounds(lo, hi);
    let dims = choose_dims(gmin, gmax, mesh.triangles.len(), res)?;
    let cell_size_f32: [f32; 3] = std::array::from_fn(|a| ((gmax[a] - gmin[a]) / dims[a] as f64) as f32);
    // The builder uses exactly the f32 cell geometry the traversal kernel uses.
    let cs = DVec3::from(cell_size_f32.map(f64::from));
    let mag = gmin.abs().max(gmax.abs()).max_element();
    let margin = CELL_MARGIN * cs.min_element() + 4.0 * mag * f64::from(f32::EPSILON) + extra;
    let half = cs * 0.5 + DVec3::splat(margin);
    let d = [dims[0] as i64, dims[1] as i64, dims[2] as i64];
    let cell_count = (dims[0] as u64 * dims[1] as u64 * dims[2] as u64) as usize;

    // Pass 1: (cell, triangle) references, triangles in increasing order.
    let mut refs: Vec<(u32, u32)> = Vec::new();
    for (prim, tri) in mesh.triangles.iter().enumerate() {
        let v = tri.map(|i| DVec3::from(mesh.positions[i as usize].map(f64::from)));
        let tlo = v[0].min(v[1]).min(v[2]) - DVec3::splat(margin);
        let thi = v[0].max(v[1]).max(v[2]) + DVec3::splat(margin);
        let range = |a: usize| {
            let i0 = ((tlo[a] - gmin[a]) / cs[a]).floor() as i64;
            let i1 = ((thi[a] - gmin[a]) / cs[a]).floor() as i64;
            (i0.clamp(0, d[a] - 1), i1.clamp(0, d[a] - 1))
        };
        let (x0, x1) = range(0);
        let (y0, y1) = range(1);
        let (z0, z1) = range(2);
        for z in z0..=z1 {
            for y in y0..=y1 {
                for x in x0..=x1 {
                    let centre = gmin + (DVec3::new(x as f64, y as f64, z as f64) + 0.5) * cs;
                    if tri_box::overlaps(v, centre, half) {
                        refs.push(((x + d[0] * (y + d[1] * z)) as u32, prim as u32));
                    }
                }
            }
        }
    }
    // Pass 2: lists by counting sort on the cell (stable, so triangles stay ordered).
    let mut counts = vec![0u32; cell_count];
    for &(c, _) in &refs {
        counts[c as usize] += 1;
    }
    let mut cells = vec![NULL_INDEX; cell_count];
    let mut next = 0u64;
    let mut cursor = vec![0u32; cell_count];
    let mut full_cells = 0;
    for c in 0..cell_count {
        if counts[c] > 0 {
            cells[c] = next as u32;
            cursor[c] = next as u32;
            next += counts[c] as u64 + 1;
            full_cells += 1;
        }
    }
    if next >= NULL_INDEX as u64 {
        bail!("grid lists would have {next} entries; lower --grid-min-dim");
    }
    let mut lists = vec![NULL_INDEX; next as usize];
    for &(c, prim) in &refs {
        lists[cursor[c as usize] as usize] = prim;
        cursor[c as usize] += 1;
    }
    let record = GridRecord {
        bounds_min: gmin.as_vec3().to_array(),
        _pad0: 0,
        bounds_max: gmax.as_vec3().to_array(),
        _pad1: 0,
        cell_size: cell_size_f32,
        _pad2: 0,
        dims,
        cell_count: cell_count as u32,
    };
    Ok(BuiltGrid { record, cells, lists, references: refs.len() as u64, full_cells })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearly_flat_scenes_get_bigger_voxels_instead_of_an_error() {
        let (lo, hi) = (DVec3::new(-2.0, 0.0, -2.0), DVec3::new(2.0, 0.005, 2.0));
        let dims = choose_dims(lo, hi, 10, GridResolution::MinDim(64)).unwrap();
        assert!(dims.iter().all(|&d| d <= MAX_DIM), "{dims:?}");
        assert!(dims.iter().map(|&d| d as u64).product::<u64>() <= MAX_CELLS);
        // Near-cubical voxels still: x and z get the same count.
        assert_eq!(dims[0], dims[2]);
        assert!(choose_dims(lo, hi, 10, GridResolution::MinDim(0)).is_err());
    }

    #[test]
    fn purcell_resolution_for_a_bunny_shaped_box() {
        // Purcell used 64 cells on the shortest axis of the bunny: 98 × 64 × 163.
        let (lo, hi) = (DVec3::new(0.0, 0.0, 0.0), DVec3::new(98.0, 64.0, 163.0));
        assert_eq!(choose_dims(lo, hi, 69451, GridResolution::MinDim(64)).unwrap(), [98, 64, 163]);
    }
}
