//! The first contract of `docs/design.md`: for random triangle soups and rays, every structure (grid,
//! kd-tree, BVH) returns exactly the brute-force hit — same triangle id, bit-identical
//! `t` and barycentrics — and the same misses, with either intersection kernel.

use proptest::prelude::*;
use raypipe::render::tracer::trace;
use raypipe::scene::Accel;
use raypipe::scene::TriangleLayout;
use raypipe_core::image::TriBlock4;
use raypipe_core::traverse::brute_force::trace_brute_force;
use raypipe_core::traverse::walk::trace_walk;
use raypipe_core::Vec3;
use raypipe_core::Vec4;
use raypipe_core::{
    Hit, Intersector, MollerTrumbore, NoProbe, Ray, RayCounters, SceneView, WaldProjection, Watertight,
};
use raypipe_tests::soup_rays::{make_ray, point, ray_kind, soup, RayKind, Soup};
use raypipe_tests::{build_soup, build_soup_layout};

fn check<I: Intersector>(view: &SceneView<'_>, ray: &Ray) -> Result<(Option<Hit>, RayCounters), TestCaseError> {
    let mut cg = RayCounters::default();
    let g = trace::<I, _>(view, ray, &mut NoProbe, &mut cg);
    let b = trace_brute_force::<I, _>(view, ray, &mut NoProbe, &mut RayCounters::default());
    // The step-by-step walk the hardware model drives finds the same hit.
    let w = trace_walk::<I, _>(view, ray, &mut NoProbe);
    let same = |a: Option<Hit>, b: Option<Hit>| match (a, b) {
        (None, None) => true,
        (Some(a), Some(b)) => a.bits_eq(&b),
        _ => false,
    };
    if !same(w, g) {
        return Err(TestCaseError::fail(format!("{}: walk {w:?} != tracer {g:?} for {ray:?}", I::NAME)));
    }
    match (g, b) {
        (None, None) => {}
        (Some(g), Some(b)) if g.bits_eq(&b) => {}
        _ => {
            let what = if view.grid().is_some() {
                "grid"
            } else if view.bvh().is_some() {
                "bvh"
            } else if view.bvh4().is_some() {
                "bvh4"
            } else if view.bvh8().is_some() {
                "bvh8"
            } else if view.kdtree().is_some() {
                "kd-tree"
            } else {
                "no structure"
            };
            return Err(TestCaseError::fail(format!("{} {what}: {g:?} != brute force {b:?} for {ray:?}", I::NAME)));
        }
    }
    Ok((g, cg))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 600, ..ProptestConfig::default() })]

    #[test]
    fn grid_returns_the_brute_force_hit(
        soup in soup(),
        min_dim in 1u32..10,
        rays in prop::collection::vec((ray_kind(), prop_oneof![
            4 => Just((0.0f32, f32::INFINITY)),
            1 => (0.0f32..4.0, 4.0f32..12.0),
        ]), 48),
    ) {
        let grid = build_soup(soup.positions.clone(), soup.triangles.clone(), Accel::Grid, min_dim);
        let gview = grid.view().expect("valid image");
        if let Some(a) = soup.flat_axis {
            prop_assert_eq!(gview.grid().unwrap().dims[a], 1, "a flat axis gets one cell");
        }
        let kd = build_soup(soup.positions.clone(), soup.triangles.clone(), Accel::Kd, 1);
        let bvh = build_soup(soup.positions.clone(), soup.triangles.clone(), Accel::Bvh, 1);
        let bvh4 = build_soup(soup.positions.clone(), soup.triangles.clone(), Accel::Bvh4, 1);
        let bvh8 = build_soup(soup.positions.clone(), soup.triangles.clone(), Accel::Bvh8, 1);
        // Leaf triangles in blocks of four, tested four at a time by single rays.
        let blocks = |accel| build_soup_layout(soup.positions.clone(), soup.triangles.clone(), accel, TriangleLayout::Blocks);
        let (bvh4_blocks, bvh8_blocks) = (blocks(Accel::Bvh4), blocks(Accel::Bvh8));
        prop_assert!(bvh8_blocks.view().unwrap().has_tri_blocks());
        for scene in [&grid, &kd, &bvh, &bvh4, &bvh8, &bvh4_blocks, &bvh8_blocks] {
            let view = scene.view().expect("valid image");
            for (kind, range) in &rays {
                // Rays on cell boundaries are placed with the grid's geometry.
                let ray = make_ray(kind, &soup, &gview, *range);
                check::<Watertight>(&view, &ray)?;
                // Möller–Trumbore's error grows with the origin's distance over the
                // angle to the plane; it agrees across structures for nearby origins.
                if ray.origin.abs().max_element() <= 8.0 {
                    check::<MollerTrumbore>(&view, &ray)?;
                    check::<WaldProjection>(&view, &ray)?;
                }
            }
        }
    }
}

