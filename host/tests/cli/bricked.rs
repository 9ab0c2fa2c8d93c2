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

/// An OBJ with what a streamed reader must get right: two material libraries' worth of
/// `usemtl` switches, one emissive; `o` and `g` names (a name coming back continues no
/// object); quads and a 12-gon; `v//vn`, `v/vt` and `v/vt/vn` corners; negative indices
/// and a `w`.
fn write_rich_obj(d: &Path) {
    use std::fmt::Write;
    let mut obj = String::from("# test scene\nmtllib rich.mtl\n");
    let mut v = 0;
    // A floor of 6×6 quads, two materials in a checker.
    obj += "o floor\n";
    for z in 0..7 {
        for x in 0..7 {
            writeln!(obj, "v {} 0 {}", x as f32 - 3.0, z as f32 - 3.0).unwrap();
        }
    }
    for z in 0..6 {
        for x in 0..6 {
            let i = 1 + z * 7 + x;
            writeln!(obj, "usemtl {}\nf {} {} {} {}", ["red", "grey"][(x + z) % 2], i, i + 7, i + 8, i + 1).unwrap();
        }
    }
    v += 49;
    // A 12-gon wall with normals.
    obj += "g wall\nvn 0 0 1\n";
    for k in 0..12 {
        let a = k as f32 / 12.0 * std::f32::consts::TAU;
        writeln!(obj, "v {} {} -2", 1.5 * a.cos(), 1.5 + 1.5 * a.sin()).unwrap();
    }
    obj += "usemtl grey\nf";
    for k in 0..12 {
        write!(obj, " {}//1", v + 1 + k).unwrap();
    }
    obj += "\n";
    v += 12;
    // Boxes: texture coordinates, negative indices, a w, a name that comes back.
    obj += "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n";
    for (b, name) in ["box", "crate", "box"].iter().enumerate() {
        writeln!(obj, "o {name}\nusemtl {}", ["red", "nosuch", "grey"][b]).unwrap();
        let c = [b as f32 - 1.0, 0.5, 0.5];
        for k in 0..8 {
            let s = |bit: usize| if k & bit != 0 { 0.4 } else { -0.4 };
            writeln!(obj, "v {} {} {} 1", (c[0] + s(1)) * 2.0, (c[1] + s(2)) * 2.0, (c[2] + s(4)) * 2.0).unwrap();
            let _ = v;
        }
        for f in [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]] {
            obj += "f";
            for (k, i) in f.iter().enumerate() {
                write!(obj, " {}/{}", i - 8, k + 1).unwrap();
            }
            obj += "\n";
        }
        v += 8;
    }
    // A lamp above everything.
    obj += "o lamp\nusemtl light\nv -1 4 -1\nv 1 4 -1\nv 1 4 1\nv -1 4 1\nf -1 -2 -3 -4\n";
    write(d, "rich.obj", &obj);
    write(
        d,
        "rich.mtl",
        "newmtl red\nKd 0.8 0.1 0.1\nnewmtl grey\nKd 0.6 0.6 0.6\nKs 0.3 0.3 0.3\nNs 40\nnewmtl light\nKd 0 0 0\nKe 20 20 20\n",
    );
}

#[test]
fn a_streamed_obj_bricks_to_the_flat_images_pixels_and_hits() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_rich_obj(d);
    let o = raypipe(d, &["build", "rich.obj", "--accel", "kd", "-o", "flat.rpsi"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = raypipe(
        d,
        &[
            "build",
            "rich.obj",
            "--accel",
            "kd",
            "--bricks",
            "--brick-size",
            "2K",
            "--memory-budget",
            "80M",
            "-o",
            "b.rpsb",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let (out, warnings) = (String::from_utf8_lossy(&o.stdout).into_owned(), stderr(&o));
    let bricks = out.split(" bricks (").next().and_then(|s| s.rsplit(' ').next()).and_then(|n| n.parse::<u32>().ok());
    assert!(bricks.is_some_and(|n| n >= 4), "{out}");
    // The lamp is strong enough to stand in for a point light, in both (the Whitted
    // frames below show it is the same light).
    let o = raypipe(d, &["info", "flat.rpsi"]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("1 emitter stand-in"));
    assert!(out.lines().any(|l| l.starts_with("lights") && l.contains("standing in")), "{out}");
    assert!(warnings.contains("2 emissive triangles are not area lights"), "{warnings}");
    for algo in ["cast", "whitted"] {
        let o = raypipe(d, &["render", "flat.rpsi", "--algo", algo, "--size", "80x60", "-o", "f.png"]);
        assert!(o.status.success(), "{}", stderr(&o));
        let o = raypipe(d, &["render", "b.rpsb", "--algo", algo, "--size", "80x60", "--cache", "16K", "-o", "b.png"]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert_eq!(decode(&d.join("f.png")), decode(&d.join("b.png")), "{algo}");
    }
    let o = raypipe(d, &["rays", "flat.rpsi", "--size", "64x48", "-o", "r.npy"]);
    assert!(o.status.success(), "{}", stderr(&o));
    for (scene, out) in [("flat.rpsi", "hf.npy"), ("b.rpsb", "hb.npy")] {
        let fields = "t,u,v,prim,ng,ns,material,object";
        let o = raypipe(d, &["trace", scene, "--rays", "r.npy", "--hits", out, "--fields", fields]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let same = std::fs::read(d.join("hf.npy")).unwrap() == std::fs::read(d.join("hb.npy")).unwrap();
    assert!(same, "streamed OBJ: hits differ from the flat image's");
    // A budget that cannot hold the vertex tables and the work.
    let o = raypipe(d, &["build", "rich.obj", "--bricks", "--memory-budget", "2M", "-o", "y.rpsb"]);
    assert_one_line_error(&o, "too small to build in");
    // A face naming a vertex that is not there yet: its line.
    write(d, "bad.obj", "v 0 0 0\nv 1 0 0\nf 1 2 3\nv 0 1 0\n");
    let o = raypipe(d, &["build", "bad.obj", "--bricks", "-o", "y.rpsb"]);
    assert_one_line_error(&o, "line 3: the face names vertex 3, but 2 are defined");
    assert!(!d.join("y.rpsb").exists());
}

#[test]
fn a_full_disk_while_building_is_a_one_line_error_and_leaves_nothing() {
    // A file size limit stands in for a full disk: writes past it fail (EFBIG rather
    // than ENOSPC, through the same error paths).
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let exe = env!("CARGO_BIN_EXE_raypipe");
    let cmd = format!(
        "ulimit -f 256; trap '' XFSZ; exec '{exe}' build --generate building:floors=2,rooms=4 --bricks --brick-size 64K -o b.rpsb"
    );
    let o = std::process::Command::new("sh").arg("-c").arg(cmd).current_dir(d).output().unwrap();
    assert_one_line_error(&o, "cannot write");
    assert!(stderr(&o).contains("spill"), "{}", stderr(&o));
    assert!(only_files(d).is_empty(), "{:?}", only_files(d));
}
