//! The work any accepted image can cost one ray is bounded by the image's own counts
//! (docs/scene-format.md, "Work bounds"): a tree walk takes at most one step per node and
//! tests at most PRIM_LISTS' length; a grid walk visits at most `dx + dy + dz` cells and
//! reads at most its lists' length. Checked on random soups and on adversarial valid
//! scenes (every triangle crossing the whole scene), for closest-hit and any-hit
//! queries; and the structures that used to amplify work are
//! rejected by the parse.

use proptest::prelude::*;
use raypipe::build::image_writer::ImageWriter;
use raypipe::build::wide_bvh::BuiltWideBvh;
use raypipe::input::mesh::Mesh;
use raypipe::platform::aligned::AlignedBytes;
use raypipe::render::tracer::trace;
use raypipe::scene::{self, Accel, BuildOptions};
use raypipe_core::image::{Bvh4Node, Bvh8Node, SectionEntry, SectionKind, WideNode, MAX_WIDE_DEPTH, NULL_INDEX};
use raypipe_core::packet::bvh4::trace_bvh4_packet;
use raypipe_core::packet::step::trace_packet_steps;
use raypipe_core::packet::{PacketCounters, RayPacket};
use raypipe_core::traverse::brute_force::trace_brute_force;
use raypipe_core::traverse::occlusion::occluded;
use raypipe_core::{NoProbe, Ray, RayCounters, SceneError, SceneView, Vec3, Watertight};
use raypipe_tests::{build_soup, cornell_with, corrupt_image, put_u32, section_entry};

const ACCELS: [Accel; 6] = [Accel::Grid, Accel::Kd, Accel::Bvh, Accel::Bvh4, Accel::Bvh8, Accel::None];

/// The bound of docs/scene-format.md for a ray through `view`: (node steps, triangle tests).
fn bound(view: &SceneView<'_>) -> (u64, u64) {
    if let Some(g) = view.grid() {
        // The 3D-DDA leaves a cell through one face, so it visits at most one cell per
        // slab crossed on each axis, plus the first.
        let steps = g.dims.iter().map(|&d| d as u64).sum::<u64>() + 1;
        return (steps, g.list_entry_count() as u64);
    }
    let nodes = [
        view.kdtree().map(|t| t.node_count()),
        view.bvh().map(|t| t.node_count()),
        view.bvh4().map(|t| t.node_count()),
        view.bvh8().map(|t| t.node_count()),
    ]
    .into_iter()
    .flatten()
    .next();
    match nodes {
        Some(n) => (n as u64, view.prim_list_len() as u64),
        None => (0, view.triangle_count() as u64),
    }
}

/// Traces `ray` both ways and checks its counters against the bound.
fn check_ray(view: &SceneView<'_>, ray: &Ray) -> Result<RayCounters, TestCaseError> {
    let (steps, tests) = bound(view);
    let mut closest = RayCounters::default();
    trace::<Watertight, _>(view, ray, &mut NoProbe, &mut closest);
    let mut any = RayCounters::default();
    occluded::<Watertight, _>(view, ray, &mut NoProbe, &mut any);
    for c in [&closest, &any] {
        prop_assert!(c.nodes as u64 <= steps, "{} steps > {steps} ({:?})", c.nodes, view.accel());
        prop_assert!(c.tri_tests as u64 <= tests, "{} tests > {tests} ({:?})", c.tri_tests, view.accel());
    }
    Ok(closest)
}