/// The generator above must produce hits, or the property would be vacuous.
#[test]
fn generated_rays_do_hit() {
    use proptest::strategy::ValueTree;
    use proptest::test_runner::TestRunner;
    let mut runner = TestRunner::deterministic();
    let (mut rays, mut hits) = (0, 0);
    for _ in 0..40 {
        let s = soup().new_tree(&mut runner).unwrap().current();
        let scene = build_soup(s.positions.clone(), s.triangles.clone(), Accel::Grid, 4);
        let view = scene.view().unwrap();
        for _ in 0..20 {
            let k = ray_kind().new_tree(&mut runner).unwrap().current();
            let ray = make_ray(&k, &s, &view, (0.0, f32::INFINITY));
            rays += 1;
            hits += check::<Watertight>(&view, &ray).unwrap().0.is_some() as u32;
        }
    }
    assert!(hits * 5 > rays, "only {hits} of {rays} generated rays hit something");
}

/// A closed mesh (a cube) shot through its shared edges and vertices: the watertight
/// kernel never lets a ray slip between adjacent triangles.
#[test]
fn no_leak_through_shared_edges_of_a_closed_cube() {
    let p: Vec<[f32; 3]> = (0..8).map(|i| [(i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32]).collect();
    let quads = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]];
    let tris: Vec<[u32; 3]> = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
    let mut scenes: Vec<_> = [Accel::Grid, Accel::Kd, Accel::Bvh, Accel::Bvh4, Accel::Bvh8]
        .map(|a| build_soup(p.clone(), tris.clone(), a, 3))
        .into();
    scenes.extend(
        [Accel::Bvh4, Accel::Bvh8].map(|a| build_soup_layout(p.clone(), tris.clone(), a, TriangleLayout::Blocks)),
    );
    for scene in &scenes {
        let view = scene.view().unwrap();
        let mut n = 0;
        // Rays from outside through points on the diagonals (shared edges) and corners.
        for i in 0..=16 {
            for j in 0..=16 {
                let (a, b) = (i as f32 / 16.0, j as f32 / 16.0);
                // The last family aims at the main diagonal, whose end points a ray can only graze.
                let c = (i.clamp(1, 15)) as f32 / 16.0;
                for (o, target) in [
                    (Vec3::new(a, b, -3.0), Vec3::new(a, b, 0.0)),
                    (Vec3::new(-3.0, a, b), Vec3::new(0.0, a, b)),
                    (Vec3::new(2.0 + a, 3.0, -1.0 - b), Vec3::new(c, c, c)),
                ] {
                    let ray = Ray::new(o, target - o);
                    let (hit, _) = check::<Watertight>(&view, &ray).unwrap();
                    assert!(hit.is_some(), "ray {ray:?} leaked through the closed cube");
                    n += 1;
                }
            }
        }
        assert_eq!(n, 17 * 17 * 3);
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    /// Purcell's bounding-box test in the eye-ray kernel only ends rays that brute force
    /// also finds no hit for, and every eye ray through the grid gets the brute-force hit.
    #[test]
    fn eye_rays_and_the_bounds_test_agree_with_brute_force(
        soup in soup(),
        eye in [-8.0f32..8.0, -8.0f32..8.0, -8.0f32..8.0],
        look in point(),
        fov in 10.0f32..120.0,
        accel in prop_oneof![Just(Accel::Grid), Just(Accel::Kd), Just(Accel::Bvh), Just(Accel::Bvh4), Just(Accel::Bvh8)],
    ) {
        use raypipe_core::camera::{Camera, EyeRays};
        let scene = build_soup(soup.positions.clone(), soup.triangles.clone(), accel, 4);
        let view = scene.view().unwrap();
        let cam = Camera { eye: Vec3::from(eye), look_at: Vec3::from(look), up: Vec3::Y, vfov_deg: fov, width: 12, height: 9 };
        let Ok(rays) = EyeRays::new(&cam) else { return Ok(()) };
        let (lo, hi) = view.test_bounds();
        for y in 0..9 {
            for x in 0..12 {
                match rays.ray_in_scene(x, y, lo, hi) {
                    None => {
                        let b = trace_brute_force::<Watertight, _>(&view, &rays.ray(x, y), &mut NoProbe, &mut RayCounters::default());
                        prop_assert!(b.is_none(), "bounds test ended a ray that hits {b:?}");
                    }
                    Some(ray) => {
                        check::<Watertight>(&view, &ray)?;
                    }
                }
            }
        }
    }
}

