//! The maths the kernels need without `std` or f64: sine, cosine and tangent, exp2, log2
//! and pow in f32, and the fixed-point numbers of the integer datapath.

#[forbid(unsafe_code)]
pub mod affine;
#[forbid(unsafe_code)]
pub mod exp_log;
#[forbid(unsafe_code)]
pub mod fixed_point;
pub mod trig;