fn coord() -> impl Strategy<Value = f32> {
    prop_oneof![3 => (-4i32..=4).prop_map(|i| i as f32 * 0.5), 1 => -3.0f32..3.0]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// Random soups (shared, degenerate and huge triangles), random rays from anywhere.
    #[test]
    fn no_ray_exceeds_the_bound_of_its_image(
        positions in prop::collection::vec([coord(), coord(), coord()], 3..24),
        picks in prop::collection::vec(any::<[prop::sample::Index; 3]>(), 1..40),
        rays in prop::collection::vec(([coord(), coord(), coord()], [-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0]), 1..16),
    ) {
        let n = positions.len();
        let tris: Vec<[u32; 3]> = picks.iter().map(|[a, b, c]| [a.index(n), b.index(n), c.index(n)].map(|i| i as u32)).collect();
        for accel in ACCELS {
            let scene = build_soup(positions.clone(), tris.clone(), accel, 3);
            let view = scene.view().expect("valid image");
            for (o, d) in &rays {
                let ray = Ray::new(Vec3::from(*o), Vec3::from(*d));
                check_ray(&view, &ray)?;
            }
        }
    }
}

/// A fan of long slivers through one point, every one crossing the whole scene: the
/// worst case for a spatial structure that a valid (builder-made) image can be. Every
/// ray stays within its bound, and the most any ray costs is printed.
#[test]
fn a_fan_of_slivers_through_one_point_stays_within_the_bound() {
    let spokes = 400u32;
    let mut positions = vec![[0.0f32, 0.0, 0.0]];
    for k in 0..=spokes {
        let a = std::f32::consts::TAU * k as f32 / spokes as f32;
        positions.push([10.0 * a.cos(), 10.0 * a.sin(), 0.3 * (k % 7) as f32]);
    }
    // Each triangle: the centre and two far points nearly opposite each other.
    let tris: Vec<[u32; 3]> =
        (0..spokes).map(|k| [1 + k, 1 + (k + spokes / 2) % spokes, 1 + (k + 1) % spokes]).collect();
    for accel in ACCELS {
        let scene = build_soup(positions.clone(), tris.clone(), accel, 16);
        let view = scene.view().unwrap();
        let (steps, tests) = bound(&view);
        let mut worst = RayCounters::default();
        for i in 0..64 {
            for j in 0..64 {
                let o = Vec3::new(-12.0 + 24.0 * i as f32 / 63.0, -12.0 + 24.0 * j as f32 / 63.0, 5.0);
                let c = check_ray(&view, &Ray::new(o, Vec3::new(0.01, 0.02, -1.0))).unwrap();
                let along =
                    check_ray(&view, &Ray::new(Vec3::new(-12.0, o.y, 0.5), Vec3::new(1.0, 0.001, 0.0))).unwrap();
                worst.nodes = worst.nodes.max(c.nodes).max(along.nodes);
                worst.tri_tests = worst.tri_tests.max(c.tri_tests).max(along.tri_tests);
            }
        }
        println!(
            "{accel:?}: worst ray {} steps (bound {steps}), {} tests (bound {tests}), {} triangles",
            worst.nodes, worst.tri_tests, spokes
        );
    }
}

fn section(bytes: &[u8], kind: SectionKind) -> SectionEntry {
    section_entry(bytes, kind).1
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().unwrap())
}

fn put_f32(b: &mut [u8], at: usize, v: f32) {
    b[at..at + 4].copy_from_slice(&v.to_le_bytes());
}

