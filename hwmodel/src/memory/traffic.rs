//! The classes of memory traffic the model accounts: core's scene data classes (indexed
//! by `DataClass as usize`) plus the framebuffer the shading unit writes.

/// Number of traffic classes.
pub const CLASSES: usize = 5;

/// Class index of framebuffer writes (after core's four scene classes).
pub const FRAMEBUFFER: usize = 4;

/// Report names, by class index.
pub const CLASS_NAMES: [&str; CLASSES] = ["nodes", "prim_lists", "triangles", "shading", "framebuffer"];
