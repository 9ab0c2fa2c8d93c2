//! The interfaces every box test implements, `f32` or fixed-point: one ray against one
//! box (the binary BVH's nodes), and one ray against a wide node's boxes.

use core::fmt::Debug;

use glam::Vec3A;

use crate::ray::Ray;
use crate::traverse::boxes::wide_slab::WideSlab;

/// One ray's test against one box (the binary BVH's nodes).
pub trait BoxTest: Clone + Debug {
    /// Per-ray constants.
    fn for_ray(ray: &Ray) -> Self;
    /// Entry distance of the ray into `[lo, hi]` within `[t0, t1]`, or `None`. Never
    /// `None` for a box that holds a hit of the matching triangle test in `[t0, t1]`;
    /// never more than such a hit's distance.
    fn entry(&self, lo: Vec3A, hi: Vec3A, t0: f32, t1: f32) -> Option<f32>;
}

/// One ray's test against the boxes of a wide node.
pub trait WideRay<N: WideSlab>: Clone + Debug {
    /// Per-ray constants.
    fn for_ray(ray: &Ray) -> Self;
    /// Entry distances into `tn` and the mask of the slots entered within `[t0, t1]`
    /// (never an empty slot), with [`BoxTest::entry`]'s guarantees per slot.
    fn slab(&self, node: &N, t0: f32, t1: f32, tn: &mut N::Dist) -> u32;
}
