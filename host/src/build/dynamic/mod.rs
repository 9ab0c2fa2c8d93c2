//! Scenes that move (Wald & Slusallek 2001 §8): an instanced scene whose instances'
//! transforms and meshes' vertices change from frame to frame, behind an API that posts
//! only what changed and commits it — the model Embree's users know
//! (`rtcSetGeometryTransform`, a vertex buffer update, `rtcCommitScene` with a build
//! quality).
//!
//! [`DynamicImages`] builds every mesh's image once (the deforming ones with a binary
//! BVH, or none for Parker's baseline) and [`DynamicImages::views`] validates them once.
//! [`DynamicState`] holds what moves: each deforming mesh's vertices, header and tree,
//! and the instances. Per frame the caller posts changes, [`DynamicState::commit`]
//! updates only the changed meshes — refit, fast rebuild (LBVH), full rebuild (binned
//! SAH), automatically a refit that turns into a rebuild once its SAH cost has grown
//! past a threshold, or moves in Reinhard's hierarchical grid — and rebuilds the top level; [`DynamicState::frame`] validates what
//! moved ([`raypipe_core::SceneView::with_geometry`], [`raypipe_core::image::instanced::TopLevel::new`])
//! and hands the kernels the frame.

pub mod images;
pub mod lbvh;
pub mod refit;
pub mod reinhard;
pub mod state;

pub use images::{BaseViews, DynamicImages};
pub use state::{CommitStats, DynamicState, FrameLevels};

/// How a changed mesh's structure follows its vertices at a commit.
#[derive(Clone, Copy, Debug, PartialEq, clap::ValueEnum)]
pub enum Update {
    /// Refit the BVH bottom-up: same topology, new boxes (Embree's
    /// `RTC_BUILD_QUALITY_REFIT`).
    Refit,
    /// Rebuild fast: a Morton-code linear BVH (Embree's `LOW`).
    Rebuild,
    /// Rebuild with the binned surface area heuristic (Embree's `MEDIUM`).
    Full,
    /// Refit, and rebuild fast once the refitted tree's SAH cost has grown past
    /// `--auto-threshold` times its cost when last built.
    Auto,
    /// Parker's baseline: deforming meshes have no structure at all; every ray that
    /// reaches their instance tests all their triangles, and an update copies vertices.
    Parker,
    /// Reinhard, Smits & Hansen's hierarchical grid with wrap-around: a moved triangle
    /// is deleted from its cells and inserted into its new ones at the level matching
    /// its size; the grid is rebuilt only when the triangles' box has outgrown it.
    Reinhard,
}

impl Update {
    /// Its name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Update::Refit => "refit",
            Update::Rebuild => "rebuild",
            Update::Full => "full",
            Update::Auto => "auto",
            Update::Parker => "parker",
            Update::Reinhard => "reinhard",
        }
    }
}
