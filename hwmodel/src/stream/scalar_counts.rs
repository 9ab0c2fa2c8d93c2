//! Instruction counts of raypipe-core's kernels as scalar code: one instruction per
//! arithmetic operation, comparison, select, conversion, `sqrt` or reciprocal on one
//! value (a `Vec3` operation counts 3). Each count is broken down against the function
//! it comes from; change the kernel, change the count.

/// `EyeRays::ray` + `clip_ray` against the scene box (core/src/camera.rs,
/// core/src/traverse/aabb.rs).
/// - pixel to screen: x and y each convert, +0.5, ×1/w, ×2, −1: 10;
/// - direction `forward + right·(sx·hw) + up·(sy·hh)`: 2 + 3 + 3 + 6 = 14;
/// - `normalize`: dot 5, sqrt, reciprocal, scale 3: 10;
/// - `clip_ray`, per axis: d = 0 test, 1/d, near (2), far (2), compare and swap (3),
///   far × growth, near/t0 and far/t1 compare-select (4), t0 > t1 test: 15, × 3 = 45.
pub const GENERATE: u64 = 10 + 14 + 10 + 45;
/// `Dda::new` (core/src/traverse/dda.rs):
/// - `Ray::is_valid` (finite origin and direction, non-zero direction): 4;
/// - `clip_ray` against the grid box: 45 (as above); entry point `ray.at(t0)`: 6;
/// - per axis: cell `floor((p − min)/size)` with NaN guard, clamp, convert: 8; step
///   sign: 3; 1/d with zero guard: 3; `boundary_t`: select k (3), convert, × size,
///   + min, − origin, × 1/d (5): 8 — 22, × 3 = 66.
pub const SETUP: u64 = 4 + 45 + 6 + 66;
/// `GridTraversal::step` + `Dda::step` (core/src/traverse/grid.rs, dda.rs):
/// - done test 1; first-boundary axis: 2 compares, 2 selects: 4; its distance 1;
/// - `t_exit`: compare, max, select: 3; cell index x + dx·(y + dy·z): 4;
/// - end test 1; advance the cell 2; bounds test 2; `boundary_t` 8; `t_enter` 1;
/// - hit-is-final test (`best.t < t_enter`): 2; empty-cell test: 1.
pub const TRAVERSE: u64 = 1 + 4 + 1 + 3 + 4 + 1 + 2 + 2 + 8 + 1 + 2 + 1;
/// `Watertight::prepare` + `Watertight::intersect` + `test_triangle` + the list
/// advance (core/src/intersect/watertight.rs, triangle.rs; the model's read-ahead):
/// - prepare (the sheared ray is not kept between passes): |d| 3, major axis 3
///   compares + 2 selects, kx/ky 2, sign swap 3, sx, sy, sz 3 divisions: 16;
/// - vertices relative to the origin: 9; shear (`shear_edges`): 6 × (mul, sub): 12;
/// - edge functions: 3 × (2 mul, sub): 9; sign test: 6 compares, 4 logic ops: 10;
/// - det: 2 adds, zero test 1; `scaled_distance`: 3 + 3 mul, 2 add: 8;
/// - 1/det, t, u, v: 4; `in_range`: 3; `keep_closest` on (t, prim): 3 compares, 4
///   selects: 7; list advance, terminator test, voxel-exit test: 4.
pub const INTERSECT: u64 = 16 + 9 + 12 + 9 + 10 + 3 + 8 + 4 + 3 + 7 + 4;
/// `Surface::at` (core/src/shade/surface.rs) and the shader's fixed part:
/// - geometric normal: 2 vector subs, cross: 6 + 9 = 15; weights: 2;
/// - normal interpolation 15 and its checks (length², finite, select) 12;
/// - colour interpolation 15; `normalize_or_zero` 12; facing test and flip 9;
/// - scene extent 5; hit point `ray.at(t)` 6; final colour (diffuse × tint × light +
///   emission) 9.
pub const SHADE: u64 = 15 + 2 + 15 + 12 + 15 + 12 + 9 + 5 + 6 + 9;
/// One point light in `lambert::shade` / `shade_whitted`: direction 3, normalize 12,
/// dot 5, clamp 1, × colour 3, accumulate 3, kind tests 2 (an ambient light: 6 of
/// these 29).
pub const SHADE_LIGHT: u64 = 3 + 12 + 5 + 1 + 3 + 3 + 2;
/// The texture part of `Surface::at` and `texture::sample` (core/src/shade/surface.rs,
/// texture.rs, ray_cone.rs), charged as the trilinear case (two levels; a magnified
/// hit reads one):
/// - uv interpolation 10; uv edges 4, their cross product 3, abs 1, × width × height
///   with conversions 4; incidence: normalize both 24, dot 5; cone width: |d| 6,
///   multiply-add 3; level: divide 1, three log2 3, half, sub, add 3, NaN test 1: 68;
/// - level clamp, floor, fraction 4; each level's record (size shifts, the chain's
///   offset) 10;
/// - per level: two axes (wrap, scale, floor, fraction) 12, four wrapped texel
///   coordinates 8, four sRGB decodes (3 lookups each) 12, three Vec3 blends 27: 59,
///   × 2 = 118; the blend of the two levels 9.
pub const TEXTURE: u64 = 68 + 4 + 10 + 118 + 9;
/// `blinn_phong::lobes` at a glossy hit: `Ks` clamped 6, `Ns` tests and clamp 3,
/// `Kd + Ks` 3, its largest channel 2 and the max with 1: 3, reciprocal 1, both
/// lobes scaled 6.
pub const GLOSSY: u64 = 6 + 3 + 3 + 3 + 1 + 6;
/// `BlinnPhong::eval_pi` for one light (core/src/shade/blinn_phong.rs) and its share
/// of `Surface::point_light_shadow`:
/// - the eye direction: normalize 12, negate 3; hemisphere tests: 2 dots 10, 2
///   compares;
/// - half vector: add 3, normalize 12; N·H 5, max 1; `powf` as exp2(n·log2 x): 3;
/// - normalisation `(n+2)(n+4) / (8 (2^(−n/2) + n))`: 2 adds, 1 product, exp2 of a
///   product 2, add, ×8, divide 2: 9;
/// - × the power and × `Ks`: 4; added to the diffuse reflectance 3.
pub const GLOSSY_LIGHT: u64 = 12 + 3 + 10 + 2 + 3 + 12 + 5 + 1 + 3 + 9 + 4 + 3;
/// One emitted record: `Surface::offset_point` (normalize 12, dot and flip 8,
/// scale 8, offset 6) and the direction 3, the weight (3 products of 3) 9, its
/// tests (max, finite) 6: 52.
pub const SPAWN: u64 = 12 + 8 + 8 + 6 + 3 + 9 + 6;
/// A shadow ray's end: the occlusion test and the weighted add: 1 + 3.
pub const SHADOW_ADD: u64 = 4;
