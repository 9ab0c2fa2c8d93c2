//! Fixed-layout records stored in the sections. Each states its size and why.

use bytemuck::{Pod, Zeroable};

use super::header::{AccelKind, SectionKind};

/// The null value: an empty grid cell, and the terminator of a primitive list
/// (Purcell 2002, Figure 4).
pub const NULL_INDEX: u32 = u32::MAX;

/// A vertex position, 12 bytes: the only vertex data the intersection unit reads.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct Position(pub [f32; 3]);
const _: () = assert!(core::mem::size_of::<Position>() == 12);
const _: () = assert!(core::mem::align_of::<Position>() == 4);

/// A triangle as three indices into POSITIONS, 12 bytes (Purcell's triangle texture:
/// triangles index vertex data). Shading data is elsewhere, indexed the same way.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq)]
pub struct TriangleRecord(pub [u32; 3]);
const _: () = assert!(core::mem::size_of::<TriangleRecord>() == 12);
const _: () = assert!(core::mem::align_of::<TriangleRecord>() == 4);

/// Uniform grid parameters, 64 bytes (one cache line), in four 16-byte rows.
///
/// Cell `(i, j, k)` covers `bounds_min + (i, j, k) * cell_size` to
/// `bounds_min + (i+1, j+1, k+1) * cell_size`; its index in GRID_CELLS is
/// `i + dims[0] * (j + dims[1] * k)`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GridRecord {
    /// Lower corner of the grid (scene bounds grown by the build margin).
    pub bounds_min: [f32; 3],
    /// Unused, zero.
    pub _pad0: u32,
    /// Upper corner of the grid.
    pub bounds_max: [f32; 3],
    /// Unused, zero.
    pub _pad1: u32,
    /// Size of one cell along each axis.
    pub cell_size: [f32; 3],
    /// Unused, zero.
    pub _pad2: u32,
    /// Cells along x, y and z.
    pub dims: [u32; 3],
    /// `dims[0] * dims[1] * dims[2]`.
    pub cell_count: u32,
}
const _: () = assert!(core::mem::size_of::<GridRecord>() == 64);
const _: () = assert!(core::mem::align_of::<GridRecord>() == 4);

/// Per-vertex shading data, 32 bytes, indexed like POSITIONS but stored apart from it
/// (Wald 2001: keep shading data out of the intersection unit's cache lines).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct ShadingVertex {
    /// Shading normal; all zero when the input had none (the geometric normal is used).
    pub normal: [f32; 3],
    /// Texture coordinates.
    pub uv: [f32; 2],
    /// Vertex colour, multiplied into the material's diffuse colour (1,1,1 when absent).
    pub color: [f32; 3],
}
const _: () = assert!(core::mem::size_of::<ShadingVertex>() == 32);
const _: () = assert!(core::mem::align_of::<ShadingVertex>() == 4);

/// A material, 64 bytes, from MTL: `Kd`, `Ks`/`Ns`, `Ke`, `Ni`, `d`, `illum`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct MaterialRecord {
    /// Diffuse reflectance `Kd`.
    pub diffuse: [f32; 3],
    /// Specular exponent `Ns`.
    pub shininess: f32,
    /// Specular reflectance `Ks`.
    pub specular: [f32; 3],
    /// Index of refraction `Ni`.
    pub ior: f32,
    /// Emitted radiance `Ke`.
    pub emission: [f32; 3],
    /// Opacity `d` (1 = opaque).
    pub dissolve: f32,
    /// MTL illumination model `illum`.
    pub illum: u32,
    /// Diffuse texture index, or [`NULL_INDEX`].
    pub texture: u32,
    /// Unused, zero.
    pub _pad: [u32; 2],
}
const _: () = assert!(core::mem::size_of::<MaterialRecord>() == 64);
const _: () = assert!(core::mem::align_of::<MaterialRecord>() == 4);

