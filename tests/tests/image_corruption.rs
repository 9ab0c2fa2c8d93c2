//! `SceneView::parse` rejects every kind of corruption with the matching typed error,
//! and no byte pattern makes it (or a kernel on what it accepts) panic.

use proptest::prelude::*;
use raypipe::platform::aligned::AlignedBytes;
use raypipe::render::tracer::trace;
use raypipe::scene::{self, Accel, BuildOptions, TriangleLayout};
use raypipe_core::image::{SectionKind, NULL_INDEX};
use raypipe_core::{NoProbe, Ray, RayCounters, SceneError, SceneView, Vec3, Watertight};
use raypipe_tests::{build_soup_layout, cornell_with, corrupt_image, put_u32, reseal, section_entry};

fn cornell() -> AlignedBytes {
    scene::load_default(&BuildOptions::default()).unwrap().image.into()
}

/// Applies `edit`, reseals the checksum, and returns the parse error.
fn corrupt(edit: impl FnOnce(&mut [u8])) -> SceneError {
    let mut b = cornell();
    edit(&mut b);
    reseal(&mut b);
    SceneView::parse(&b).expect_err("corruption must be rejected")
}

#[test]
fn a_valid_image_parses_and_round_trips_its_counts() {
    let b = cornell();
    let v = SceneView::parse(&b).unwrap();
    assert_eq!(v.triangle_count(), 32);
    assert_eq!(v.bytes().len(), b.len());
    assert!(v.grid().is_some() && v.camera().is_some());
}

#[test]
fn truncated_images_are_rejected() {
    let b = cornell();
    for len in [0, 10, 63, 64, 200, b.len() - 1] {
        let t = AlignedBytes::from_slice(&b[..len]);
        assert!(matches!(SceneView::parse(&t), Err(SceneError::Truncated { .. })), "length {len}");
    }
}

#[test]
fn misaligned_buffers_are_rejected_with_a_clear_error() {
    let b = cornell();
    let mut shifted = AlignedBytes::from_slice(&vec![0u8; b.len() + 4]);
    shifted[4..].copy_from_slice(&b);
    let e = SceneView::parse(&shifted[4..]).unwrap_err();
    assert_eq!(e, SceneError::Misaligned { offset: 4, required: 16 });
    assert!(e.to_string().contains("misaligned"));
}

#[test]
fn header_corruptions() {
    assert_eq!(corrupt(|b| b[0] = b'X'), SceneError::BadMagic);
    assert_eq!(corrupt(|b| put_u32(b, 8, 1)), SceneError::UnsupportedVersion { found: 1, supported: 2 });
    assert_eq!(corrupt(|b| put_u32(b, 8, 3)), SceneError::UnsupportedVersion { found: 3, supported: 2 });
    assert_eq!(corrupt(|b| put_u32(b, 12, 2)), SceneError::UnknownFlags(2));
    assert_eq!(corrupt(|b| put_u32(b, 12, 0x8000_0001)), SceneError::UnknownFlags(0x8000_0000));
    assert_eq!(corrupt(|b| put_u32(b, 16, 9)), SceneError::UnknownAccel(9));
    assert!(matches!(
        corrupt(|b| put_u32(b, 56, 31)),
        SceneError::CountMismatch { section: SectionKind::Triangles, .. }
    ));
    // Bounds that do not contain the vertices.
    assert!(matches!(corrupt(|b| b[32..36].copy_from_slice(&1.0f32.to_le_bytes())), SceneError::OutOfBounds { .. }));
    assert!(matches!(corrupt(|b| b[32..36].copy_from_slice(&f32::NAN.to_le_bytes())), SceneError::NonFinite { .. }));
}

#[test]
fn a_flipped_bit_is_caught_by_the_checksum() {
    let mut b = cornell();
    let last = b.len() - 100;
    b[last] ^= 0x10;
    assert!(matches!(SceneView::parse(&b), Err(SceneError::ChecksumMismatch { .. })));
}