/// An "empty" wide-BVH slot (child null) whose box is inverted by one ulp
/// and whose count is 2^32 − 1 was accepted, and the single-ray box test entered it as a
/// leaf of four billion entries. Empty slots must now be exactly the empty encoding.
#[test]
fn an_almost_empty_wide_slot_with_a_huge_count_is_rejected() {
    for (accel, kind, w) in [(Accel::Bvh4, SectionKind::Bvh4Nodes, 4usize), (Accel::Bvh8, SectionKind::Bvh8Nodes, 8)] {
        let img = cornell_with(accel);
        let nodes = section(&img, kind);
        let size = 32 * w;
        // The first node with an empty slot.
        let (node, k) = (0..nodes.count as usize)
            .flat_map(|n| (0..w).map(move |k| (n, k)))
            .find(|&(n, k)| u32_at(&img, nodes.offset as usize + n * size + 24 * w + 4 * k) == NULL_INDEX)
            .expect("the Cornell box's wide BVH has an empty slot");
        let at = nodes.offset as usize + node * size;
        let d1 = |b: &mut [u8]| {
            for (a, c) in [4.42f32, 3.00002, 4.166].into_iter().enumerate() {
                put_f32(b, at + (a * w + k) * 4, c.next_up());
                put_f32(b, at + ((3 + a) * w + k) * 4, c);
            }
            put_u32(b, at + 28 * w + 4 * k, u32::MAX);
        };
        let e = corrupt_image(&img, d1);
        assert!(matches!(e, SceneError::BadTree { section, .. } if section == kind), "{accel:?}: {e}");
        // The exact empty box with a count is no better.
        let e = corrupt_image(&img, |b| put_u32(b, at + 28 * w + 4 * k, 7));
        assert!(matches!(e, SceneError::BadTree { .. }), "{accel:?}: {e}");
    }
}

/// Leaves whose ranges add up to more entries than PRIM_LISTS holds (here: every leaf
/// slot of a node covering the whole list) would let a ray test the list many times over.
#[test]
fn leaves_holding_more_than_the_list_are_rejected() {
    let img = cornell_with(Accel::Bvh4);
    let nodes = section(&img, SectionKind::Bvh4Nodes);
    let lists = section(&img, SectionKind::PrimLists);
    let size = 128;
    let (child, count) = (96, 112);
    // A node with two leaf slots.
    let node = (0..nodes.count as usize)
        .find(|&n| (0..4).filter(|&k| u32_at(&img, nodes.offset as usize + n * size + count + 4 * k) > 0).count() >= 2)
        .expect("a node with two leaves");
    let at = nodes.offset as usize + node * size;
    let e = corrupt_image(&img, |b| {
        for k in 0..4 {
            if u32_at(b, at + count + 4 * k) > 0 {
                put_u32(b, at + child + 4 * k, 0);
                put_u32(b, at + count + 4 * k, lists.count);
            }
        }
    });
    assert!(matches!(e, SceneError::BadTree { section: SectionKind::Bvh4Nodes, .. }), "{e}");
}

/// Grid cells sharing one list (a 330 KB image cost one ray 10^9 tests), or
/// starting in the middle of another cell's list, are rejected.
#[test]
fn grid_cells_sharing_a_list_are_rejected() {
    let img = cornell_with(Accel::Grid);
    let cells = section(&img, SectionKind::GridCells);
    let full: Vec<usize> = (0..cells.count as usize)
        .filter(|&i| u32_at(&img, cells.offset as usize + 4 * i) != NULL_INDEX)
        .take(2)
        .collect();
    let [a, b] = full[..] else { panic!("two full cells") };
    let first = u32_at(&img, cells.offset as usize + 4 * a);
    let e = corrupt_image(&img, |bytes| put_u32(bytes, cells.offset as usize + 4 * b, first));
    assert_eq!(e, SceneError::SharedList { cell: b as u32 });
    let e = corrupt_image(&img, |bytes| put_u32(bytes, cells.offset as usize + 4 * b, first + 1));
    assert!(matches!(e, SceneError::SharedList { .. }), "{e}");
    assert!(e.to_string().contains("shares a primitive list"));
}