impl MaterialRecord {
    /// The material used when a triangle has none: light grey, matte.
    pub const DEFAULT: MaterialRecord = MaterialRecord {
        diffuse: [0.8, 0.8, 0.8],
        shininess: 0.0,
        specular: [0.0; 3],
        ior: 1.0,
        emission: [0.0; 3],
        dissolve: 1.0,
        illum: 1,
        texture: NULL_INDEX,
        _pad: [0; 2],
    };
}

/// A light, 32 bytes. Area lights come last in LIGHTS: the shaders of ray casting, the
/// shadow caster and Whitted read only the lights before them.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct LightRecord {
    /// Position (point lights); the unit direction towards the light (directional);
    /// the horizon's radiance (environment); unused otherwise.
    pub position: [f32; 3],
    /// [`LightRecord::POINT`], [`LightRecord::AMBIENT`], [`LightRecord::AREA`],
    /// [`LightRecord::EMITTERS`], [`LightRecord::DIRECTIONAL`] or
    /// [`LightRecord::ENVIRONMENT`].
    pub kind: u32,
    /// Colour times intensity (area lights: the emitted radiance `Ke`; directional: the
    /// irradiance it gives a surface facing it; environment: the zenith's radiance).
    pub color: [f32; 3],
    /// The emitting triangle of an area light; zero otherwise.
    pub triangle: u32,
}
const _: () = assert!(core::mem::size_of::<LightRecord>() == 32);
const _: () = assert!(core::mem::align_of::<LightRecord>() == 4);

impl LightRecord {
    /// A point light without distance fall-off.
    pub const POINT: u32 = 0;
    /// Ambient light, added to every lit point.
    pub const AMBIENT: u32 = 1;
    /// An emissive triangle as an area light (path tracing samples points on it).
    pub const AREA: u32 = 2;
    /// A point light standing in for the emissive triangles in ray casting, the shadow
    /// caster and Whitted ray tracing (path tracing samples the area lights instead).
    pub const EMITTERS: u32 = 3;
    /// A light at infinity (the sun): parallel rays from direction `position`.
    pub const DIRECTIONAL: u32 = 4;
    /// Light from every direction of the sky: radiance blending from the horizon's
    /// (`position`) at and below the horizon to the zenith's (`color`) straight up (+y).
    /// Path tracing samples it; the other algorithms add its mean as ambient light.
    pub const ENVIRONMENT: u32 = 5;
    /// The largest kind.
    pub const MAX_KIND: u32 = 5;

    /// The name of a light kind, for reports (`"?"` for an unknown one).
    pub const fn kind_name(kind: u32) -> &'static str {
        match kind {
            LightRecord::POINT => "point",
            LightRecord::AMBIENT => "ambient",
            LightRecord::AREA => "area",
            LightRecord::EMITTERS => "emitter stand-in",
            LightRecord::DIRECTIONAL => "directional",
            LightRecord::ENVIRONMENT => "sky",
            _ => "?",
        }
    }

    /// The environment's radiance along unit direction `dir`.
    pub fn sky(&self, dir: glam::Vec3) -> glam::Vec3 {
        let t = dir.y.clamp(0.0, 1.0);
        glam::Vec3::from(self.position) * (1.0 - t) + glam::Vec3::from(self.color) * t
    }

    /// The mean radiance of the environment over the upper hemisphere, cosine-weighted
    /// about +y: what a surface facing up receives, over π (used as ambient light).
    pub fn sky_mean(&self) -> glam::Vec3 {
        // ∫ L(cos θ) cos θ dω / π with L linear in cos θ: (horizon + 2 zenith) / 3.
        (glam::Vec3::from(self.position) + glam::Vec3::from(self.color) * 2.0) / 3.0
    }

    /// True for the lights the point-light shaders use (cast, shadow caster, Whitted).
    pub fn is_point(&self) -> bool {
        self.kind == LightRecord::POINT || self.kind == LightRecord::EMITTERS
    }
}

