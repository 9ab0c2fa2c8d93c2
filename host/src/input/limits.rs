//! The most geometry one scene may hold, checked by every loader and generator against
//! what it *will* create — triangles × instances, generator parameters — before it
//! allocates, so that a small input cannot multiply into an out-of-memory abort.

use anyhow::{bail, Result};

/// Triangles in one scene: 2²⁵ (33.5 M). A scene image addresses its sections with
/// 32-bit offsets, so it holds at most 4 GiB — about 48 M triangles at the 90 bytes per
/// triangle of a 4-wide BVH image with shading data; the limit leaves room for the
/// structure's worst case. Loading at the limit takes about 2 GB of host memory.
pub const MAX_TRIANGLES: u64 = 1 << 25;

/// Vertices in one scene: three per triangle at the limit (no sharing).
pub const MAX_VERTICES: u64 = 3 * MAX_TRIANGLES;

/// Fails with one line naming `what` if `triangles` is more than [`MAX_TRIANGLES`].
pub fn check_triangles(what: &str, triangles: u64) -> Result<()> {
    if triangles > MAX_TRIANGLES {
        bail!("{what}: {triangles} triangles is more than {MAX_TRIANGLES}, the most one scene may hold");
    }
    Ok(())
}

/// Fails with one line naming `what` if `vertices` is more than [`MAX_VERTICES`].
pub fn check_vertices(what: &str, vertices: u64) -> Result<()> {
    if vertices > MAX_VERTICES {
        bail!("{what}: {vertices} vertices is more than {MAX_VERTICES}, the most one scene may hold");
    }
    Ok(())
}

/// The most triangles an instanced scene may draw (each instance counting its mesh's):
/// instancing draws far more than a flat scene holds, but every drawn triangle is still
/// visited once when the default lights are placed.
pub const MAX_DRAWN_TRIANGLES: u64 = 1 << 32;
