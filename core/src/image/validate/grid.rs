//! GRID, GRID_CELLS and PRIM_LISTS of Purcell's uniform grid: a grid that covers the
//! scene, cells that each start their own null-terminated list, entries that name
//! triangles.

use glam::Vec3;

use crate::image::error::SceneError;
use crate::image::header::SectionKind;
use crate::image::records::{GridRecord, NULL_INDEX};
use crate::image::sections::{finite3, Sections};
use crate::image::structure_views::GridView;

use super::indices::indices_below;

/// The grid of an image whose scene bounds are `bmin..bmax` and which holds `nt` triangles.
pub(in crate::image) fn grid<'a>(
    s: &Sections<'a>,
    nt: u32,
    bmin: Vec3,
    bmax: Vec3,
) -> Result<GridView<'a>, SceneError> {
    use SectionKind as K;
    let rec: &[GridRecord] = s.required(K::Grid)?;
    let rec = rec.first().ok_or(SceneError::CountMismatch { section: K::Grid, expected: 1, found: 0 })?;
    if s.count(K::Grid) != 1 {
        return Err(SceneError::CountMismatch { section: K::Grid, expected: 1, found: s.count(K::Grid) });
    }
    if !finite3(rec.bounds_min) || !finite3(rec.bounds_max) || !finite3(rec.cell_size) {
        return Err(SceneError::NonFinite { section: K::Grid, record: 0 });
    }
    let cells_expected = rec.dims.iter().try_fold(1u32, |acc, &d| if d == 0 { None } else { acc.checked_mul(d) });
    let cell_count = match cells_expected {
        Some(c) if c == rec.cell_count && c < NULL_INDEX => c,
        _ => return Err(SceneError::BadGrid),
    };
    let (gmin, gmax, cs) = (Vec3::from(rec.bounds_min), Vec3::from(rec.bounds_max), Vec3::from(rec.cell_size));
    if !cs.cmpgt(Vec3::ZERO).all() || !gmin.cmplt(gmax).all() || rec.dims.iter().any(|&d| d > (1 << 24)) {
        return Err(SceneError::BadGrid);
    }
    if !(gmin.cmple(bmin).all() && gmax.cmpge(bmax).all()) {
        return Err(SceneError::OutOfBounds { section: K::Grid, record: 0 });
    }
    let cells: &[u32] = s.required(K::GridCells)?;
    if cells.len() as u32 != cell_count {
        return Err(SceneError::CountMismatch {
            section: K::GridCells,
            expected: cell_count,
            found: cells.len() as u32,
        });
    }
    let lists: &[u32] = s.required(K::PrimLists)?;
    let nl = lists.len() as u32;
    // Each full cell starts its own list: offsets grow from cell to cell and each one
    // follows a terminator (or is 0). So the lists a ray's cells hold are disjoint, and
    // a ray tests at most as many entries as the section holds (docs/scene-format.md,
    // "Work bounds").
    let mut next_free = 0u32;
    for (i, &c) in cells.iter().enumerate() {
        if c == NULL_INDEX {
            continue;
        }
        if c >= nl {
            return Err(SceneError::IndexOutOfRange { section: K::GridCells, record: i as u32, value: c, limit: nl });
        }
        let starts_a_list = c == 0 || lists.get(c as usize - 1) == Some(&NULL_INDEX);
        if c < next_free || !starts_a_list {
            return Err(SceneError::SharedList { cell: i as u32 });
        }
        next_free = c + 1;
    }
    // A walk from any offset ends at a null entry inside the section because the last
    // entry is null; every other entry must name a triangle.
    if lists.last().is_some_and(|&l| l != NULL_INDEX) {
        return Err(SceneError::UnterminatedList);
    }
    indices_below(K::PrimLists, lists.iter().copied(), nt, true)?;
    Ok(GridView {
        min: gmin,
        max: gmax,
        cell_size: cs,
        dims: rec.dims,
        cells,
        lists,
        cells_addr: s.addr(K::GridCells),
        lists_addr: s.addr(K::PrimLists),
        wrap: None,
    })
}