/// The default pinhole camera and background, 64 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct CameraRecord {
    /// Eye position.
    pub eye: [f32; 3],
    /// Vertical field of view in degrees.
    pub vfov_deg: f32,
    /// Point looked at.
    pub look_at: [f32; 3],
    /// Image width in pixels.
    pub width: u32,
    /// Up vector (need not be orthogonal to the view direction, must not be parallel).
    pub up: [f32; 3],
    /// Image height in pixels.
    pub height: u32,
    /// Colour of rays that hit nothing.
    pub background: [f32; 3],
    /// Unused, zero.
    pub _pad: u32,
}
const _: () = assert!(core::mem::size_of::<CameraRecord>() == 64);
const _: () = assert!(core::mem::align_of::<CameraRecord>() == 4);

/// One entry of the area lights' alias table (Walker 1977), 16 bytes: entry `i` keeps
/// area light `i` with probability `keep`, else gives area light `alias`; `pdf` and
/// `alias_pdf` are the probabilities with which the table picks each of the two.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct LightAlias {
    /// Probability of keeping this entry's own light, in `[0, 1]`.
    pub keep: f32,
    /// The other light of the entry (an area-light number).
    pub alias: u32,
    /// Probability that the table picks this entry's own light.
    pub pdf: f32,
    /// Probability that the table picks `alias`.
    pub alias_pdf: f32,
}
const _: () = assert!(core::mem::size_of::<LightAlias>() == 16);
const _: () = assert!(core::mem::align_of::<LightAlias>() == 4);

/// A BVH node, 32 bytes: the "traditional" layout Ingo Wald proposed (as in tinybvh and
/// pbrt's `LinearBVHNode`), two 16-byte rows of box corner plus one word.
///
/// * inner node: `count == 0`; its children are nodes `first` and `first + 1`;
/// * leaf: `count > 0` triangles, PRIM_LISTS entries `first .. first + count`.
///
/// The box is the bounds of everything below, grown outwards by the build margin.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct BvhNode {
    /// Lower corner.
    pub min: [f32; 3],
    /// First child (inner) or first PRIM_LISTS entry (leaf).
    pub first: u32,
    /// Upper corner.
    pub max: [f32; 3],
    /// Triangles in a leaf; 0 for an inner node.
    pub count: u32,
}
const _: () = assert!(core::mem::size_of::<BvhNode>() == 32);
const _: () = assert!(core::mem::align_of::<BvhNode>() == 4);

/// A kd-tree node, 8 bytes: Wald's compact layout (Wald 2004, §7.3; Wald & Slusallek
/// 2001): eight nodes share a 64-byte cache line.
///
/// `flags` holds the split axis (0, 1, 2) or 3 for a leaf in its two low bits and an
/// index in the upper 30 bits:
/// * inner node: `value` is the split position (f32 bits); the children are nodes
///   `index` (below the plane) and `index + 1` (above it);
/// * leaf: `value` is the triangle count; the triangles are PRIM_LISTS entries
///   `index .. index + count`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq)]
pub struct KdNode {
    /// Axis or leaf tag (2 bits) and child / list index (30 bits).
    pub flags: u32,
    /// Split position as f32 bits (inner) or triangle count (leaf).
    pub value: u32,
}
const _: () = assert!(core::mem::size_of::<KdNode>() == 8);
const _: () = assert!(core::mem::align_of::<KdNode>() == 4);

impl KdNode {
    /// The tag of a leaf in the two low bits of `flags`.
    pub const LEAF: u32 = 3;

    /// An inner node splitting `axis` at `split`, children at `child` and `child + 1`.
    pub fn inner(axis: u32, split: f32, child: u32) -> KdNode {
        KdNode { flags: (child << 2) | axis, value: split.to_bits() }
    }

    /// A leaf of `count` triangles starting at PRIM_LISTS entry `first`.
    pub fn leaf(first: u32, count: u32) -> KdNode {
        KdNode { flags: (first << 2) | Self::LEAF, value: count }
    }

    /// Axis 0–2, or [`KdNode::LEAF`].
    #[inline]
    pub fn axis(&self) -> u32 {
        self.flags & 3
    }

