//! The images of a moving scene, built once: each mesh's scene image (a deforming mesh's
//! with a binary BVH, or with no structure for Parker's baseline, and indexed triangles:
//! no copy of its vertices to go stale) and the globals image.

use anyhow::{anyhow, Result};
use raypipe_core::SceneView;

use super::Update;
use crate::build::instanced::InstancedScene;
use crate::platform::aligned::AlignedBytes;
use crate::scene::{Accel, BuildOptions, BuildReport};

/// The built images.
pub struct DynamicImages {
    /// What the user called the scene.
    pub name: String,
    /// Each mesh's image.
    pub images: Vec<AlignedBytes>,
    /// Camera, lights and override materials.
    pub globals: AlignedBytes,
    /// Which meshes deform.
    pub deforming: Vec<bool>,
    /// Sizes, lights and warnings of the build.
    pub report: BuildReport,
}

/// The images' views, validated once for the whole animation.
#[derive(Clone, Debug)]
pub struct BaseViews<'i> {
    /// Each mesh's view as built.
    pub bottoms: Vec<SceneView<'i>>,
    /// The globals image.
    pub globals: SceneView<'i>,
}

impl DynamicImages {
    /// Builds `scene`'s images; the meshes `deforming` marks get a binary BVH (no
    /// structure under [`Update::Parker`], and under [`Update::Reinhard`], whose grid
    /// lives beside the image), the others `opts.accel`.
    pub fn build(scene: &InstancedScene, deforming: &[bool], opts: &BuildOptions, update: Update) -> Result<Self> {
        let moving = if matches!(update, Update::Parker | Update::Reinhard) { Accel::None } else { Accel::Bvh };
        let accel_of = |b: usize| if deforming.get(b).copied().unwrap_or(false) { moving } else { opts.accel };
        let parts = scene.build_parts(opts, &accel_of)?;
        Ok(DynamicImages {
            name: scene.name.clone(),
            images: parts.images,
            globals: AlignedBytes::from_slice(&parts.globals),
            deforming: (0..scene.bottoms.len()).map(|b| deforming.get(b).copied().unwrap_or(false)).collect(),
            report: parts.report,
        })
    }

    /// Validates every image once.
    pub fn views(&self) -> Result<BaseViews<'_>> {
        let bottoms = self
            .images
            .iter()
            .map(|i| SceneView::parse(i).map_err(|e| anyhow!("internal error: {}: {e}", self.name)))
            .collect::<Result<Vec<_>>>()?;
        let globals = SceneView::parse(&self.globals).map_err(|e| anyhow!("internal error: {}: {e}", self.name))?;
        Ok(BaseViews { bottoms, globals })
    }
}
