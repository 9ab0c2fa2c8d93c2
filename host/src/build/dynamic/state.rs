//! [`DynamicState`]: what moves in an animated instanced scene, and the commit that
//! brings the structures up to date.

use std::time::Instant;

use anyhow::{anyhow, bail, Result};
use glam::Vec3A;
use raypipe_core::image::instanced::{index_layout, InstanceRecord, TopLevel, TopParts};
use raypipe_core::image::{BvhNode, FrameGeometry, GridLevel, Header, Position};
use raypipe_core::math::affine::Affine34;

use super::images::BaseViews;
use super::lbvh::build_lbvh;
use super::refit::{bounds_of, margin_for, refit, sah_cost};
use super::reinhard::HierGrid;
use super::Update;
use crate::build::box_bvh::{build_box_bvh, BoxBvh};
use crate::build::instanced::{inverse, world_box, InstancedScene};
use crate::render::instanced::Instances;

/// Triangles per leaf of a rebuilt tree.
const LEAF: usize = 4;

/// Each mesh's hierarchical-grid levels for a frame (empty where it has none).
pub type FrameLevels<'s> = Vec<Vec<GridLevel<'s>>>;

/// A deforming mesh's moving parts.
struct MeshState {
    header: Header,
    positions: Vec<Position>,
    triangles: Vec<[u32; 3]>,
    nodes: Vec<BvhNode>,
    prims: Vec<u32>,
    changed: bool,
    /// The tree's SAH cost when it was last built.
    built_cost: f64,
    /// Reinhard's update: the hierarchical grid (no tree).
    grid: Option<HierGrid>,
}

/// What one commit did and what it cost.
#[derive(Clone, Copy, Debug, Default)]
pub struct CommitStats {
    /// Seconds refitting.
    pub refit_seconds: f64,
    /// Seconds rebuilding bottom levels.
    pub rebuild_seconds: f64,
    /// Seconds on the instances' boxes and the top level.
    pub top_seconds: f64,
    /// Meshes refitted.
    pub refits: u32,
    /// Meshes rebuilt.
    pub rebuilds: u32,
    /// Triangles of the meshes updated.
    pub triangles: u64,
    /// The largest SAH cost of an updated tree relative to its cost when last built.
    pub cost_growth: f64,
}

impl CommitStats {
    /// The whole update: bottoms and top level.
    pub fn seconds(&self) -> f64 {
        self.refit_seconds + self.rebuild_seconds + self.top_seconds
    }
}

/// The moving parts of a scene.
pub struct DynamicState {
    name: String,
    meshes: Vec<Option<MeshState>>,
    instances: Vec<InstanceRecord>,
    top: BoxBvh,
    moved: bool,
    update: Update,
    threshold: f64,
}

/// Builds `mesh`'s tree anew with `update`'s builder (the binned SAH for a full
/// rebuild, the linear BVH otherwise) and refits its boxes.
fn rebuild(mesh: &mut MeshState, full: bool) {
    let (lo, hi) = bounds_of(&mesh.positions);
    let (mut nodes, prims) = if full {
        let boxes: Vec<([f32; 3], [f32; 3])> = mesh
            .triangles
            .iter()
            .map(|t| {
                let p = |k: usize| Vec3A::from_array(mesh.positions[t[k] as usize].0);
                (p(0).min(p(1)).min(p(2)).to_array(), p(0).max(p(1)).max(p(2)).to_array())
            })
            .collect();
        let t = build_box_bvh(&boxes, LEAF);
        (t.nodes, t.list)
    } else {
        build_lbvh(&mesh.triangles, &mesh.positions, LEAF)
    };
    refit(&mut nodes, &prims, &mesh.triangles, &mesh.positions, margin_for(lo, hi));
    mesh.nodes = nodes;
    mesh.prims = prims;
    mesh.built_cost = sah_cost(&mesh.nodes);
}

