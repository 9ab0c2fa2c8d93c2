//! Bricked scenes from the command line: build, render, trace — the same pixels and
//! hits as the flat image — and every kind of damage to a bricked file answered with
//! one line naming the file and the brick or the part of the index.

use std::path::Path;

use crate::common::*;

/// A bricked and a flat image of the same generated building.
fn scenes(d: &Path) {
    let gen = "building:floors=1,rooms=3,seed=2";
    let o = raypipe(d, &["build", "--generate", gen, "--accel", "bvh4", "-o", "flat.rpsi"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o =
        raypipe(d, &["build", "--generate", gen, "--accel", "bvh4", "--bricks", "--brick-size", "16K", "-o", "b.rpsb"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("bricks") && out.contains("stored"), "{out}");
}

#[test]
fn bricked_renders_and_traces_equal_the_flat_images() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    scenes(d);
    for algo in ["cast", "whitted"] {
        let o = raypipe(d, &["render", "flat.rpsi", "--algo", algo, "--size", "96x64", "-o", "f.png"]);
        assert!(o.status.success(), "{}", stderr(&o));
        // A cache of a few bricks: loads, evictions and parked rays.
        let o = raypipe(d, &["render", "b.rpsb", "--algo", algo, "--size", "96x64", "--cache", "200K", "-o", "b.png"]);
        assert!(o.status.success(), "{}", stderr(&o));
        let out = String::from_utf8_lossy(&o.stdout);
        assert!(out.contains("first pixel") && out.contains("hit rate") && out.contains("parked"), "{out}");
        assert_eq!(decode(&d.join("f.png")), decode(&d.join("b.png")), "{algo}");
    }
    // A walkthrough: each frame, then the frame rate and MB loaded as a chart.
    let o = raypipe(d, &["render", "b.rpsb", "--orbit", "3", "--size", "48x32", "--cache", "300K", "-o", "w.png"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("MB loaded") && out.contains("w-walk.png"), "{out}");
    assert_eq!(decode(&d.join("w-0002.png")).0, 48);
    assert!(decode(&d.join("w-walk.png")).0 > 100);
    let o = raypipe(d, &["rays", "flat.rpsi", "--size", "64x48", "-o", "r.npy"]);
    assert!(o.status.success(), "{}", stderr(&o));
    for (query, fields) in [("closest", "t,u,v,prim,ng,ns,material,object"), ("any", "occluded")] {
        for (scene, out) in [("flat.rpsi", "hf.npy"), ("b.rpsb", "hb.npy")] {
            let o =
                raypipe(d, &["trace", scene, "--rays", "r.npy", "--hits", out, "--query", query, "--fields", fields]);
            assert!(o.status.success(), "{}", stderr(&o));
        }
        assert_eq!(std::fs::read(d.join("hf.npy")).unwrap(), std::fs::read(d.join("hb.npy")).unwrap(), "{query}");
    }
}

#[test]
fn stats_bench_and_info_read_bricked_scenes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    scenes(d);
    let o = raypipe(d, &["stats", "b.rpsb", "--size", "64x48", "--cache", "300K"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("top-level nodes") && out.contains("bricks") && out.contains("hit rate"), "{out}");
    let o = raypipe(d, &["bench", "b.rpsb", "--size", "64x48", "--runs", "2", "--packet", "1,16", "--cache", "8M"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("cold Mrays/s") && out.contains("4x4"), "{out}");
    let o = raypipe(d, &["info", "b.rpsb", "--codecs"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("top-level BVH") && out.contains("zstd") && out.contains("decompress MB/s"), "{out}");
}

#[test]
fn damaged_bricked_files_are_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    scenes(d);
    let good = std::fs::read(d.join("b.rpsb")).unwrap();
    let u64_at = |b: &[u8], at: usize| u64::from_le_bytes(b[at..at + 8].try_into().unwrap());
    let index_size = u64_at(&good, 24) as usize;
    let reseal = |b: &mut Vec<u8>| {
        let mut h = b[..index_size].to_vec();
        h[100..104].fill(0);
        let crc = raypipe_core::image::crc32(&h);
        b[100..104].copy_from_slice(&crc.to_le_bytes());
    };
    let render = |name: &str, bytes: &[u8], needle: &str| {
        std::fs::write(d.join(name), bytes).unwrap();
        let o = raypipe(d, &["render", name, "--size", "32x24", "-o", "x.png"]);
        assert_one_line_error(&o, needle);
        assert!(!d.join("x.png").exists(), "{name}: half-written output");
    };
    // A brick whose stored bytes changed.
    let mut b = good.clone();
    let first = u64_at(&good, 128) as usize;
    b[first + 10] ^= 0xff;
    render("crc.rpsb", &b, "fails its checksum");
    // Truncated.
    render("cut.rpsb", &good[..good.len() - 100], "truncated");
    render("cut2.rpsb", &good[..60], "cut2.rpsb");
    // A directory entry pointing outside the file, and one overlapping the index.
    let mut b = good.clone();
    b[128..136].copy_from_slice(&(good.len() as u64 + 64).to_le_bytes());
    reseal(&mut b);
    render("outside.rpsb", &b, "brick 0 lies outside the file");
    let mut b = good.clone();
    b[128..136].copy_from_slice(&64u64.to_le_bytes());
    reseal(&mut b);
    render("overlap.rpsb", &b, "brick 0 lies outside the file or overlaps");
    // The top-level list naming a brick that does not exist.
    let mut b = good.clone();
    let bricks = u32::from_le_bytes(good[16..20].try_into().unwrap()) as usize;
    let nodes = u32::from_le_bytes(good[20..24].try_into().unwrap()) as usize;
    let list = 128 + 64 * bricks + 32 * nodes;
    b[list..list + 4].copy_from_slice(&(bricks as u32 + 5).to_le_bytes());
    reseal(&mut b);
    render("list.rpsb", &b, "top-level tree");
    // An index checksum that does not match.
    let mut b = good.clone();
    b[40] ^= 1;
    render("index.rpsb", &b, "index checksum");
    // A cache that cannot hold the largest brick.
    let o = raypipe(d, &["render", "b.rpsb", "--cache", "1K", "-o", "x.png"]);
    assert_one_line_error(&o, "cannot hold the largest brick");
    // Algorithms that need the whole scene at once.
    let o = raypipe(d, &["render", "b.rpsb", "--algo", "path", "-o", "x.png"]);
    assert_one_line_error(&o, "--algo path");
    // A memory budget too small to build in.
    let o = raypipe(
        d,
        &["build", "--generate", "building:floors=1,rooms=2", "--bricks", "--memory-budget", "1M", "-o", "y.rpsb"],
    );
    assert_one_line_error(&o, "too small to build in");
    assert!(!d.join("y.rpsb").exists());
}

#[test]
fn a_read_error_during_a_frame_names_the_brick() {
    // The file shrinks after it was opened: the bricks past the cut cannot be read.
    use raypipe::input::bricked::BrickedScene;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    scenes(d);
    let path = d.join("b.rpsb");
    let scene = BrickedScene::open(&path).unwrap();
    let last = scene.view().brick_count() - 1;
    let at = scene.view().brick(last).unwrap().offset;
    std::fs::OpenOptions::new().write(true).open(&path).unwrap().set_len(at + 1).unwrap();
    let err = scene.load(last).err().expect("a read error").to_string();
    assert!(err.contains(&format!("brick {last}: cannot read")), "{err}");
    assert!(err.contains("b.rpsb"), "{err}");
}

#[test]
fn a_killed_bricked_build_leaves_no_output_and_its_scratch_is_cleared() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A scratch folder of a process that no longer runs, as a killed build leaves it.
    let host = std::fs::read_to_string("/proc/sys/kernel/hostname").unwrap_or_else(|_| "localhost".into());
    let host = host.trim().replace(['-', '/', '@'], "_");
    let stale = d.join(format!(".b.rpsb.raypipe-999999@{host}-abcdef"));
    std::fs::create_dir(&stale).unwrap();
    std::fs::write(stale.join("all"), b"spill").unwrap();
    let o = raypipe(d, &["build", "--generate", "building:floors=1,rooms=2", "--bricks", "-o", "b.rpsb"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(only_files(d), vec!["b.rpsb".to_string()]);
}