/// A 20,000-vertex OBJ polygon made 91 M grid list entries (22 s) when it
/// was triangulated as a fan; split by halving it makes `n log n` references.
#[test]
fn a_large_obj_polygon_builds_a_grid_of_n_log_n_references() {
    let n = 20_000usize;
    let mut obj = String::new();
    for k in 0..n {
        let a = std::f64::consts::TAU * k as f64 / n as f64;
        obj += &format!("v {} {} 0\n", 10.0 * a.cos(), 10.0 * a.sin());
    }
    obj += "f";
    for k in 1..=n {
        obj += &format!(" {k}");
    }
    obj += "\n";
    let (mesh, _) = raypipe::input::obj::load_obj_str("polygon.obj", &obj, &|_| None).unwrap();
    assert_eq!(mesh.triangles.len(), n - 2);
    let opts = BuildOptions { accel: Accel::Grid, ..Default::default() };
    let scene = scene::build("polygon".into(), mesh, Vec::new(), Default::default(), &opts).unwrap();
    let view = scene.view().unwrap();
    let entries = view.grid().unwrap().list_entry_count();
    let log_n = (n as f64).log2();
    println!("{n}-gon: {entries} grid list entries ({:.1} n log2 n)", entries as f64 / (n as f64 * log_n));
    assert!((entries as f64) < 4.0 * n as f64 * log_n, "{entries} list entries");
}

/// With `t_min < 0` the kd-tree returned another hit than every other
/// structure (it ignores the part of the ray behind its origin). The rule is now one for
/// all: a ray starts at its origin, `Ray::is_valid` demands `0 <= t_min`, and every
/// structure and the packet kernels return no hit for such a ray; the batch reader
/// rejects it with the row named.
#[test]
fn a_negative_t_min_is_no_ray_for_any_structure() {
    let origin = Vec3::new(0.0, 1.0, 0.5);
    let dir = Vec3::new(0.3, -0.2, -1.0);
    let behind = Ray { origin, dir, t_min: -2.0, t_max: f32::INFINITY };
    assert!(!behind.is_valid());
    let mut hits = Vec::new();
    for accel in ACCELS {
        let img = cornell_with(accel);
        let view = SceneView::parse(&img).unwrap();
        let mut c = RayCounters::default();
        assert_eq!(trace::<Watertight, _>(&view, &behind, &mut NoProbe, &mut c), None, "{accel:?}");
        assert!(!occluded::<Watertight, _>(&view, &behind, &mut NoProbe, &mut c), "{accel:?}");
        let mut packet = raypipe_core::packet::RayPacket::<4>::new();
        packet.set(0, &behind);
        assert_eq!(packet.active & 1, 0, "{accel:?}: the packet lane is inactive");
        let ahead = Ray { t_min: 0.0, ..behind };
        hits.push(trace::<Watertight, _>(&view, &ahead, &mut NoProbe, &mut c).map(|h| (h.t.to_bits(), h.prim)));
    }
    assert!(hits[0].is_some() && hits.iter().all(|h| *h == hits[0]), "{hits:?}");
    let rows = raypipe::input::npy::Array2 { rows: 1, cols: 8, data: vec![0.0, 1.0, 0.5, 0.3, -0.2, -1.0, -2.0, 10.0] };
    let (_, invalid) = raypipe::render::batch::rays_from_array(&rows).unwrap();
    assert_eq!(invalid, [true], "a negative t_min is no ray: returned as a miss");
}

/// A chain of wide nodes `depth` deep, made to fill a walk's stack: each node's slot 0
/// is the next node, with a box around everything, and its other slots leaves of one
/// triangle each (the last node: leaves only). The triangles stand across the x axis,
/// the deeper the nearer, and every leaf box lies beyond the nodes' entry: a ray along
/// +x descends the whole chain first, leaving every level's leaves on its stack.
fn chain_image<N: WideNode>(depth: usize) -> AlignedBytes {
    let w = N::WIDTH;
    let count = depth * (w - 1) + 1;
    let mut mesh = Mesh::default();
    let x_of = |id: usize| 10.0 + 0.01 * (count - id) as f32;
    for id in 0..count {
        let x = x_of(id);
        let at = mesh.positions.len() as u32;
        mesh.positions.extend([[x, -1.0, -1.0], [x, 3.0, -1.0], [x, -1.0, 3.0]]);
        mesh.triangles.push([at, at + 1, at + 2]);
    }
    let (lo, hi) = ([9.0, -1.0, -1.0], [20.0, 3.0, 3.0]);
    let mut nodes = Vec::new();
    let mut id = 0u32;
    for level in 0..depth {
        let mut node = *N::empty();
        let last = level + 1 == depth;
        for k in 0..w {
            if k == 0 && !last {
                node.set_slot(0, lo, hi, level as u32 + 1, 0);
            } else if k > 0 || last {
                let x = x_of(id as usize);
                node.set_slot(k, [x, -1.0, -1.0], [x, 3.0, 3.0], id, 1);
                id += 1;
            }
        }
        nodes.push(node);
    }
    let prims: Vec<u32> = (0..id).collect();
    let bvh = BuiltWideBvh { nodes, prims, depth: depth as u32 };
    ImageWriter::new(&mesh).wide_bvh(&bvh).finish().expect("the chain's image")
}

