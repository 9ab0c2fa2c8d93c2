//! Shading: Lambert shading, surfaces and textures, mirrors and glass, Whitted's and the
//! path tracer's shaders as stream kernels that emit weighted ray records, exact radiance
//! sums, counter-based random numbers, colours, and the shadow caster's rasterizer.

pub mod blinn_phong;
pub mod color;
pub mod escaped;
pub mod hemisphere;
pub mod instance_surface;
pub mod lambert;
pub mod mis;
pub mod path;
pub mod radiance_sum;
pub mod raster;
pub mod ray_cone;
pub mod ray_record;
pub mod rng;
pub mod shader;
pub mod specular;
mod srgb_tables;
pub mod surface;
pub mod texture;
pub mod whitted;