    /// Child index (inner) or first list entry (leaf).
    #[inline]
    pub fn index(&self) -> u32 {
        self.flags >> 2
    }

    /// Split position of an inner node.
    #[inline]
    pub fn split(&self) -> f32 {
        f32::from_bits(self.value)
    }
}

/// A 4-wide BVH node, 128 bytes (two cache lines): the boxes of its four children in
/// structure-of-arrays form, so one SIMD slab test checks all four (Wald, Benthin &
/// Boulos 2008, "Getting rid of packets"; Embree's BVH4).
///
/// Slot `k` is empty when `child[k] == NULL_INDEX`, and then its box is inverted
/// (`min = f32::MAX`, `max = −f32::MAX` on every axis) so that no slab test accepts it;
/// an inner child when `count[k] == 0`
/// (`child[k]` is its node index); a leaf when `count[k] > 0` (PRIM_LISTS entries
/// `child[k] .. child[k] + count[k]`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct Bvh4Node {
    /// Lower x of each child box.
    pub min_x: [f32; 4],
    /// Lower y.
    pub min_y: [f32; 4],
    /// Lower z.
    pub min_z: [f32; 4],
    /// Upper x.
    pub max_x: [f32; 4],
    /// Upper y.
    pub max_y: [f32; 4],
    /// Upper z.
    pub max_z: [f32; 4],
    /// Child node, first list entry, or [`NULL_INDEX`].
    pub child: [u32; 4],
    /// Leaf triangle count, or 0.
    pub count: [u32; 4],
}
const _: () = assert!(core::mem::size_of::<Bvh4Node>() == 128);
const _: () = assert!(core::mem::align_of::<Bvh4Node>() == 4);

impl Bvh4Node {
    /// A node with four empty slots.
    pub const EMPTY: Bvh4Node = Bvh4Node {
        min_x: [f32::MAX; 4],
        min_y: [f32::MAX; 4],
        min_z: [f32::MAX; 4],
        max_x: [-f32::MAX; 4],
        max_y: [-f32::MAX; 4],
        max_z: [-f32::MAX; 4],
        child: [NULL_INDEX; 4],
        count: [0; 4],
    };
}

/// An 8-wide BVH node, 256 bytes (four cache lines): [`Bvh4Node`]'s layout with eight
/// slots, so that one 8-lane slab test (two SSE or one AVX register per plane) checks
/// all eight children and a ray visits fewer, wider nodes (Embree's BVH8). Slots follow
/// [`Bvh4Node`]'s rules: empty slots have `child == NULL_INDEX` and an inverted box.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct Bvh8Node {
    /// Lower x of each child box.
    pub min_x: [f32; 8],
    /// Lower y.
    pub min_y: [f32; 8],
    /// Lower z.
    pub min_z: [f32; 8],
    /// Upper x.
    pub max_x: [f32; 8],
    /// Upper y.
    pub max_y: [f32; 8],
    /// Upper z.
    pub max_z: [f32; 8],
    /// Child node, first list entry, or [`NULL_INDEX`].
    pub child: [u32; 8],
    /// Leaf triangle count, or 0.
    pub count: [u32; 8],
}
const _: () = assert!(core::mem::size_of::<Bvh8Node>() == 256);
const _: () = assert!(core::mem::align_of::<Bvh8Node>() == 4);

impl Bvh8Node {
    /// A node with eight empty slots.
    pub const EMPTY: Bvh8Node = Bvh8Node {
        min_x: [f32::MAX; 8],
        min_y: [f32::MAX; 8],
        min_z: [f32::MAX; 8],
        max_x: [-f32::MAX; 8],
        max_y: [-f32::MAX; 8],
        max_z: [-f32::MAX; 8],
        child: [NULL_INDEX; 8],
        count: [0; 8],
    };
}

