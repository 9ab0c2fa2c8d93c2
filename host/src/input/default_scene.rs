//! The built-in default scene: the Cornell box, written by this project from the
//! dimensions published by the Cornell Program of Computer Graphics
//! (fixtures/cornell_box.obj, .mtl and .camera), compiled into the binary so that
//! `raypipe render` works anywhere without arguments.

/// The OBJ text.
pub const OBJ: &str = include_str!("../../../fixtures/cornell_box.obj");
/// The MTL text.
pub const MTL: &str = include_str!("../../../fixtures/cornell_box.mtl");
/// The camera file text.
pub const CAMERA: &str = include_str!("../../../fixtures/cornell_box.camera");
/// Name used in messages.
pub const NAME: &str = "built-in Cornell box";
