//! The 3D digital differential analyser of Amanatides & Woo ("A Fast Voxel Traversal
//! Algorithm for Ray Tracing", Eurographics 1987), one voxel per step, as Purcell 2002
//! §3.1.2 uses it in the traversal kernel.
//!
//! The distance to the next cell boundary on each axis is recomputed from the cell index
//! (`(boundary − origin) / dir`) instead of accumulated by `tDelta` additions, so its
//! error stays one rounding deep however long the walk is; the builder's margin covers
//! that error.

use glam::Vec3;

use crate::image::GridView;
use crate::ray::Ray;
use crate::traverse::boxes::clip::clip_ray;

/// One voxel on the ray's path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Voxel {
    /// Index of the cell in GRID_CELLS.
    pub index: u32,
    /// Cell coordinates.
    pub cell: [i32; 3],
    /// Ray parameter where the ray enters the cell.
    pub t_enter: f32,
    /// Ray parameter where the ray leaves the cell (or the end of the ray inside it).
    pub t_exit: f32,
}

/// The DDA's registers: plain data, advanced by [`Dda::step`].
#[derive(Clone, Copy, Debug)]
pub struct Dda {
    cell: [i32; 3],
    step: [i32; 3],
    dims: [i32; 3],
    t_next: [f32; 3],
    t_enter: f32,
    t_end: f32,
    origin: Vec3,
    inv_dir: Vec3,
    grid_min: Vec3,
    cell_size: Vec3,
    done: bool,
}

impl Dda {
    /// Sets up the walk, clipping the ray to the grid box (Purcell's bounding-box test:
    /// a ray that misses the scene ends here and `None` is returned).
    pub fn new(grid: &GridView<'_>, ray: &Ray) -> Option<Dda> {
        if !ray.is_valid() {
            return None;
        }
        let (t0, t1) = clip_ray(ray, grid.min, grid.max)?;
        let dims = [grid.dims[0] as i32, grid.dims[1] as i32, grid.dims[2] as i32];
        let p = ray.at(t0);
        let mut dda = Dda {
            cell: [0; 3],
            step: [0; 3],
            dims,
            t_next: [f32::INFINITY; 3],
            t_enter: t0,
            t_end: t1,
            origin: ray.origin,
            inv_dir: Vec3::ZERO,
            grid_min: grid.min,
            cell_size: grid.cell_size,
            done: false,
        };
        for a in 0..3 {
            // Clamping puts a start point that rounding left just outside into the edge cell.
            let c = libm::floorf((p[a] - grid.min[a]) / grid.cell_size[a]);
            let c = if c.is_nan() { 0.0 } else { c };
            dda.cell[a] = (c.max(0.0) as i32).min(dims[a] - 1);
            let d = ray.dir[a];
            if d > 0.0 {
                dda.step[a] = 1;
            } else if d < 0.0 {
                dda.step[a] = -1;
            }
            dda.inv_dir[a] = if d != 0.0 { 1.0 / d } else { 0.0 };
            dda.t_next[a] = dda.boundary_t(a);
        }
        Some(dda)
    }

    /// Ray parameter of the boundary the ray crosses next on axis `a`.
    #[inline]
    fn boundary_t(&self, a: usize) -> f32 {
        let k = match self.step[a] {
            1 => self.cell[a] + 1,
            -1 => self.cell[a],
            _ => return f32::INFINITY,
        };
        let plane = self.grid_min[a] + k as f32 * self.cell_size[a];
        (plane - self.origin[a]) * self.inv_dir[a]
    }

    /// Returns the current voxel and advances to the next one; `None` once the ray has
    /// left the grid or passed its `t_max`.
    #[inline]
    pub fn step(&mut self) -> Option<Voxel> {
        if self.done {
            return None;
        }
        // Axis whose boundary comes first; ties go to the lowest axis.
        let mut axis = 0;
        if self.t_next[1] < self.t_next[axis] {
            axis = 1;
        }
        if self.t_next[2] < self.t_next[axis] {
            axis = 2;
        }
        let t_boundary = self.t_next[axis];
        let t_exit = if t_boundary < self.t_end { t_boundary.max(self.t_enter) } else { self.t_end };
        let [x, y, z] = self.cell;
        let voxel = Voxel {
            index: (x + self.dims[0] * (y + self.dims[1] * z)) as u32,
            cell: self.cell,
            t_enter: self.t_enter,
            t_exit,
        };
        if t_boundary >= self.t_end {
            self.done = true;
        } else {
            self.cell[axis] += self.step[axis];
            if self.cell[axis] < 0 || self.cell[axis] >= self.dims[axis] {
                self.done = true;
            } else {
                self.t_next[axis] = self.boundary_t(axis);
                self.t_enter = t_exit;
            }
        }
        Some(voxel)
    }
}

impl Iterator for Dda {
    type Item = Voxel;

    fn next(&mut self) -> Option<Voxel> {
        self.step()
    }
}