/// A wide BVH node, whatever its width: its slots as `(lower corner, upper corner, child,
/// count)` for the image validation and the builder, its child links for the walk, and
/// where an image keeps such nodes.
pub trait WideNode: Pod {
    /// Slots per node.
    const WIDTH: usize;
    /// The structure kind of an image holding these nodes.
    const ACCEL: AccelKind;
    /// The section holding them.
    const SECTION: SectionKind;
    /// A node with every slot empty.
    fn empty() -> &'static Self;
    /// Slot `k` (`k < WIDTH`).
    fn slot(&self, k: usize) -> ([f32; 3], [f32; 3], u32, u32);
    /// Sets slot `k`.
    fn set_slot(&mut self, k: usize, lo: [f32; 3], hi: [f32; 3], child: u32, count: u32);
    /// Child (node index or first list entry) and leaf count of slot `k`.
    fn link(&self, k: usize) -> (u32, u32);
}

macro_rules! wide_node {
    ($t:ty, $w:expr, $accel:expr, $section:expr) => {
        impl WideNode for $t {
            const WIDTH: usize = $w;
            const ACCEL: AccelKind = $accel;
            const SECTION: SectionKind = $section;
            #[inline]
            fn empty() -> &'static Self {
                &<$t>::EMPTY
            }
            #[inline]
            fn slot(&self, k: usize) -> ([f32; 3], [f32; 3], u32, u32) {
                let k = k % $w;
                (
                    [self.min_x[k], self.min_y[k], self.min_z[k]],
                    [self.max_x[k], self.max_y[k], self.max_z[k]],
                    self.child[k],
                    self.count[k],
                )
            }
            #[inline]
            fn set_slot(&mut self, k: usize, lo: [f32; 3], hi: [f32; 3], child: u32, count: u32) {
                let k = k % $w;
                [self.min_x[k], self.min_y[k], self.min_z[k]] = lo;
                [self.max_x[k], self.max_y[k], self.max_z[k]] = hi;
                self.child[k] = child;
                self.count[k] = count;
            }
            #[inline(always)]
            fn link(&self, k: usize) -> (u32, u32) {
                (self.child[k % $w], self.count[k % $w])
            }
        }
    };
}
wide_node!(Bvh4Node, 4, AccelKind::Bvh4, SectionKind::Bvh4Nodes);
wide_node!(Bvh8Node, 8, AccelKind::Bvh8, SectionKind::Bvh8Nodes);

/// Wald's precomputed triangle for the projection test (Wald 2004, §7.1; Wald &
/// Slusallek 2001): 37 bytes of data padded to 48 so that triangles never straddle a
/// cache line in pairs, in three 16-byte rows.
///
/// The plane is `P[k] + n_u·P[u] + n_v·P[v] = n_d` with `(u, v) = (k+1, k+2) mod 3` and
/// `k` the dominant axis of the normal; the barycentric weights of the second and third
/// vertex are affine functions `b_nu·h_u + b_nv·h_v + b_d` and `c_nu·h_u + c_nv·h_v + c_d`
/// of the hit point projected to `(u, v)`. `k == 3` marks a degenerate triangle.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct WaldTriangle {
    /// Plane coefficient of `P[u]`.
    pub n_u: f32,
    /// Plane coefficient of `P[v]`.
    pub n_v: f32,
    /// Plane constant.
    pub n_d: f32,
    /// Projection axis 0–2, or 3 (degenerate).
    pub k: u32,
    /// Second-vertex weight: coefficient of `h_u`.
    pub b_nu: f32,
    /// Second-vertex weight: coefficient of `h_v`.
    pub b_nv: f32,
    /// Second-vertex weight: constant.
    pub b_d: f32,
    /// `sqrt(1 + n_u² + n_v²)`, for the scale-free parallelism test (in Wald's padding).
    pub n_scale: f32,
    /// Third-vertex weight: coefficient of `h_u`.
    pub c_nu: f32,
    /// Third-vertex weight: coefficient of `h_v`.
    pub c_nv: f32,
    /// Third-vertex weight: constant.
    pub c_d: f32,
    /// Unused, zero.
    pub _pad: u32,
}
const _: () = assert!(core::mem::size_of::<WaldTriangle>() == 48);
const _: () = assert!(core::mem::align_of::<WaldTriangle>() == 4);

