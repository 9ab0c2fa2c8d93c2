//! How either hardware model traces and shades a frame: the settings `simulate` and
//! `stream` share, gathered once.

use raypipe_core::pixel_filter::PixelSampler;
use raypipe_core::shade::shader::Shader;

use crate::render::tracer::IntersectorKind;

/// The triangle test, the shader (none: ray casting), whether visibility comes from the
/// rasterized G-buffer (the shadow caster), where a pixel's eye rays go, and whether to
/// show progress.
#[derive(Clone, Copy, Debug, Default)]
pub struct FrameSetup {
    /// The triangle test.
    pub intersector: IntersectorKind,
    /// The ray-emitting shader, or `None` for ray casting.
    pub shader: Option<Shader>,
    /// Primary visibility from the rasterizer's G-buffer (Purcell's shadow caster).
    pub shadow_caster: bool,
    /// How many eye rays each pixel gets and where they go.
    pub sampler: PixelSampler,
    /// A progress bar on a terminal.
    pub show_progress: bool,
}
