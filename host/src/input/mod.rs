//! Reading scenes and rays: OBJ/MTL, PLY, glTF, scene files, textures, cameras, camera paths, ray batches, generated scenes.

pub mod aff;
pub mod bricked;
pub mod camera_file;
pub mod camera_path;
pub mod default_scene;
pub mod generate;
pub mod gltf;
pub mod gltf_checks;
pub mod instanced;
pub mod limits;
pub mod mesh;
pub mod npy;
pub mod obj;
pub mod obj_indices;
pub mod obj_stream;
pub mod panic_guard;
pub mod ply;
pub mod ply_stream;
pub mod polygon;
pub mod ppm;
pub mod range_check;
pub mod read_file;
pub mod scene_file;
pub mod texture;
