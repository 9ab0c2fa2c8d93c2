//! The classes of memory traffic the model accounts: core's scene data classes plus the
//! framebuffer the shading unit writes.

use raypipe_core::DataClass;

/// Number of traffic classes.
pub const CLASSES: usize = 5;

/// Class index of framebuffer writes (after core's four scene classes).
pub const FRAMEBUFFER: usize = 4;

/// Report names, by class index.
pub const CLASS_NAMES: [&str; CLASSES] = ["nodes", "prim_lists", "triangles", "shading", "framebuffer"];

/// Class index of a scene read.
pub fn class_index(class: DataClass) -> usize {
    class as usize
}
