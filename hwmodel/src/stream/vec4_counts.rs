//! Instruction counts of raypipe-core's kernels as Purcell 2002 counts them (§3.2):
//! 4-wide fragment-program instructions of the NVIDIA vertex-program instruction set.
//!
//! The rule: one instruction per `ADD`, `MUL`, `MAD`, `DP3`, `MIN`, `MAX`, `SLT`, `SGE`,
//! `FRC`, `MOV` or select (`LRP`) on up to four components at once; one per scalar
//! `RCP`, `RSQ`, `LG2`, `EX2` (which take one component); one `TEX` per texture fetch.
//! Swizzles, negation and write masks are free, as in the instruction set. The
//! operations are raypipe-core's own, vectorised as written — no algebra is refolded and
//! nothing is fitted to the paper's table. A value whose scalar code has no vector form
//! (a `powf`, a chain of compares) keeps its scalar count.
//!
//! `body` counts are what a kernel does in either architecture. The multipass machine
//! adds, per invocation, one `TEX` per state texel it reads (see
//! [`crate::stream::cost_model`]) and what it recomputes because it does not store it
//! (the `*_RECOMPUTE` entries); the branching machine keeps those in registers — the
//! paper's "branching kernels are slightly smaller, since initialization and
//! termination instructions are removed" (§3.2).

/// `EyeRays::ray` + `clip_ray` against the scene box (core/src/camera.rs,
/// core/src/traverse/aabb.rs), x and y in one vector:
/// - pixel to screen: `ADD` 0.5, `MUL` 1/w, `MAD` ×2−1: 3;
/// - direction: `MUL` (sx·hw, sy·hh), `MAD` forward + right·a, `MAD` + up·b: 3;
/// - `normalize`: `DP3`, `RSQ`, `MUL`: 3;
/// - `clip_ray`: 1/d `RCP` ×3; the d = 0 guard, a compare and a select: 2; near and far
///   planes, `ADD` + `MUL` each: 4; swap, `MIN` + `MAX`: 2; far × growth: 1; t0 the
///   largest of three nears and `t_min`: 3 `MAX`; t1 likewise: 3 `MIN`; t0 ≤ t1: 1 — 19.
pub const GENERATE: u64 = 3 + 3 + 3 + 19;

/// `Dda::new` (core/src/traverse/dda.rs):
/// - `Ray::is_valid`: finite origin, finite direction, non-zero direction: 3 compares;
/// - `clip_ray` against the grid box: 19 (as in [`GENERATE`]); entry `ray.at(t0)`: `MAD`;
/// - cell: `ADD` −min, `MUL` 1/size, floor as x − `FRC`(x): 2, NaN guard and clamp
///   `MAX` + `MIN`: 6;
/// - step sign: `SGE`, `MAD` ×2−1: 2;
/// - `boundary_t` on all three axes: cell + (step > 0) `ADD`, `MAD` × size + min, `ADD`
///   −origin, `MUL` × 1/d, the infinite boundary of a zero direction (select): 5.
pub const SETUP: u64 = 3 + 19 + 1 + 6 + 2 + 5;

/// `Watertight::prepare` (core/src/intersect/watertight.rs): |d| `MAX`(d, −d) 1; the
/// major axis kz, 2 compares and 2 selects: 4; kx, ky by select: 2; the winding swap: 1;
/// sx, sy, sz: `RCP` of `d[kz]` and one `MUL`: 2 — 10. The branching machine prepares a
/// ray once, in setup; the multipass machine does not keep the sheared ray between
/// passes and prepares it in every intersection pass.
pub const PREPARE: u64 = 1 + 4 + 2 + 1 + 2;

/// `GridTraversal::step` + `Dda::step` (core/src/traverse/grid.rs, dda.rs):
/// - the first boundary: `MIN` ×2 over t_next and the lowest-axis mask, 2 compares and a
///   select: 5;
/// - t_exit (boundary < t_end ? max(boundary, t_enter) : t_end): `SLT`, `MAX`, select: 3;
/// - end of the walk: boundary ≥ t_end and the advanced cell outside the grid: `SGE`,
///   `SLT` + `SGE` on the cell, combine: 4;
/// - the cell's index as `DP3` with (1, dx, dx·dy): 1; its texture coordinate `MUL` and
///   the grid `TEX`: 2;
/// - advance: cell + step × mask `MAD` 1; `boundary_t` on three axes 4 and the masked
///   select 1: 6;
/// - t_enter ← t_exit: `MOV` 1; the hit is final (best.t < t_enter): `SLT` 1;
/// - the empty-cell test 1 and the first list entry's `TEX` 1.
pub const TRAVERSE: u64 = 5 + 3 + 4 + 2 + 6 + 1 + 1 + 1 + 1;

