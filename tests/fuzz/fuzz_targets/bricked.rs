//! Any bytes as a bricked scene: `BrickedView::parse` returns an error or an index; on an
//! index every brick is checked (checksum, decompression, `check_brick`) and the
//! two-level walk runs on rays made from the input, with the bricks resident from the
//! start or arriving one by one (rays parked and resumed) — no panic, a bounded number
//! of steps, and the same hit either way.
#![no_main]

use libfuzzer_sys::fuzz_target;
use raypipe::input::bricked::codec::decompress;
use raypipe::platform::aligned::AlignedBytes;
use raypipe_core::image::bricked::BrickedView;
use raypipe_core::image::crc32;
use raypipe_core::traverse::two_level::{run_two_level, TopWalk, TwoLevelOutcome};
use raypipe_core::{NoProbe, Ray, SceneView, Vec3, Watertight};

fuzz_target!(|data: &[u8]| {
    let bytes = AlignedBytes::from_slice(data);
    let Ok(index) = BrickedView::parse(&bytes, bytes.len() as u64) else { return };
    // Each brick decoded as a reader would; a bad one stays missing.
    let images: Vec<Option<AlignedBytes>> = index
        .bricks()
        .iter()
        .enumerate()
        .map(|(b, rec)| {
            if rec.image_size > 1 << 20 {
                return None;
            }
            let stored = bytes.get(rec.offset as usize..(rec.offset + rec.stored_size) as usize)?;
            let mut image = AlignedBytes::zeroed(rec.image_size as usize);
            decompress(index.codec(), stored, &mut image).ok()?;
            index.check_brick(b as u32, crc32(stored), &image).ok()?;
            Some(image)
        })
        .collect();
    let views: Vec<Option<SceneView<'_>>> =
        images.iter().map(|i| i.as_ref().and_then(|i| SceneView::parse(i).ok())).collect();
    let h = index.header();
    let (lo, hi) = (Vec3::from(h.bounds_min), Vec3::from(h.bounds_max));
    let centre = (lo + hi) * 0.5;
    let rays = [
        Ray::new(centre + Vec3::new(0.3, 0.7, 5.0) * (hi - lo + Vec3::ONE), Vec3::new(-0.05, -0.1, -1.0)),
        Ray::new(lo - Vec3::ONE, hi - lo + Vec3::ONE),
        Ray::new(centre, Vec3::X),
    ];
    let bound = index.top().node_count() as u64 + 4 * index.brick_count() as u64 + 8;
    for ray in &rays {
        for any in [false, true] {
            // Every valid brick resident at once.
            let mut walk = TopWalk::start(ray, any);
            let all = match run_two_level::<Watertight, _>(&mut walk, &index, ray, &mut |b| views[b as usize], &mut NoProbe) {
                TwoLevelOutcome::Done(h) => Some(h.map(|h| (h.hit.t.to_bits(), h.hit.prim))),
                // A brick that failed its checks: the walk waits for it forever.
                TwoLevelOutcome::Missing(_) => None,
            };
            // Bricks arriving one at a time.
            let mut have = vec![false; views.len()];
            let mut walk = TopWalk::start(ray, any);
            let mut waits = 0u64;
            let one_by_one = loop {
                let mut resident = |b: u32| if have[b as usize] { views[b as usize] } else { None };
                match run_two_level::<Watertight, _>(&mut walk, &index, ray, &mut resident, &mut NoProbe) {
                    TwoLevelOutcome::Done(h) => break Some(h.map(|h| (h.hit.t.to_bits(), h.hit.prim))),
                    TwoLevelOutcome::Missing(b) if views[b as usize].is_some() && !have[b as usize] => {
                        have[b as usize] = true;
                        waits += 1;
                        assert!(waits <= bound, "runaway: {waits} waits");
                    }
                    TwoLevelOutcome::Missing(_) => break None,
                }
            };
            assert_eq!(all, one_by_one);
        }
    }
});