/// Four triangles' vertices as SIMD lanes, 144 bytes: `v[i][axis]` holds coordinate
/// `axis` of vertex `i` of the four triangles, one per lane, so that one ray is tested
/// against four triangles with no gather (Embree's `Triangle4` leaves). The vertices are
/// copies of POSITIONS, in the order of PRIM_LISTS: no index is followed to reach them.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct TriBlock4 {
    /// `v[vertex][axis][lane]`.
    pub v: [[[f32; 4]; 3]; 3],
}
const _: () = assert!(core::mem::size_of::<TriBlock4>() == 144);
const _: () = assert!(core::mem::align_of::<TriBlock4>() == 4);

impl TriBlock4 {
    /// Triangles per block (PRIM_LISTS entries per record).
    pub const LANES: usize = 4;
}

/// A diffuse texture, 32 bytes: its size, where its texels start in TEXELS (row-major,
/// the top row first), how coordinates outside `[0, 1]` wrap, and how many mipmap levels
/// it has. Level `k` is `max(1, width >> k)` by `max(1, height >> k)` texels and follows
/// level `k − 1` in TEXELS.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq)]
pub struct TextureRecord {
    /// Width in texels (level 0).
    pub width: u32,
    /// Height in texels (level 0).
    pub height: u32,
    /// First texel in TEXELS (level 0's top-left).
    pub first: u32,
    /// [`TextureRecord::REPEAT`] or [`TextureRecord::CLAMP`].
    pub wrap: u32,
    /// Mipmap levels, 1 to [`TextureRecord::full_chain`].
    pub levels: u32,
    /// Unused, zero.
    pub _pad: [u32; 3],
}
const _: () = assert!(core::mem::size_of::<TextureRecord>() == 32);
const _: () = assert!(core::mem::align_of::<TextureRecord>() == 4);

impl TextureRecord {
    /// Coordinates wrap around (MTL's default).
    pub const REPEAT: u32 = 0;
    /// Coordinates clamp to the edge (MTL `-clamp on`).
    pub const CLAMP: u32 = 1;

    /// The levels of a complete mipmap chain down to 1 × 1 for a `width` × `height`
    /// texture: 1 + ⌊log₂ max(width, height)⌋.
    pub const fn full_chain(width: u32, height: u32) -> u32 {
        let side = if width > height { width } else { height };
        if side == 0 {
            0
        } else {
            32 - side.leading_zeros()
        }
    }

    /// Level `k`'s size in texels (at least 1 × 1).
    pub const fn level_size(width: u32, height: u32, k: u32) -> (u32, u32) {
        let (w, h) = if k >= 32 { (0, 0) } else { (width >> k, height >> k) };
        (if w == 0 { 1 } else { w }, if h == 0 { 1 } else { h })
    }

    /// Texels in levels `0..levels` together, saturating at `u64::MAX`: one level of a
    /// hostile record holds nearly 2⁶⁴ texels, and 32 of them overflow any sum, so a
    /// record that saturates is one no image can hold.
    pub fn chain_texels(width: u32, height: u32, levels: u32) -> u64 {
        (0..levels.min(32))
            .map(|k| TextureRecord::level_size(width, height, k))
            .fold(0u64, |sum, (w, h)| sum.saturating_add(w as u64 * h as u64))
    }

    /// Level `k` (clamped to the last) as a one-level texture of its own.
    pub fn level(&self, k: u32) -> TextureRecord {
        let k = k.min(self.levels.saturating_sub(1));
        let (width, height) = TextureRecord::level_size(self.width, self.height, k);
        let before = TextureRecord::chain_texels(self.width, self.height, k);
        TextureRecord { width, height, first: self.first.wrapping_add(before as u32), levels: 1, ..*self }
    }
}