#[test]
fn section_table_corruptions() {
    // Unknown kind, duplicate kind.
    assert_eq!(corrupt(|b| put_u32(b, 64, 99)), SceneError::UnknownSection(99));
    assert!(matches!(
        corrupt(|b| {
            let k = u32::from_le_bytes(b[64..68].try_into().unwrap());
            put_u32(b, 80, k)
        }),
        SceneError::DuplicateSection(_)
    ));
    let (at, e) = section_entry(&cornell(), SectionKind::Triangles);
    assert_eq!(
        corrupt(|b| put_u32(b, at + 4, e.offset + 4)),
        SceneError::SectionMisaligned { section: SectionKind::Triangles, offset: e.offset + 4 }
    );
    assert!(matches!(corrupt(|b| put_u32(b, at + 4, 1 << 20)), SceneError::SectionOutOfBounds { .. }));
    assert!(matches!(corrupt(|b| put_u32(b, at + 4, 0)), SceneError::SectionOutOfBounds { .. }));
    assert!(matches!(corrupt(|b| put_u32(b, at + 8, e.size - 4)), SceneError::SectionSize { .. }));
    // Point TRIANGLES at the POSITIONS bytes: overlap.
    let (_, pos) = section_entry(&cornell(), SectionKind::Positions);
    assert!(matches!(
        corrupt(|b| {
            put_u32(b, at + 4, pos.offset);
        }),
        SceneError::SectionsOverlap(..) | SceneError::IndexOutOfRange { .. }
    ));
    // Remove the grid's cells from the table by renaming them into an unused kind.
    let (cells_at, _) = section_entry(&cornell(), SectionKind::GridCells);
    assert!(matches!(corrupt(|b| put_u32(b, cells_at, SectionKind::Camera as u32)), SceneError::DuplicateSection(_)));
}

#[test]
fn record_corruptions() {
    let base = cornell();
    let (_, tris) = section_entry(&base, SectionKind::Triangles);
    assert_eq!(
        corrupt(|b| put_u32(b, tris.offset as usize + 4, 1000)),
        SceneError::IndexOutOfRange { section: SectionKind::Triangles, record: 0, value: 1000, limit: 64 }
    );
    let (_, pos) = section_entry(&base, SectionKind::Positions);
    assert_eq!(
        corrupt(|b| b[pos.offset as usize + 12..pos.offset as usize + 16].copy_from_slice(&f32::INFINITY.to_le_bytes())),
        SceneError::NonFinite { section: SectionKind::Positions, record: 1 }
    );
    let (_, cells) = section_entry(&base, SectionKind::GridCells);
    let first_full = (0..cells.count as usize)
        .find(|i| {
            let o = cells.offset as usize + 4 * i;
            u32::from_le_bytes(base[o..o + 4].try_into().unwrap()) != NULL_INDEX
        })
        .unwrap();
    assert!(matches!(
        corrupt(|b| put_u32(b, cells.offset as usize + 4 * first_full, 1 << 30)),
        SceneError::IndexOutOfRange { section: SectionKind::GridCells, .. }
    ));
    let (_, lists) = section_entry(&base, SectionKind::PrimLists);
    let last = lists.offset as usize + lists.size as usize - 4;
    assert_eq!(corrupt(|b| put_u32(b, last, 0)), SceneError::UnterminatedList);
    assert!(matches!(
        corrupt(|b| put_u32(b, lists.offset as usize, 77)),
        SceneError::IndexOutOfRange { section: SectionKind::PrimLists, value: 77, .. }
    ));
    let (_, grid) = section_entry(&base, SectionKind::Grid);
    assert_eq!(corrupt(|b| put_u32(b, grid.offset as usize + 48, 0)), SceneError::BadGrid);
    assert_eq!(corrupt(|b| put_u32(b, grid.offset as usize + 60, 5)), SceneError::BadGrid);
    assert_eq!(
        corrupt(|b| b[grid.offset as usize + 32..grid.offset as usize + 36].copy_from_slice(&(-1.0f32).to_le_bytes())),
        SceneError::BadGrid
    );
    let (_, mats) = section_entry(&base, SectionKind::TriangleMaterials);
    assert!(matches!(
        corrupt(|b| put_u32(b, mats.offset as usize, 50)),
        SceneError::IndexOutOfRange { section: SectionKind::TriangleMaterials, .. }
    ));
}

