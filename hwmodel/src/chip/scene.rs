//! What the chip reads: one scene image, or an instanced scene — the top level, each
//! bottom's image and the globals image (Wald & Slusallek 2001 §8.3) — placed in one
//! scene memory the way the instanced file places them (the index with its globals,
//! then every bottom on a 64-byte boundary), so a frame held by the host in separate
//! buffers costs the chip what the file would.

use raypipe_core::image::instanced::{index_layout, TopLevel};
use raypipe_core::{SceneView, Vec3};

/// The scene the chip renders.
#[derive(Clone, Debug)]
pub enum ChipScene<'s> {
    /// One scene image.
    Flat(SceneView<'s>),
    /// A two-level scene.
    Instanced(InstancedScene<'s>),
}

/// A two-level scene with the base address of each image in the chip's scene memory.
#[derive(Clone, Debug)]
pub struct InstancedScene<'s> {
    /// The instances and the BVH over them (its reads are reported at file offsets).
    pub top: TopLevel<'s>,
    /// Each bottom's validated view, by bottom id.
    pub bottoms: Vec<SceneView<'s>>,
    /// Camera, lights and override materials.
    pub globals: SceneView<'s>,
    bottom_base: Vec<u64>,
    globals_base: u64,
    size: u64,
}

fn align64(a: u64) -> u64 {
    a.div_ceil(64) * 64
}

impl<'s> InstancedScene<'s> {
    /// The scene of `top`, `bottoms` and `globals`, laid out as the file lays them out.
    pub fn new(top: TopLevel<'s>, bottoms: Vec<SceneView<'s>>, globals: SceneView<'s>) -> InstancedScene<'s> {
        let count = |n: usize| n as u32;
        let (_, list_end) = index_layout(top.instance_count(), count(bottoms.len()), count(top.tree().node_count()));
        let globals_base = align64(list_end);
        let mut at = align64(globals_base + globals.bytes().len() as u64);
        let bottom_base = bottoms
            .iter()
            .map(|b| {
                let base = at;
                // A hierarchical grid's levels follow their image.
                at = align64(at + b.bytes().len() as u64 + b.level_bytes());
                base
            })
            .collect();
        InstancedScene { top, bottoms, globals, bottom_base, globals_base, size: at }
    }

    /// Bottom `b`'s view and its base address (`None` for an id with no bottom).
    pub fn bottom(&self, b: u32) -> Option<(&SceneView<'s>, u64)> {
        Some((self.bottoms.get(b as usize)?, *self.bottom_base.get(b as usize)?))
    }

    /// The globals image's base address.
    pub fn globals_base(&self) -> u64 {
        self.globals_base
    }
}

impl<'s> ChipScene<'s> {
    /// The image the shading unit reads lights, materials and the camera's background
    /// from (the scene, or the instanced scene's globals), and its base address.
    pub fn shading_view(&self) -> (&SceneView<'s>, u64) {
        match self {
            ChipScene::Flat(v) => (v, 0),
            ChipScene::Instanced(s) => (&s.globals, s.globals_base),
        }
    }

    /// The flat scene, if it is one.
    pub fn flat(&self) -> Option<&SceneView<'s>> {
        match self {
            ChipScene::Flat(v) => Some(v),
            ChipScene::Instanced(_) => None,
        }
    }

    /// Bytes of scene memory.
    pub fn size(&self) -> u64 {
        match self {
            ChipScene::Flat(v) => v.bytes().len() as u64,
            ChipScene::Instanced(s) => s.size,
        }
    }

    /// The box eye rays are clipped to (Purcell's scene-bounds test).
    pub fn test_bounds(&self) -> (Vec3, Vec3) {
        self.shading_view().0.test_bounds()
    }

    /// The view whose structure stands for the scene's in the energy estimate: the
    /// scene's, or its first bottom's.
    pub fn structure_view(&self) -> &SceneView<'s> {
        match self {
            ChipScene::Flat(v) => v,
            ChipScene::Instanced(s) => s.bottoms.first().unwrap_or(&s.globals),
        }
    }
}