/// What a multipass traversal step recomputes from the ray each pass instead of storing
/// (the state texels hold only cell, t_next and t_enter — [`crate::stream::ray_state`]):
/// 1/d `RCP` ×3; the step sign `SGE`, `MAD`: 2; t_end, the grid box's far planes: `ADD`,
/// `MUL`, `ADD`, `MUL`, `MAX`, then `MIN` ×3 with t_max: 8 — 13.
pub const TRAVERSE_RECOMPUTE: u64 = 3 + 2 + 8;

/// `Watertight::intersect` + `test_triangle` and the list advance
/// (core/src/intersect/watertight.rs, triangle.rs; the model's read-ahead):
/// - the three vertices: `TEX` ×3 (Purcell's three RGB vertex textures);
/// - relative to the origin: `ADD` ×3; permuted and sheared, `DP3` for each of x, y, z
///   of each vertex: 9;
/// - the three edge functions at once: `MUL`, `MAD`: 2;
/// - the sign test: `SGE` and `SLT` on (U, V, W), each summed by `DP3` and compared: 4;
/// - det = U + V + W: `DP3` 1, zero test 1; the scaled distance: z scaled `MUL`, `DP3`: 2;
/// - `in_range`: det × t range `MUL`, two compares, det's sign: 4;
/// - 1/det `RCP` and (t, u, v) `MUL`: 2; `keep_closest`: compare and select the
///   (t, u, v, triangle) vector: 2;
/// - list advance `ADD`, the next entry's `TEX`, terminator test, voxel-exit test: 4.
pub const INTERSECT: u64 = 3 + 3 + 9 + 2 + 4 + 2 + 2 + 4 + 2 + 2 + 4;

/// `Surface::at` and the shader's fixed part (core/src/shade/surface.rs):
/// - fetches: three vertex normals, three vertex colours, the material: 7 `TEX`;
/// - geometric normal: 2 edges `ADD`, cross `MUL` + `MAD`: 4; weights 1 − u − v: 1;
/// - normal interpolation `MUL`, `MAD`, `MAD` 3 and its checks (length² `DP3`, finite
///   compare, select) 3; colour interpolation 3; `normalize_or_zero` 3; facing test and
///   flip: `DP3`, `SLT`, `MAD` 3;
/// - scene extent 1; hit point `MAD` 1; final colour (diffuse × tint × light +
///   emission) `MUL`, `MAD` 2.
pub const SHADE: u64 = 7 + 4 + 1 + 3 + 3 + 3 + 3 + 3 + 1 + 1 + 2;

/// One point light in `lambert::shade` / `shade_whitted`: direction `ADD`, normalize 3,
/// `DP3`, clamp `MAX`, × colour and accumulate `MAD`, the light kind's test 1: 8.
pub const SHADE_LIGHT: u64 = 1 + 3 + 1 + 1 + 1 + 1;

/// A textured hit's mipmap level and trilinear filter (core/src/shade/surface.rs,
/// texture.rs, ray_cone.rs):
/// - uv interpolation 3; uv edges 2, their cross product 1, `MAX` for abs 1, × width ×
///   height 1; incidence: both normalized 6, `DP3` 1; cone width: `DP3`, `RSQ`, `MAD` 3;
///   level: `RCP`, `MUL`, three `LG2` 3, half, sub and add 2, NaN test 1: 26;
/// - level clamp, floor, fraction 3; the two levels' records, 2 `TEX` and 2 to address
///   them: 4;
/// - per level: wrap, scale, floor and fraction of (u, v) 4, the four texel
///   coordinates 2, four texel `TEX` 4, four sRGB decodes 4, three blends 3: 17, × 2 = 34;
///   the blend of the two levels 1.
pub const TEXTURE: u64 = 26 + 3 + 4 + 34 + 1;

/// `blinn_phong::lobes` at a glossy hit: `Ks` clamped `MIN` + `MAX` 2, `Ns` tests and
/// clamp 2, `Kd + Ks` 1, its largest channel 2, the max with 1: 1, `RCP` 1, both lobes
/// scaled 2.
pub const GLOSSY: u64 = 2 + 2 + 1 + 2 + 1 + 1 + 2;

/// `BlinnPhong::eval_pi` for one light (core/src/shade/blinn_phong.rs):
/// - the eye direction normalized 3; hemisphere tests, 2 `DP3` and a vector compare 3;
/// - half vector `ADD` + normalize 4; N·H `DP3`, `MAX` 2; `powf` as `LG2`, `MUL`, `EX2`: 3;
/// - the normalisation `(n+2)(n+4) / (8 (2^(−n/2) + n))`, scalar: 9;
/// - × the power and × `Ks`: 2; added to the diffuse reflectance 1.
pub const GLOSSY_LIGHT: u64 = 3 + 3 + 4 + 2 + 3 + 9 + 2 + 1;

/// One emitted record: `Surface::offset_point` (normalize 3, `DP3` and flip 2, scale 1,
/// offset 1), the direction 1, the weight (three products) 3, its tests (max, finite) 2.
pub const SPAWN: u64 = 3 + 2 + 1 + 1 + 1 + 3 + 2;

/// A shadow ray's end: the occlusion test and the weighted add.
pub const SHADOW_ADD: u64 = 2;
