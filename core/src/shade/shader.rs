//! The ray-emitting shaders behind one interface, so that a driver (the host's ray
//! stream, the hardware model's shading unit) runs any algorithm the same way.

use glam::Vec3;

use crate::hit::Hit;
use crate::image::SceneView;
use crate::probe::MemoryProbe;
use crate::shade::path::{shade_path, PathOptions};
use crate::shade::radiance_sum::RadianceSum;
use crate::shade::ray_record::RayRecord;
use crate::shade::whitted::{shade_whitted, WhittedOptions};

/// A shader that consumes hits and emits ray records.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shader {
    /// Whitted ray tracing.
    Whitted(WhittedOptions),
    /// Path tracing.
    Path(PathOptions),
}

impl Shader {
    /// Shades the end of `rec`: the radiance added now (times its weight); new records go
    /// to `emit`.
    #[inline]
    pub fn shade<P: MemoryProbe>(
        &self,
        scene: &SceneView<'_>,
        rec: &RayRecord,
        hit: Option<Hit>,
        probe: &mut P,
        emit: &mut impl FnMut(RayRecord),
    ) -> Vec3 {
        match self {
            Shader::Whitted(o) => shade_whitted(scene, rec, hit, o, probe, emit),
            Shader::Path(o) => shade_path(scene, rec, hit, o, probe, emit),
        }
    }

    /// Shades the hit of eye ray `sample` of `samples` (built with
    /// [`RayRecord::eye_sample`]: weight `1 / samples`), its radiance added to `sum`.
    /// Each sample has its own eye ray and hit (Purcell's path tracer traces one eye ray
    /// per sample).
    #[inline]
    pub fn shade_primary<P: MemoryProbe>(
        &self,
        scene: &SceneView<'_>,
        primary: RayRecord,
        hit: Option<Hit>,
        sum: &mut RadianceSum,
        probe: &mut P,
        emit: &mut impl FnMut(RayRecord),
    ) {
        sum.add(self.shade(scene, &primary, hit, probe, emit));
    }
}
