//! Picks the structure kernel for a scene (grid if the image has one, brute force
//! otherwise) and the intersection kernel the user asked for.

use raypipe_core::grid::trace_grid;
use raypipe_core::{brute_force::trace_brute_force, Hit, Intersector, MemoryProbe, Ray, RayCounters, SceneView};

/// Which ray–triangle test to use.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum IntersectorKind {
    /// Woop, Benthin & Wald 2013 (default).
    #[default]
    Watertight,
    /// Möller & Trumbore 1997, for comparison.
    MollerTrumbore,
}

/// Traces one ray with the scene's structure.
#[inline]
pub fn trace<I: Intersector, P: MemoryProbe>(
    scene: &SceneView<'_>,
    ray: &Ray,
    probe: &mut P,
    counters: &mut RayCounters,
) -> Option<Hit> {
    match scene.grid() {
        Some(grid) => trace_grid::<I, P>(scene, grid, ray, probe, counters),
        None => trace_brute_force::<I, P>(scene, ray, probe, counters),
    }
}

/// Calls `$body` with `$I` bound to the intersector type chosen by `$kind`.
#[macro_export]
macro_rules! with_intersector {
    ($kind:expr, $I:ident => $body:expr) => {
        match $kind {
            $crate::tracer::IntersectorKind::Watertight => {
                type $I = raypipe_core::Watertight;
                $body
            }
            $crate::tracer::IntersectorKind::MollerTrumbore => {
                type $I = raypipe_core::MollerTrumbore;
                $body
            }
        }
    };
}
