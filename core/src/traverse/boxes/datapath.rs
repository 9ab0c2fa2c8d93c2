//! The box tests of a datapath: which ray–box test the BVH walks use, chosen by the
//! triangle test ([`crate::intersect::triangle::Intersector::Nodes`]). The `f32` tests
//! ([`FloatNodes`]: the robust slab test of [`crate::traverse::boxes::slab`] and the wide
//! nodes' SIMD tests) go with the `f32` triangle tests; the fixed-point box test
//! ([`FixedNodes`]) goes with the fixed-point triangle test, whose rounding its margins
//! are made for. A box test is conservative only for the triangle test it was made for.

use core::fmt::Debug;

use glam::Vec3A;

use crate::image::{Bvh4Node, Bvh8Node};
use crate::ray::Ray;
use crate::traverse::boxes::fixed_slab::FixedRayBox;
use crate::traverse::boxes::slab::RayBox;
use crate::traverse::boxes::wide_slab::{NodeRay, WideSlab};

pub use crate::traverse::boxes::box_test::{BoxTest, WideRay};

/// A datapath's box tests, for each kind of BVH node.
pub trait NodeTests: Clone + Debug + 'static {
    /// True for the `f32` tests (the walks may then take their SIMD fast paths and the
    /// packet kernels, whose box tests are `f32`).
    const FLOAT: bool;
    /// The binary BVH's test.
    type Binary: BoxTest;
    /// The wide BVHs' test.
    type Wide: WideRay<Bvh4Node> + WideRay<Bvh8Node>;
}

/// The `f32` box tests.
#[derive(Clone, Copy, Debug)]
pub struct FloatNodes;

impl NodeTests for FloatNodes {
    const FLOAT: bool = true;
    type Binary = RayBox;
    type Wide = NodeRay;
}

/// The fixed-point box test in the format `Q(BITS − FRAC).FRAC`.
#[derive(Clone, Copy, Debug)]
pub struct FixedNodes<const BITS: u32, const FRAC: u32>;

impl<const BITS: u32, const FRAC: u32> NodeTests for FixedNodes<BITS, FRAC> {
    const FLOAT: bool = false;
    type Binary = FixedRayBox<BITS, FRAC>;
    type Wide = FixedRayBox<BITS, FRAC>;
}

impl BoxTest for RayBox {
    #[inline(always)]
    fn for_ray(ray: &Ray) -> Self {
        RayBox::new(ray)
    }

    #[inline(always)]
    fn entry(&self, lo: Vec3A, hi: Vec3A, t0: f32, t1: f32) -> Option<f32> {
        RayBox::entry(self, lo, hi, t0, t1)
    }
}

impl<N: WideSlab> WideRay<N> for NodeRay {
    #[inline(always)]
    fn for_ray(ray: &Ray) -> Self {
        NodeRay::new(ray)
    }

    #[inline(always)]
    fn slab(&self, node: &N, t0: f32, t1: f32, tn: &mut N::Dist) -> u32 {
        node.slab(self, t0, t1, tn)
    }
}
