//! [`TopLevel`]: the validated top level of an instanced scene — the instance records
//! and the BVH over their world boxes — whether read from a file ([`super::InstancedView`])
//! or rebuilt in memory every frame by a host that animates the scene.

use glam::Vec3;

use super::error::InstancedError;
use super::layout::InstanceRecord;
use crate::image::limits::MAX_TREE_DEPTH;
use crate::image::records::{BvhNode, NULL_INDEX};
use crate::image::sections::finite3;
use crate::image::structure_views::BvhView;
use crate::image::validate::tree::{pair, validate_tree, Children};
use crate::math::affine;
use crate::probe::{DataClass, MemoryProbe};

/// The parts of a top level before validation, with the addresses its reads are
/// reported at (byte offsets in the instanced file, or any labels a driver chooses).
#[derive(Clone, Copy, Debug)]
pub struct TopParts<'a> {
    /// The instance records.
    pub instances: &'a [InstanceRecord],
    /// The top-level BVH; node 0 is the root.
    pub nodes: &'a [BvhNode],
    /// The list its leaves index: instance ids.
    pub list: &'a [u32],
    /// Addresses of the instances, the nodes and the list.
    pub addrs: [u32; 3],
}

/// A validated top level. Cheap to copy.
#[derive(Clone, Copy, Debug)]
pub struct TopLevel<'a> {
    tree: BvhView<'a>,
    instances: &'a [InstanceRecord],
    instances_addr: u32,
}

/// The box of `bottom`'s corners mapped by `to_world`, as [`TopLevel::new`] checks it.
pub fn mapped_box(to_world: &affine::Affine34, (lo, hi): (Vec3, Vec3)) -> (Vec3, Vec3) {
    let mut out = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for k in 0..8u32 {
        let c = Vec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        );
        let p = affine::point(to_world, c);
        out = (out.0.min(p), out.1.max(p));
    }
    out
}

fn ordered_box(lo: [f32; 3], hi: [f32; 3]) -> bool {
    finite3(lo) && finite3(hi) && Vec3::from(lo).cmple(Vec3::from(hi)).all()
}

fn contains(outer: (Vec3, Vec3), inner: (Vec3, Vec3)) -> bool {
    outer.0.cmple(inner.0).all() && inner.1.cmple(outer.1).all()
}

impl<'a> TopLevel<'a> {
    /// Validates a top level: every instance's transform finite with a stored inverse
    /// that undoes it ([`affine::is_inverse_pair`]), its bottom image among
    /// `bottom_bounds` (each bottom's object-space box) and its world box holding that
    /// box's mapped corners, its material below `materials` or [`NULL_INDEX`]; the tree
    /// of finite ordered boxes, at most [`MAX_TREE_DEPTH`] deep, each child's box inside
    /// its parent's and each leaf's inside its instances' boxes, leaves naming existing
    /// instances. A ray through an accepted top level visits at most `nodes.len()` nodes
    /// and `list.len()` instances.
    pub fn new(
        parts: TopParts<'a>,
        bottom_bounds: impl Fn(u32) -> Option<(Vec3, Vec3)>,
        materials: u32,
    ) -> Result<TopLevel<'a>, InstancedError> {
        let TopParts { instances, nodes, list, addrs } = parts;
        let n = instances.len() as u32;
        for (i, inst) in instances.iter().enumerate() {
            let bad = InstancedError::BadInstance { instance: i as u32 };
            if !affine::is_inverse_pair(&inst.to_world, &inst.to_object)
                || (inst.material != NULL_INDEX && inst.material >= materials)
                || !ordered_box(inst.bounds_min, inst.bounds_max)
            {
                return Err(bad);
            }
            let bottom = bottom_bounds(inst.bottom).ok_or(bad)?;
            let world = (Vec3::from(inst.bounds_min), Vec3::from(inst.bounds_max));
            if !contains(world, mapped_box(&inst.to_world, bottom)) {
                return Err(bad);
            }
        }
        if list.len() != instances.len() || list.iter().any(|&e| e >= n) {
            return Err(InstancedError::BadTree { node: 0 });
        }
        let node_box = |i: u32| nodes.get(i as usize).map(|c| (Vec3::from(c.min), Vec3::from(c.max)));
        let inst_box = |e: u32| instances.get(e as usize).map(|c| (Vec3::from(c.bounds_min), Vec3::from(c.bounds_max)));
        validate_tree(nodes.len(), crate::image::SectionKind::BvhNodes, MAX_TREE_DEPTH, n as u64, |i| {
            let node = nodes.get(i).ok_or(())?;
            if !ordered_box(node.min, node.max) {
                return Err(());
            }
            let outer = (Vec3::from(node.min), Vec3::from(node.max));
            let inside = |b: Option<(Vec3, Vec3)>| b.is_some_and(|b| contains(outer, b));
            if node.count == 0 {
                let c = node.first;
                if !inside(node_box(c)) || !inside(node_box(c.wrapping_add(1))) {
                    return Err(());
                }
                Ok((pair(c), 0))
            } else if node.first as u64 + node.count as u64 <= n as u64 {
                let entries = node.first..node.first + node.count;
                if !entries.into_iter().all(|k| inside(list.get(k as usize).and_then(|&e| inst_box(e)))) {
                    return Err(());
                }
                Ok((Children::new(), node.count as u64))
            } else {
                Err(())
            }
        })
        .map_err(|e| match e {
            crate::image::SceneError::BadTree { node, .. } => InstancedError::BadTree { node },
            _ => InstancedError::BadTree { node: 0 },
        })?;
        let tree = BvhView { nodes, prims: list, nodes_addr: addrs[1], prims_addr: addrs[2] };
        Ok(TopLevel { tree, instances, instances_addr: addrs[0] })
    }

    /// The BVH over the instances' world boxes (its leaves' list entries are instance
    /// ids).
    pub fn tree(&self) -> &BvhView<'a> {
        &self.tree
    }

    /// Every instance record (for statistics; not an observed kernel read).
    pub fn instances(&self) -> &'a [InstanceRecord] {
        self.instances
    }

    /// Number of instances.
    pub fn instance_count(&self) -> u32 {
        self.instances.len() as u32
    }

    /// Reads instance `i`'s record (the transformation unit's fetch).
    #[inline]
    pub fn instance<P: MemoryProbe>(&self, i: u32, probe: &mut P) -> InstanceRecord {
        probe.read(DataClass::Nodes, self.instances_addr.wrapping_add(i.wrapping_mul(128)), 128);
        self.instances.get(i as usize).copied().unwrap_or(InstanceRecord {
            to_world: affine::IDENTITY,
            to_object: affine::IDENTITY,
            bottom: NULL_INDEX,
            material: NULL_INDEX,
            bounds_min: [0.0; 3],
            bounds_max: [0.0; 3],
        })
    }

    /// Reads top-level list entry `pos`: an instance id.
    #[inline]
    pub fn list_instance<P: MemoryProbe>(&self, pos: u32, probe: &mut P) -> u32 {
        self.tree.prim(pos, probe)
    }
}