#[test]
fn every_error_prints_one_line() {
    let errors = [
        corrupt(|b| b[0] = 0),
        corrupt(|b| put_u32(b, 8, 7)),
        corrupt(|b| put_u32(b, 64, 99)),
        SceneView::parse(&[]).unwrap_err(),
    ];
    for e in errors {
        let s = e.to_string();
        assert!(!s.is_empty() && !s.contains('\n'), "{s:?}");
    }
}

fn soup_image(accel: Accel, layout: TriangleLayout) -> AlignedBytes {
    build_soup_layout(
        vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        vec![[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]],
        accel,
        layout,
    )
    .image
    .into()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1000, ..ProptestConfig::default() })]

    /// Random edits anywhere (checksum resealed, so the structural checks are what is
    /// tested): parse never panics, and whatever it accepts can be traced without panic.
    #[test]
    fn random_corruption_never_panics(
        edits in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..6),
        cut in any::<Option<prop::sample::Index>>(),
        accel in prop_oneof![Just(Accel::Grid), Just(Accel::Kd), Just(Accel::Bvh), Just(Accel::Bvh4), Just(Accel::Bvh8)],
        layout in prop_oneof![Just(TriangleLayout::Indexed), Just(TriangleLayout::Wald), Just(TriangleLayout::Blocks)],
    ) {
        let mut b = soup_image(accel, layout);
        for (i, v) in &edits {
            let at = i.index(b.len());
            b[at] = *v;
        }
        reseal(&mut b);
        let b = match cut {
            Some(c) => AlignedBytes::from_slice(&b[..c.index(b.len())]),
            None => b,
        };
        if let Ok(view) = SceneView::parse(&b) {
            for k in 0..16 {
                let o = Vec3::new(-1.0 + k as f32 * 0.1, 0.3, -2.0);
                let ray = Ray::new(o, Vec3::new(0.2, 0.1, 1.0));
                let _ = trace::<Watertight, _>(&view, &ray, &mut NoProbe, &mut RayCounters::default());
            }
        }
    }
}

/// A wide BVH's root (nodes of `width` slots: six rows of boxes, then children, then
/// counts) with slot 0's child index back to the root, a leaf range past the list, and a
/// NaN plane: each rejected. Returns the intact image.
fn wide_root_corruptions(accel: Accel, section: SectionKind, width: usize) -> AlignedBytes {
    let img = cornell_with(accel);
    let (_, nodes) = section_entry(&img, section);
    let root = nodes.offset as usize;
    let (child, count) = (root + 24 * width, root + 28 * width);
    let tree = |e: SceneError| matches!(e, SceneError::BadTree { section: s, .. } if s == section);
    assert!(tree(corrupt_image(&img, |b| {
        put_u32(b, child, 0);
        put_u32(b, count, 0)
    })));
    assert!(tree(corrupt_image(&img, |b| {
        put_u32(b, child, 1_000_000);
        put_u32(b, count, 3)
    })));
    assert!(tree(corrupt_image(&img, |b| b[root..root + 4].copy_from_slice(&f32::NAN.to_le_bytes()))));
    img
}