/// Traces every ray both alone and in a packet of `N`, and demands identical hits.
fn packet_matches_single<const N: usize>(view: &SceneView<'_>, rays: &[Ray]) -> Result<(), TestCaseError> {
    use raypipe::render::tracer::{occluded_packet, trace_packet};
    use raypipe_core::packet::step::trace_packet_steps;
    use raypipe_core::packet::{PacketCounters, RayPacket};
    use raypipe_core::traverse::occlusion::occluded;
    use raypipe_core::traverse::wide_bvh::last_occluder::LastOccluder;
    // One shadow cache across the packets, as the batches keep it.
    let mut cache = LastOccluder::default();
    for chunk in rays.chunks(N) {
        let mut packet = RayPacket::<N>::new();
        for (i, r) in chunk.iter().enumerate() {
            packet.set(i, r);
        }
        let mut hits = [None; N];
        let mut pc = PacketCounters::default();
        trace_packet::<Watertight, _, N>(view, &packet, &mut hits, &mut NoProbe, &mut pc);
        for (i, r) in chunk.iter().enumerate() {
            let single = trace::<Watertight, _>(view, r, &mut NoProbe, &mut RayCounters::default());
            let same = match (hits[i], single) {
                (None, None) => true,
                (Some(a), Some(b)) => a.bits_eq(&b),
                _ => false,
            };
            prop_assert!(same, "packet of {N}, lane {i}: {:?} != single {:?} for {r:?}", hits[i], single);
        }
        prop_assert!(pc.active_lanes <= pc.visits * N as u64);
        // The any-hit query of the same packet: blocked exactly where the single ray has
        // a hit, and where the single-ray any-hit query says so.
        let blocked = occluded_packet::<Watertight, _, N>(view, &packet, &mut cache, &mut NoProbe, &mut pc);
        prop_assert_eq!(blocked & !packet.live(), 0, "packet of {}: inactive lanes blocked", N);
        for (i, r) in chunk.iter().enumerate() {
            let single = trace::<Watertight, _>(view, r, &mut NoProbe, &mut RayCounters::default());
            let any = occluded::<Watertight, _>(view, r, &mut NoProbe, &mut RayCounters::default());
            prop_assert_eq!(any, single.is_some(), "any-hit query for {:?}", r);
            prop_assert_eq!(blocked & (1 << i) != 0, any, "any-hit packet of {}, lane {} for {:?}", N, i, r);
        }
        // SaarCOR's shared packet walk, one node per step, as the hardware model drives it.
        let mut rays_n = [Ray { origin: Vec3::ZERO, dir: Vec3::X, t_min: 0.0, t_max: 0.0 }; N];
        rays_n[..chunk.len()].copy_from_slice(chunk);
        let mut stepped = [None; N];
        trace_packet_steps::<Watertight, _, N>(view, &rays_n, packet.active, &mut stepped, &mut NoProbe);
        for (i, r) in chunk.iter().enumerate() {
            let single = trace::<Watertight, _>(view, r, &mut NoProbe, &mut RayCounters::default());
            let same = match (stepped[i], single) {
                (None, None) => true,
                (Some(a), Some(b)) => a.bits_eq(&b),
                _ => false,
            };
            prop_assert!(same, "packet steps of {N}, lane {i}: {:?} != single {:?} for {r:?}", stepped[i], single);
        }
    }
    Ok(())
}

