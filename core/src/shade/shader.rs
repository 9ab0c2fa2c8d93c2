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

    /// Shades the hit of a primary record (`RayRecord::primary`): one record per sample,
    /// each of weight `1 / samples`, their radiance added to `sum` one by one.
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
        let samples = self.samples();
        for s in 0..samples {
            let rec = RayRecord { weight: Vec3::splat(1.0 / samples as f32), sample: s, ..primary };
            sum.add(self.shade(scene, &rec, hit, probe, emit));
        }
    }

    /// Primary records per pixel (path tracing's samples).
    pub fn samples(&self) -> u32 {
        match self {
            Shader::Whitted(_) => 1,
            Shader::Path(o) => o.samples.max(1),
        }
    }
}
