//! Rendering an instanced scene: the top level, every bottom image's view and the
//! globals image, validated once per frame; rays walk both levels
//! ([`raypipe_core::traverse::instanced`]) with each bottom's own fast kernels, and hits
//! are shaded from the world-space surface of their instance
//! ([`raypipe_core::shade::instance_surface`]).

pub mod frame;
pub mod tracer;

use anyhow::{anyhow, Result};
use raypipe_core::image::instanced::{InstancedView, TopLevel};
use raypipe_core::SceneView;

/// What a frame of an instanced scene reads: the top level, the bottoms' views (indexed
/// by bottom id) and the globals image.
#[derive(Clone, Debug)]
pub struct Instances<'a> {
    /// Instances and the BVH over them.
    pub top: TopLevel<'a>,
    /// Each bottom image's validated view.
    pub bottoms: Vec<SceneView<'a>>,
    /// Camera, lights and override materials.
    pub globals: SceneView<'a>,
}

impl<'a> Instances<'a> {
    /// Validates every bottom image of `view` once; `name` names the file in errors.
    pub fn of(view: &InstancedView<'a>, name: &str) -> Result<Instances<'a>> {
        let bottoms = (0..view.bottom_count())
            .map(|b| view.bottom(b).map_err(|e| anyhow!("{name}: {e}")))
            .collect::<Result<Vec<_>>>()?;
        Ok(Instances { top: *view.top(), bottoms, globals: *view.globals() })
    }
}