/// The host's ray-batch driver (`raypipe trace`), whose single-ray loop runs the AVX2
/// build of the kernels where the CPU has it, returns the bits of [`trace`] ray by ray,
/// into a fresh output and into one reused across batches (longer, and holding other
/// records, before each), in every order it may trace single rays in, on one thread and
/// two.
fn batch_matches_single(view: &SceneView<'_>, rays: &[Ray]) -> Result<(), TestCaseError> {
    use raypipe::input::npy::HitRecord;
    use raypipe::render::batch::{occluded_batch, trace_batch, trace_batch_into, BatchOptions, BatchScratch};
    use raypipe::render::packets::PacketSize;
    use raypipe::render::ray_order::RayOrder;
    use raypipe::render::tracer::IntersectorKind;
    let stale = HitRecord { t: 1.0, u: 0.25, v: 0.5, prim: 7 };
    let mut reused = vec![stale; rays.len() + 3];
    let mut scratch = BatchScratch::default();
    let runs = [
        (PacketSize::Single, RayOrder::Input, 1),
        (PacketSize::Single, RayOrder::Direction, 1),
        (PacketSize::Single, RayOrder::Direction, 2),
        (PacketSize::Single, RayOrder::Auto, 2),
        (PacketSize::P64, RayOrder::Direction, 1),
    ];
    for (packet, order, threads) in runs {
        let opts = BatchOptions { kind: IntersectorKind::Watertight, packet, order, threads: Some(threads) };
        let fresh = trace_batch(view, rays, opts).unwrap();
        trace_batch_into(view, rays, opts, &mut reused, &mut scratch).unwrap();
        prop_assert_eq!(fresh.len(), rays.len());
        prop_assert_eq!(reused.len(), rays.len());
        for ((r, h), h2) in rays.iter().zip(&fresh).zip(&reused) {
            let single = trace::<Watertight, _>(view, r, &mut NoProbe, &mut RayCounters::default());
            let want = single.map_or((f32::INFINITY.to_bits(), 0, 0, -1), |s| {
                (s.t.to_bits(), s.u.to_bits(), s.v.to_bits(), s.prim as i32)
            });
            let got = (h.t.to_bits(), h.u.to_bits(), h.v.to_bits(), h.prim);
            prop_assert_eq!(got, want, "{:?} batch, {:?} order, {} threads, for {:?}", packet, order, threads, r);
            let got = (h2.t.to_bits(), h2.u.to_bits(), h2.v.to_bits(), h2.prim);
            prop_assert_eq!(got, want, "{:?} batch into a reused output, {:?} order, for {:?}", packet, order, r);
        }
        reused.push(stale);
        // The any-hit batch, with every third ray marked invalid (reported unblocked).
        let invalid: Vec<bool> = (0..rays.len()).map(|i| i % 3 == 1).collect();
        let blocked = occluded_batch(view, rays, &invalid, opts, &mut scratch).unwrap();
        prop_assert_eq!(blocked.len(), rays.len());
        for ((r, b), bad) in rays.iter().zip(&blocked).zip(&invalid) {
            let hit = trace::<Watertight, _>(view, r, &mut NoProbe, &mut RayCounters::default());
            prop_assert_eq!(*b, !bad && hit.is_some(), "{:?} any-hit batch, {:?} order, for {:?}", packet, order, r);
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    /// Packets of 2×2, 4×4 and 8×8 — coherent (a camera's pixel block) or not (random
    /// rays) — return exactly the single-ray hits, hence the brute-force hits, for every
    /// structure.
    #[test]
    fn packets_return_the_single_ray_hits(
        soup in soup(),
        eye in [-8.0f32..8.0, -8.0f32..8.0, -8.0f32..8.0],
        look in point(),
        random in prop::collection::vec(ray_kind(), 64),
        light in point(),
        accel in prop_oneof![Just(Accel::Grid), Just(Accel::Kd), Just(Accel::Bvh), Just(Accel::Bvh4), Just(Accel::Bvh8), Just(Accel::None)],
        layout in prop_oneof![Just(TriangleLayout::Indexed), Just(TriangleLayout::Blocks)],
    ) {
        use raypipe_core::camera::{Camera, EyeRays};
        let scene = match layout {
            TriangleLayout::Blocks => build_soup_layout(soup.positions.clone(), soup.triangles.clone(), accel, layout),
            _ => build_soup(soup.positions.clone(), soup.triangles.clone(), accel, 3),
        };
        let view = scene.view().unwrap();
        let grid = build_soup(soup.positions.clone(), soup.triangles.clone(), Accel::Grid, 3);
        let gview = grid.view().unwrap();
        let mut rays: Vec<Ray> = random.iter().map(|k| make_ray(k, &soup, &gview, (0.0, f32::INFINITY))).collect();
        let cam = Camera { eye: Vec3::from(eye), look_at: Vec3::from(look), up: Vec3::Y, vfov_deg: 50.0, width: 8, height: 8 };
        if let Ok(e) = EyeRays::new(&cam) {
            let eye_rays: Vec<Ray> = (0..64).map(|i| e.ray(i % 8, i / 8)).collect();
            // Shadow segments from the eye rays' hits (or far points) to one light: rays of
            // many origins and one end, blocked and not.
            let shadow = eye_rays.iter().map(|r| {
                let t = trace::<Watertight, _>(&view, r, &mut NoProbe, &mut RayCounters::default()).map_or(4.0, |h| h.t);
                let p = r.origin + r.dir * (t * 0.999);
                Ray { origin: p, dir: Vec3::from(light) - p, t_min: 0.0, t_max: 0.999 }
            });
            rays.extend(eye_rays.iter().copied().chain(shadow));
        }
        packet_matches_single::<4>(&view, &rays)?;
        packet_matches_single::<16>(&view, &rays)?;
        packet_matches_single::<64>(&view, &rays)?;
        batch_matches_single(&view, &rays)?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    /// Wald's 48-byte triangle layout: the stored records give the same hits as records
    /// computed on the fly from the vertices, in every structure and in brute force.
    #[test]
    fn wald_triangle_layout_returns_the_brute_force_hit(
        soup in soup(),
        rays in prop::collection::vec(ray_kind(), 32),
        accel in prop_oneof![Just(Accel::Grid), Just(Accel::Kd), Just(Accel::Bvh), Just(Accel::Bvh4), Just(Accel::Bvh8)],
    ) {
        let stored = build_soup_layout(soup.positions.clone(), soup.triangles.clone(), accel, TriangleLayout::Wald);
        let sview = stored.view().unwrap();
        prop_assert!(sview.has_wald_triangles());
        let plain = build_soup(soup.positions.clone(), soup.triangles.clone(), Accel::None, 1);
        let pview = plain.view().unwrap();
        let grid = build_soup(soup.positions.clone(), soup.triangles.clone(), Accel::Grid, 3);
        let gview = grid.view().unwrap();
        for k in &rays {
            let ray = make_ray(k, &soup, &gview, (0.0, f32::INFINITY));
            if ray.origin.abs().max_element() > 8.0 {
                continue;
            }
            let (a, _) = check::<WaldProjection>(&sview, &ray)?;
            let b = trace_brute_force::<WaldProjection, _>(&pview, &ray, &mut NoProbe, &mut RayCounters::default());
            prop_assert!(a.map(|h| (h.t.to_bits(), h.u.to_bits(), h.v.to_bits(), h.prim)) == b.map(|h| (h.t.to_bits(), h.u.to_bits(), h.v.to_bits(), h.prim)));
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    /// Huge and tiny coordinates: the same soups scaled by 1e-4 … 1e4 and moved far from
    /// the origin; every structure still returns the brute-force hit (watertight kernel).
    #[test]
    fn huge_and_tiny_coordinates(
        soup in soup(),
        rays in prop::collection::vec(ray_kind(), 24),
        scale in prop_oneof![Just(1e-4f32), Just(1e-2), Just(1e3), Just(1e4)],
        offset in prop_oneof![Just(0.0f32), Just(1e3), Just(-5e4)],
    ) {
        let map = |p: [f32; 3]| p.map(|c| c * scale + offset);
        let positions: Vec<[f32; 3]> = soup.positions.iter().map(|&p| map(p)).collect();
        let scaled = Soup { positions: positions.clone(), triangles: soup.triangles.clone(), flat_axis: soup.flat_axis };
        let grid = build_soup(positions.clone(), soup.triangles.clone(), Accel::Grid, 3);
        let gview = grid.view().unwrap();
        let blocks = [Accel::Bvh4, Accel::Bvh8]
            .map(|a| build_soup_layout(positions.clone(), soup.triangles.clone(), a, TriangleLayout::Blocks));
        let structures = [Accel::Grid, Accel::Kd, Accel::Bvh, Accel::Bvh4, Accel::Bvh8]
            .map(|a| build_soup(positions.clone(), soup.triangles.clone(), a, 3));
        for scene in structures.iter().chain(&blocks) {
            let view = scene.view().unwrap();
            for k in &rays {
                let ray = match k {
                    // Cell-boundary origins come from the scaled grid itself.
                    RayKind::OnCellBoundary(..) => make_ray(k, &scaled, &gview, (0.0, f32::INFINITY)),
                    // Other rays are made in soup space and mapped like the geometry.
                    _ => {
                        let r = make_ray(k, &soup, &gview, (0.0, f32::INFINITY));
                        Ray::new(Vec3::from(map(r.origin.to_array())), r.dir * scale)
                    }
                };
                check::<Watertight>(&view, &ray)?;
            }
        }
    }

    /// Rays lying in a triangle's plane (through two of its vertices, or along an edge):
    /// the tangent case where only a consistent kernel keeps structures in agreement.
    #[test]
    fn rays_in_a_triangles_plane(soup in soup(), picks in prop::collection::vec((any::<prop::sample::Index>(), 0u8..3, -0.5f32..1.5), 24)) {
        let mut scenes: Vec<_> = [Accel::Grid, Accel::Kd, Accel::Bvh, Accel::Bvh4, Accel::Bvh8]
            .into_iter()
            .map(|a| build_soup(soup.positions.clone(), soup.triangles.clone(), a, 3))
            .collect();
        scenes.extend(
            [Accel::Bvh4, Accel::Bvh8]
                .map(|a| build_soup_layout(soup.positions.clone(), soup.triangles.clone(), a, TriangleLayout::Blocks)),
        );
        for (i, edge, s) in &picks {
            let t = soup.triangles[i.index(soup.triangles.len())];
            let v = t.map(|k| Vec3::from(soup.positions[k as usize]));
            let (a, b) = (v[*edge as usize], v[(*edge as usize + 1) % 3]);
            let c = v[(*edge as usize + 2) % 3];
            // From a point on the line through c and a point of edge ab, towards it.
            let target = a + (b - a) * *s;
            let origin = c + (c - target) * 2.0;
            if (target - origin).length_squared() == 0.0 {
                continue;
            }
            let ray = Ray::new(origin, target - origin);
            for scene in &scenes {
                check::<Watertight>(&scene.view().unwrap(), &ray)?;
            }
        }
    }
}

/// A zero-area triangle (three collinear vertices) is written with three equal indices,
/// so no kernel reports a rounding-noise hit on it (the regression proptest found: a ray
/// through such a segment "hit" it at a distance no structure could be conservative
/// about).
#[test]
fn collinear_triangles_never_hit() {
    let p = vec![[-2.0, 0.25, 1.5], [1.0, 0.25, 1.5], [-0.98723924, 0.25, 1.5], [0.0, 0.0, 0.0]];
    let tris = vec![[0, 1, 2], [2, 0, 1], [0, 1, 3]];
    for accel in [Accel::None, Accel::Grid, Accel::Kd, Accel::Bvh, Accel::Bvh4, Accel::Bvh8] {
        let scene = build_soup(p.clone(), tris.clone(), accel, 4);
        let view = scene.view().unwrap();
        assert_eq!(view.triangle_indices(0), [0, 0, 0]);
        assert_eq!(view.triangle_indices(1), [2, 2, 2]);
        assert_eq!(view.triangle_indices(2), [0, 1, 3], "a proper triangle keeps its indices");
        let target = Vec3::new(-0.6614, 0.25, 1.5);
        let origin = Vec3::new(34.575718, 3.2541952, -26.011099);
        for k in 0..50 {
            let o = origin + Vec3::new(0.0, k as f32 * 1e-3, 0.0);
            let ray = Ray::new(o, target - o);
            let hit = trace::<Watertight, _>(&view, &ray, &mut NoProbe, &mut RayCounters::default());
            assert!(hit.is_none_or(|h| h.prim == 2), "{accel:?}: {hit:?}");
        }
    }
}

fn hit_bits(h: Option<(f32, f32, f32)>) -> Option<[u32; 3]> {
    h.map(|(t, u, v)| [t.to_bits(), u.to_bits(), v.to_bits()])
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    /// The watertight test's four-ray form (packets) gives, lane by lane, the bits of the
    /// one-ray test, or hands the lane back (`redo`) where an edge function is exactly
    /// zero. Vertices on a lattice and rays aimed at lattice points (through vertices
    /// and edges) make exact zeros common.
    #[test]
    fn four_ray_watertight_test_matches_the_one_ray_test(
        tri in [point(), point(), point()],
        origin in point(),
        aims in [(0u8..7, point()), (0u8..7, point()), (0u8..7, point()), (0u8..7, point())],
    ) {
        let v = tri.map(Vec3::from);
        let o = Vec3::from(origin);
        // Each lane aims at a vertex, an edge midpoint, the centroid or a lattice point.
        let target = |(kind, p): (u8, [f32; 3])| match kind {
            0..=2 => v[kind as usize],
            3..=5 => (v[kind as usize - 3] + v[(kind as usize - 2) % 3]) * 0.5,
            _ if kind == 6 && p[0] > 0.0 => (v[0] + v[1] + v[2]) / 3.0,
            _ => Vec3::from(p),
        };
        let rays: Vec<Ray> = aims.iter().map(|&a| Ray::new(o, target(a) - o)).filter(|r| r.is_valid()).collect();
        prop_assume!(!rays.is_empty());
        let preps: Vec<_> = rays.iter().map(Watertight::prepare).collect();
        // Four rays' constants in SIMD lanes, from their origins and directions.
        let four_of = |l: [usize; 4]| {
            let axes = |f: fn(&Ray) -> Vec3| -> [Vec4; 3] {
                let p = l.map(|i| f(&rays[i]));
                core::array::from_fn(|a| Vec4::new(p[0][a], p[1][a], p[2][a], p[3][a]))
            };
            Watertight::prepare_rays4(axes(|r| r.origin), axes(|r| r.dir))
        };
        // Lanes must share one axis order: a lane that does not repeats the first ray.
        let lane = |k: usize| {
            let i = k.min(preps.len() - 1);
            if four_of([0, i, i, i]).is_some() { i } else { 0 }
        };
        let lanes = [lane(0), lane(1), lane(2), lane(3)];
        let four = four_of(lanes);
        prop_assert!(four.is_some());
        let r = Watertight::intersect_rays4(&four.unwrap(), &v);
        for (k, &i) in lanes.iter().enumerate() {
            if r.redo & (1 << k) != 0 {
                continue;
            }
            let lane = (r.hit & (1 << k) != 0).then_some((r.t[k], r.u[k], r.v[k]));
            prop_assert_eq!(hit_bits(lane), hit_bits(Watertight::intersect(&preps[i], &v)), "lane {}", k);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    /// The watertight test's four-triangle form (leaf blocks) gives, lane by lane, the
    /// bits of the one-triangle test, or hands the lane back (`redo`) where an edge
    /// function is exactly zero. Triangles on a lattice, rays aimed at their vertices,
    /// edges and centroids.
    #[test]
    fn four_triangle_watertight_test_matches_the_one_triangle_test(
        tris in [[point(), point(), point()], [point(), point(), point()], [point(), point(), point()], [point(), point(), point()]],
        origin in point(),
        aim in (0usize..4, 0u8..7),
    ) {
        let v = tris.map(|t| t.map(Vec3::from));
        let o = Vec3::from(origin);
        let (lane, kind) = aim;
        let t = v[lane];
        let target = match kind {
            0..=2 => t[kind as usize],
            3..=5 => (t[kind as usize - 3] + t[(kind as usize - 2) % 3]) * 0.5,
            _ => (t[0] + t[1] + t[2]) / 3.0,
        };
        let ray = Ray::new(o, target - o);
        prop_assume!(ray.is_valid());
        let prep = Watertight::prepare(&ray);
        let mut block = TriBlock4 { v: [[[0.0; 4]; 3]; 3] };
        for (k, tri) in v.iter().enumerate() {
            for (i, p) in tri.iter().enumerate() {
                for a in 0..3 {
                    block.v[i][a][k] = p[a];
                }
            }
        }
        let r = Watertight::intersect_block4(&prep, &block);
        for (k, tri) in v.iter().enumerate() {
            if r.redo & (1 << k) != 0 {
                continue;
            }
            let got = (r.hit & (1 << k) != 0).then_some((r.t[k], r.u[k], r.v[k]));
            prop_assert_eq!(hit_bits(got), hit_bits(Watertight::intersect(&prep, tri)), "lane {}", k);
        }
    }
}