/// The wide BVHs may be at most `MAX_WIDE_DEPTH` levels deep, which bounds a firmware
/// walk's stack (≤ 2 KiB for a 4-wide walk): a chain that deep, made to fill
/// the stack, gives the brute-force hits on every kernel (single rays, any-hit, the
/// packet walk and the 4-wide packet kernel); one level more is rejected by the parse.
#[test]
fn wide_bvhs_at_the_depth_limit_fill_the_stack_and_one_level_more_is_rejected() {
    fn check<N: WideNode>() {
        let img = chain_image::<N>(MAX_WIDE_DEPTH as usize);
        let view = SceneView::parse(&img).expect("a chain at the depth limit is valid");
        let rays: [Ray; 16] = std::array::from_fn(|i| {
            let (y, z) = (0.1 + 0.05 * i as f32, 0.9 - 0.04 * i as f32);
            Ray::new(Vec3::new(0.0, y, z), Vec3::new(1.0, 0.001 * i as f32, -0.002 * i as f32))
        });
        let mut reference = [None; 16];
        for (i, ray) in rays.iter().enumerate() {
            let want = trace_brute_force::<Watertight, _>(&view, ray, &mut NoProbe, &mut RayCounters::default());
            assert!(want.is_some(), "{}: ray {i} crosses every triangle", N::WIDTH);
            let mut counters = RayCounters::default();
            assert_eq!(trace::<Watertight, _>(&view, ray, &mut NoProbe, &mut counters), want, "{}: ray {i}", N::WIDTH);
            // The walk descended the whole chain before it found a hit.
            assert!(counters.nodes >= MAX_WIDE_DEPTH, "{}: {} node steps", N::WIDTH, counters.nodes);
            assert!(occluded::<Watertight, _>(&view, ray, &mut NoProbe, &mut RayCounters::default()));
            reference[i] = want;
        }
        let mut hits = [None; 16];
        trace_packet_steps::<Watertight, _, 16>(&view, &rays, u64::MAX, &mut hits, &mut NoProbe);
        assert_eq!(hits, reference, "{}: packet walk", N::WIDTH);
        if let Some(bvh) = view.bvh4() {
            let mut packet = RayPacket::<16>::new();
            packet.fill(&rays);
            let mut hits = [None; 16];
            trace_bvh4_packet::<Watertight, _, 16>(
                &view,
                bvh,
                &packet,
                &mut hits,
                &mut NoProbe,
                &mut PacketCounters::default(),
            );
            assert_eq!(hits, reference, "4-wide packet kernel");
        }
        let deeper = chain_image::<N>(MAX_WIDE_DEPTH as usize + 1);
        let e = SceneView::parse(&deeper).expect_err("a chain one level deeper is rejected");
        assert!(matches!(e, SceneError::BadTree { section, .. } if section == N::SECTION), "{e}");
        assert!(e.to_string().contains(&format!("depth above {MAX_WIDE_DEPTH}")), "{e}");
    }
    check::<Bvh4Node>();
    check::<Bvh8Node>();
}