impl DynamicState {
    /// The moving parts of `scene`, whose images `base` holds; deforming meshes get
    /// their first tree here (the full build, or the linear BVH under
    /// [`Update::Rebuild`]). `threshold` is [`Update::Auto`]'s cost growth.
    pub fn new(
        scene: &InstancedScene,
        base: &BaseViews<'_>,
        deforming: &[bool],
        update: Update,
        threshold: f64,
    ) -> Result<Self> {
        let mut meshes = Vec::with_capacity(scene.bottoms.len());
        for (b, mesh) in scene.bottoms.iter().enumerate() {
            if !deforming.get(b).copied().unwrap_or(false) {
                meshes.push(None);
                continue;
            }
            let view = base.bottoms.get(b).ok_or_else(|| anyhow!("internal error: mesh {b} has no image"))?;
            let mut state = MeshState {
                header: *view.header(),
                positions: mesh.positions.iter().map(|&p| Position(p)).collect(),
                triangles: mesh.triangles.clone(),
                nodes: Vec::new(),
                prims: Vec::new(),
                changed: false,
                built_cost: 0.0,
                grid: None,
            };
            match update {
                Update::Parker => {}
                Update::Reinhard => {
                    let mut grid = HierGrid::build(&state.positions, &state.triangles);
                    let (lo, hi) = bounds_of(&state.positions);
                    grid.flatten(lo, hi);
                    state.grid = Some(grid);
                }
                _ => rebuild(&mut state, update != Update::Rebuild),
            }
            meshes.push(Some(state));
        }
        let mut s = DynamicState {
            name: scene.name.clone(),
            meshes,
            instances: Vec::with_capacity(scene.instances.len()),
            top: BoxBvh::default(),
            moved: true,
            update,
            threshold,
        };
        for inst in &scene.instances {
            let to_object = inverse(&inst.to_world).map_err(|e| anyhow!("{}: {e}", scene.name))?;
            s.instances.push(InstanceRecord {
                to_world: inst.to_world,
                to_object,
                bottom: inst.bottom,
                material: inst.material.unwrap_or(raypipe_core::image::NULL_INDEX),
                bounds_min: [0.0; 3],
                bounds_max: [0.0; 3],
            });
        }
        s.commit_top(base);
        Ok(s)
    }