#[test]
fn tree_corruptions() {
    // BVH: node 0 is inner; point its children back at itself, past the end, or make a
    // leaf reach past PRIM_LISTS; put a NaN in a box.
    let bvh = cornell_with(Accel::Bvh);
    let (_, nodes) = section_entry(&bvh, SectionKind::BvhNodes);
    let root = nodes.offset as usize;
    let tree = |e: SceneError| matches!(e, SceneError::BadTree { section: SectionKind::BvhNodes, .. });
    assert!(tree(corrupt_image(&bvh, |b| put_u32(b, root + 12, 0))));
    assert!(tree(corrupt_image(&bvh, |b| put_u32(b, root + 12, nodes.count))));
    assert!(tree(corrupt_image(&bvh, |b| b[root..root + 4].copy_from_slice(&f32::NAN.to_le_bytes()))));
    assert!(tree(corrupt_image(&bvh, |b| {
        put_u32(b, root + 12, 1_000_000);
        put_u32(b, root + 28, 5)
    })));

    let kd = cornell_with(Accel::Kd);
    let (_, nodes) = section_entry(&kd, SectionKind::KdNodes);
    let root = nodes.offset as usize;
    let tree = |e: SceneError| matches!(e, SceneError::BadTree { section: SectionKind::KdNodes, .. });
    let flags = u32::from_le_bytes(kd[root..root + 4].try_into().unwrap());
    assert_ne!(flags & 3, 3, "the Cornell box's kd root is an inner node");
    assert!(tree(corrupt_image(&kd, |b| put_u32(b, root, flags & 3))));
    assert!(tree(corrupt_image(&kd, |b| b[root + 4..root + 8].copy_from_slice(&f32::INFINITY.to_le_bytes()))));
    assert!(tree(corrupt_image(&kd, |b| {
        put_u32(b, root, 3 | (7 << 2));
        put_u32(b, root + 4, 1 << 20)
    })));

    let bvh4 = wide_root_corruptions(Accel::Bvh4, SectionKind::Bvh4Nodes, 4);
    let bvh8 = wide_root_corruptions(Accel::Bvh8, SectionKind::Bvh8Nodes, 8);
    let (_, nodes) = section_entry(&bvh8, SectionKind::Bvh8Nodes);
    let root = nodes.offset as usize;
    let tree = |e: SceneError| matches!(e, SceneError::BadTree { section: SectionKind::Bvh8Nodes, .. });
    // An empty slot (child null) whose box is not inverted.
    assert!(tree(corrupt_image(&bvh8, |b| {
        put_u32(b, root + 192, u32::MAX);
        put_u32(b, root + 224, 0)
    })));
    // Every structure's image is otherwise valid and traceable.
    for img in [&bvh, &kd, &bvh4, &bvh8] {
        assert!(SceneView::parse(img).is_ok());
    }
}

/// TRI_BLOCKS copies the leaf triangles' vertices: a copy that disagrees with POSITIONS,
/// or a block count that does not cover PRIM_LISTS, is rejected (single rays would
/// otherwise see another scene than packets and the hardware model).
#[test]
fn stale_triangle_blocks_are_rejected() {
    for accel in [Accel::Bvh4, Accel::Bvh8] {
        let opts = BuildOptions { accel, triangles: TriangleLayout::Blocks, ..Default::default() };
        let img = scene::load_default(&opts).unwrap().image;
        assert!(SceneView::parse(&img).unwrap().has_tri_blocks());
        let (pos, blocks) = section_entry(&img, SectionKind::TriBlocks);
        let first = blocks.offset as usize;
        // Lane 0's first vertex x moved.
        let stale = corrupt_image(&img, |b| {
            let x = f32::from_le_bytes(b[first..first + 4].try_into().unwrap());
            b[first..first + 4].copy_from_slice(&(x + 1.0).to_le_bytes())
        });
        assert!(matches!(stale, SceneError::StaleCopy { section: SectionKind::TriBlocks, record: 0 }), "{stale}");
        // One block fewer than the lists need (size and count shrunk together).
        let short = corrupt_image(&img, |b| {
            put_u32(b, pos + 8, blocks.size - 144);
            put_u32(b, pos + 12, blocks.count - 1)
        });
        assert!(matches!(short, SceneError::CountMismatch { section: SectionKind::TriBlocks, .. }), "{short}");
    }
}
