//! Compiling a mesh into a scene image: the acceleration structure builders, mipmaps, default lights and the image writer.

pub mod box_bvh;
pub mod bricks;
pub mod bvh;
pub mod default_lights;
pub mod dynamic;
pub mod emitter_sums;
pub mod grid;
pub mod image_writer;
pub mod instanced;
pub mod kdtree;
pub mod light_distribution;
pub mod mipmap;
pub mod sah;
pub mod spatial_split;
#[cfg(test)]
mod test_meshes;
pub(crate) mod tree_part;
pub mod tri_box;
pub mod tri_clip;
pub mod wide_bvh;