    /// Posts mesh `mesh`'s new vertices (as many as it has, all finite).
    pub fn set_vertices(&mut self, mesh: u32, positions: &[[f32; 3]]) -> Result<()> {
        let name = &self.name;
        let Some(slot) = self.meshes.get_mut(mesh as usize) else {
            bail!("{name}: mesh {mesh} does not exist ({} meshes)", self.meshes.len());
        };
        let Some(m) = slot.as_mut() else { bail!("{name}: mesh {mesh} was not built to deform") };
        if positions.len() != m.positions.len() {
            bail!("{name}: mesh {mesh}: {} vertices posted, the mesh has {}", positions.len(), m.positions.len());
        }
        if let Some(i) = positions.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
            bail!("{name}: mesh {mesh}: vertex {i} is NaN or infinite");
        }
        for (d, s) in m.positions.iter_mut().zip(positions) {
            d.0 = *s;
        }
        m.changed = true;
        Ok(())
    }

    /// Posts instance `instance`'s new object-to-world map.
    pub fn set_transform(&mut self, instance: u32, to_world: Affine34) -> Result<()> {
        let name = &self.name;
        let n = self.instances.len();
        let Some(rec) = self.instances.get_mut(instance as usize) else {
            bail!("{name}: instance {instance} does not exist ({n} instances)");
        };
        rec.to_object = inverse(&to_world).map_err(|e| anyhow!("{name}: instance {instance}: {e}"))?;
        rec.to_world = to_world;
        self.moved = true;
        Ok(())
    }

    /// Brings every changed mesh's structure up to date (refit, rebuild or the
    /// automatic choice, by the state's [`Update`]) and rebuilds the top level.
    pub fn commit(&mut self, base: &BaseViews<'_>) -> CommitStats {
        let mut stats = CommitStats::default();
        for m in self.meshes.iter_mut().flatten().filter(|m| m.changed) {
            m.changed = false;
            self.moved = true;
            stats.triangles += m.triangles.len() as u64;
            let (lo, hi) = bounds_of(&m.positions);
            m.header.bounds_min = lo.to_array();
            m.header.bounds_max = hi.to_array();
            let start = Instant::now();
            match self.update {
                Update::Parker => {}
                Update::Reinhard => {
                    if let Some(grid) = m.grid.as_mut() {
                        let rebuilt = grid.update(&m.positions, &m.triangles);
                        grid.flatten(lo, hi);
                        // An incremental move counts as a refit, a new grid as a rebuild.
                        let secs = start.elapsed().as_secs_f64();
                        if rebuilt {
                            stats.rebuilds += 1;
                            stats.rebuild_seconds += secs;
                        } else {
                            stats.refits += 1;
                            stats.refit_seconds += secs;
                        }
                    }
                    continue;
                }
                Update::Refit | Update::Auto => {
                    refit(&mut m.nodes, &m.prims, &m.triangles, &m.positions, margin_for(lo, hi));
                    let growth = sah_cost(&m.nodes) / m.built_cost.max(f64::MIN_POSITIVE);
                    stats.cost_growth = stats.cost_growth.max(growth);
                    stats.refits += 1;
                    if self.update == Update::Auto && growth > self.threshold {
                        stats.refit_seconds += start.elapsed().as_secs_f64();
                        let start = Instant::now();
                        rebuild(m, false);
                        stats.rebuilds += 1;
                        stats.rebuild_seconds += start.elapsed().as_secs_f64();
                        continue;
                    }
                    stats.refit_seconds += start.elapsed().as_secs_f64();
                    continue;
                }
                Update::Rebuild | Update::Full => {
                    rebuild(m, self.update == Update::Full);
                    stats.rebuilds += 1;
                }
            }
            stats.rebuild_seconds += start.elapsed().as_secs_f64();
        }
        if self.moved {
            let start = Instant::now();
            self.commit_top(base);
            stats.top_seconds = start.elapsed().as_secs_f64();
        }
        stats
    }

    /// The instances' world boxes from their meshes' current bounds, and the top level
    /// over them.
    fn commit_top(&mut self, base: &BaseViews<'_>) {
        for rec in &mut self.instances {
            let b = rec.bottom as usize;
            let bounds = match self.meshes.get(b) {
                Some(Some(m)) => (m.header.bounds_min, m.header.bounds_max),
                _ => {
                    base.bottoms.get(b).map_or(([0.0; 3], [0.0; 3]), |v| (v.header().bounds_min, v.header().bounds_max))
                }
            };
            (rec.bounds_min, rec.bounds_max) = world_box(&rec.to_world, bounds);
        }
        let boxes: Vec<([f32; 3], [f32; 3])> = self.instances.iter().map(|r| (r.bounds_min, r.bounds_max)).collect();
        self.top = build_box_bvh(&boxes, 1);
        self.moved = false;
    }

    /// The hierarchical grids' levels of the meshes under [`Update::Reinhard`] (empty for
    /// the others), for [`DynamicState::frame`]; the caller keeps them while the frame is
    /// in use.
    pub fn levels(&self) -> FrameLevels<'_> {
        self.meshes
            .iter()
            .map(|m| m.as_ref().and_then(|m| m.grid.as_ref()).map(|g| g.levels()).unwrap_or_default())
            .collect()
    }

    /// The frame for the kernels: each deforming mesh's view with its moved vertices and
    /// tree (or the grid `levels` holds for it), the others as built, and the top level —
    /// what moved validated once.
    pub fn frame<'s>(&'s self, base: &'s BaseViews<'_>, levels: &'s FrameLevels<'s>) -> Result<Instances<'s>> {
        let name = &self.name;
        let mut bottoms = Vec::with_capacity(base.bottoms.len());
        for (b, view) in base.bottoms.iter().enumerate() {
            let v = match self.meshes.get(b) {
                Some(Some(m)) if m.grid.is_some() => {
                    let grid = levels.get(b).map_or(&[][..], |l| &l[..]);
                    view.with_levels(&m.header, &m.positions, grid).map_err(|e| anyhow!("{name}: mesh {b}: {e}"))?
                }
                Some(Some(m)) => view
                    .with_geometry(FrameGeometry {
                        header: &m.header,
                        positions: &m.positions,
                        nodes: &m.nodes,
                        prims: &m.prims,
                    })
                    .map_err(|e| anyhow!("{name}: mesh {b}: {e}"))?,
                _ => *view,
            };
            bottoms.push(v);
        }
        // The file's addresses, so a model reads the frame as it would read the file.
        let count = |n: usize| n as u32;
        let (addrs, _) = index_layout(count(self.instances.len()), count(bottoms.len()), count(self.top.nodes.len()));
        let parts = TopParts { instances: &self.instances, nodes: &self.top.nodes, list: &self.top.list, addrs };
        let top = TopLevel::new(
            parts,
            |b| bottoms.get(b as usize).map(|v| v.bounds()),
            base.globals.materials().len() as u32,
        )
        .map_err(|e| anyhow!("{name}: {e}"))?;
        Ok(Instances { top, bottoms, globals: base.globals })
    }

    /// Number of instances.
    pub fn instance_count(&self) -> usize {
        self.instances.len()
    }
}
