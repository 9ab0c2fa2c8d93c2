//! Reading scenes and rays: OBJ/MTL, PLY, glTF, scene files, textures, cameras, camera paths, ray batches, generated scenes.

pub mod camera_file;
pub mod camera_path;
pub mod default_scene;
pub mod generate;
pub mod gltf;
pub mod mesh;
pub mod npy;
pub mod obj;
pub mod obj_indices;
pub mod ply;
pub mod polygon;
pub mod range_check;
pub mod scene_file;
pub mod texture;
