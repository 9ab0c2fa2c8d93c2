//! The command line as a user meets it: defaults that work with no arguments, `--help`
//! everywhere, and bad input answered with one line on stderr, a non-zero exit, no panic
//! and no output file.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn raypipe(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_raypipe")).args(args).current_dir(dir).output().expect("runs")
}

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A failure the way the standards want it: non-zero exit, exactly one line on stderr
/// starting with "error:", containing `needle`, and no panic.
fn assert_one_line_error(o: &Output, needle: &str) {
    let err = stderr(o);
    assert!(!o.status.success(), "expected failure, stderr: {err}");
    assert_eq!(o.status.code(), Some(1), "stderr: {err}");
    let lines: Vec<&str> = err.lines().filter(|l| !l.starts_with("warning:")).collect();
    assert_eq!(lines.len(), 1, "expected one error line, got: {err}");
    assert!(lines[0].starts_with("error: "), "{err}");
    assert!(lines[0].contains(needle), "expected '{needle}' in: {err}");
    assert!(!err.contains("panicked"), "{err}");
}

fn decode(path: &Path) -> (u32, u32, Vec<u8>) {
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = dec.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf)
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn only_files(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    v.sort();
    v
}

#[test]
fn render_without_arguments_draws_the_cornell_box() {
    let dir = tempfile::tempdir().unwrap();
    let o = raypipe(dir.path(), &["render"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (w, h, px) = decode(&dir.path().join("raypipe.png"));
    assert_eq!((w, h), (512, 512));
    // Red wall on the left, green wall on the right, at mid height.
    let at = |x: usize, y: usize| &px[(y * w as usize + x) * 3..(y * w as usize + x) * 3 + 3];
    let left = at(30, 256);
    let right = at(480, 256);
    assert!(left[0] > 2 * left[1] && left[0] > 100, "left wall {left:?}");
    assert!(right[1] > right[0] && right[1] > right[2], "right wall {right:?}");
    // The ceiling light is emissive: bright.
    assert!(at(256, 72).iter().all(|&c| c > 200), "light {:?}", at(256, 72));
}

#[test]
fn every_subcommand_has_help() {
    let dir = tempfile::tempdir().unwrap();
    for sub in ["build", "render", "stats", "bench", "trace", "rays", "simulate", "fixed-point"] {
        let o = raypipe(dir.path(), &[sub, "--help"]);
        assert!(o.status.success());
        let out = String::from_utf8_lossy(&o.stdout);
        assert!(out.contains("Usage: raypipe"), "{sub}: {out}");
    }
    let o = raypipe(dir.path(), &["--help"]);
    let out = String::from_utf8_lossy(&o.stdout);
    for sub in ["build", "render", "stats", "bench", "trace", "rays", "simulate", "fixed-point"] {
        assert!(out.contains(sub));
    }
}

#[test]
fn build_then_render_the_image_equals_rendering_the_obj() {
    let dir = tempfile::tempdir().unwrap();
    let obj = fixtures().join("cornell_box.obj");
    let obj = obj.to_str().unwrap();
    let o = raypipe(dir.path(), &["build", obj, "-o", "box.rpsi", "--grid-min-dim", "5"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("triangles    32"), "{out}");
    assert!(out.contains("grid         5 x 5 x 5"), "{out}");
    let a = raypipe(dir.path(), &["render", "box.rpsi", "-o", "a.png", "--size", "80x60"]);
    let b = raypipe(dir.path(), &["render", obj, "-o", "b.png", "--size", "80x60", "--grid-min-dim", "5"]);
    let c = raypipe(dir.path(), &["render", "-o", "c.png", "--size", "80x60"]);
    assert!(a.status.success() && b.status.success() && c.status.success());
    let (pa, pb, pc) =
        (decode(&dir.path().join("a.png")), decode(&dir.path().join("b.png")), decode(&dir.path().join("c.png")));
    assert_eq!(pa, pb);
    // The built-in default is the same box; a different grid resolution, the same image.
    assert_eq!(pa, pc);
}

#[test]
fn image_is_identical_for_any_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let mut images = Vec::new();
    for t in ["1", "2", "3"] {
        let name = format!("t{t}.png");
        let o = raypipe(dir.path(), &["render", "-o", &name, "--size", "97x61", "--threads", t]);
        assert!(o.status.success());
        images.push(std::fs::read(dir.path().join(name)).unwrap());
    }
    assert!(images.windows(2).all(|w| w[0] == w[1]));
}

#[test]
fn stats_and_bench_report_their_figures() {
    let dir = tempfile::tempdir().unwrap();
    let o = raypipe(dir.path(), &["stats", "--size", "64x64"]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", stderr(&o));
    for key in ["rays that hit", "voxels visited per ray", "triangles tested per ray", "list entries read"] {
        assert!(out.contains(key), "{out}");
    }
    let o = raypipe(dir.path(), &["bench", "--size", "32x32", "--runs", "1"]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.contains("Mrays/s") && out.contains("built-in Cornell box"), "{out}");
}

#[test]
fn missing_and_unreadable_inputs() {
    let dir = tempfile::tempdir().unwrap();
    let o = raypipe(dir.path(), &["render", "nope.obj", "-o", "x.png"]);
    assert_one_line_error(&o, "nope.obj");
    let o = raypipe(dir.path(), &["build", "nope.obj", "-o", "x.rpsi"]);
    assert_one_line_error(&o, "nope.obj");
    let o = raypipe(dir.path(), &["render", "--camera", "nope.camera", "-o", "x.png"]);
    assert_one_line_error(&o, "nope.camera");
    let o = raypipe(dir.path(), &["render", ".", "-o", "x.png"]);
    assert!(!o.status.success());
    assert!(only_files(dir.path()).is_empty(), "{:?}", only_files(dir.path()));
}

#[test]
fn malformed_and_degenerate_geometry() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "bad.obj", "v 1 2\nv 0 0 0\nv 1 1 1\nf 1 2 3\n");
    assert_one_line_error(&raypipe(d, &["build", "bad.obj", "-o", "o.rpsi"]), "bad.obj: malformed OBJ");
    write(d, "face.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    assert_one_line_error(&raypipe(d, &["build", "face.obj", "-o", "o.rpsi"]), "face.obj");
    write(d, "nan.obj", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    assert_one_line_error(&raypipe(d, &["build", "nan.obj", "-o", "o.rpsi"]), "NaN or infinite");
    // A scene of extent 1e20 was "internal error: built an invalid image".
    write(d, "huge.obj", "v 0 0 0\nv 1e20 0 0\nv 0 1e20 0\nf 1 2 3\n");
    for accel in ["grid", "kd", "bvh", "bvh4", "bvh8"] {
        let o = raypipe(d, &["build", "huge.obj", "--accel", accel, "-o", "o.rpsi"]);
        assert_one_line_error(&o, "beyond ±1e18");
    }
    write(d, "inf.obj", "v inf 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    assert_one_line_error(&raypipe(d, &["render", "inf.obj", "-o", "o.png"]), "NaN or infinite");
    write(d, "empty.obj", "# nothing\nv 0 0 0\n");
    assert_one_line_error(&raypipe(d, &["build", "empty.obj", "-o", "o.rpsi"]), "no triangles");
    write(d, "mtl.obj", "mtllib m.mtl\nusemtl a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    write(d, "m.mtl", "newmtl a\nKd 0.5 -1 0.2\n");
    assert_one_line_error(&raypipe(d, &["build", "mtl.obj", "-o", "o.rpsi"]), "material 'a'");
    assert!(!only_files(d).iter().any(|f| f.starts_with("o.")), "{:?}", only_files(d));
    // Degenerate triangles are kept with a warning, not an error.
    write(d, "deg.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\n");
    let o = raypipe(d, &["build", "deg.obj", "-o", "deg.rpsi"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("1 degenerate"), "{}", stderr(&o));
}

#[test]
fn truncated_and_corrupted_images() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let obj = fixtures().join("cornell_box.obj");
    assert!(raypipe(d, &["build", obj.to_str().unwrap(), "-o", "ok.rpsi"]).status.success());
    let bytes = std::fs::read(d.join("ok.rpsi")).unwrap();
    std::fs::write(d.join("short.rpsi"), &bytes[..bytes.len() / 2]).unwrap();
    assert_one_line_error(&raypipe(d, &["render", "short.rpsi", "-o", "o.png"]), "short.rpsi: truncated");
    let mut flipped = bytes.clone();
    flipped[bytes.len() - 70] ^= 1;
    std::fs::write(d.join("flip.rpsi"), &flipped).unwrap();
    assert_one_line_error(&raypipe(d, &["render", "flip.rpsi", "-o", "o.png"]), "corrupted");
    std::fs::write(d.join("junk.rpsi"), "hello world, not a scene\n".repeat(8)).unwrap();
    assert_one_line_error(&raypipe(d, &["stats", "junk.rpsi"]), "bad magic");
    assert!(!d.join("o.png").exists());
}

#[test]
fn impossible_cameras_and_sizes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let o = raypipe(d, &["render", "--size", "0x10", "-o", "o.png"]);
    assert!(!o.status.success() && stderr(&o).contains("zero"), "{}", stderr(&o));
    let o = raypipe(d, &["render", "--eye", "0,0,0", "--look-at", "0,5,0", "-o", "o.png"]);
    assert_one_line_error(&o, "looks along its up vector");
    write(d, "up.camera", "eye 0 0 0\nlook_at 0 0 -1\nup 0 0 2\n");
    assert_one_line_error(&raypipe(d, &["render", "--camera", "up.camera", "-o", "o.png"]), "up.camera");
    write(d, "typo.camera", "eye 0 0 0\nlook_at 0 0 -1\nfvo 40\n");
    assert_one_line_error(&raypipe(d, &["render", "--camera", "typo.camera", "-o", "o.png"]), "typo.camera:3");
    let o = raypipe(d, &["render", "--fov", "180", "-o", "o.png"]);
    assert_one_line_error(&o, "field of view");
    // Sizes from camera files are capped like --size (a 6 GB allocation
    // aborted the process; 100000 x 100000 never finished).
    write(d, "huge.camera", "eye 0 1 3\nlook_at 0 1 0\nsize 4294967295 1\n");
    write(d, "wide.camera", "eye 0 1 3\nlook_at 0 1 0\nsize 100000 100000\n");
    for cam in ["huge.camera", "wide.camera"] {
        for args in [&["render", "-o", "o.png"][..], &["simulate", "-o", "o.png"], &["rays", "--output", "r.npy"]] {
            let mut a = vec![args[0], "--camera", cam];
            a.extend_from_slice(&args[1..]);
            assert_one_line_error(&raypipe(d, &a), "more than 2^28 pixels");
        }
    }
    assert!(!d.join("o.png").exists() && !d.join("r.npy").exists());
}

#[test]
fn failed_writes_leave_no_half_written_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A report into a missing directory left the image behind.
    let o = raypipe(d, &["simulate", "--size", "8x8", "-o", "o.png", "--report", "missing/r.json"]);
    assert_one_line_error(&o, "does not exist");
    assert!(!d.join("o.png").exists(), "no image without its report");
    let o = raypipe(d, &["render", "-o", "missing/dir/o.png", "--size", "8x8"]);
    assert_one_line_error(&o, "does not exist");
    // An existing output survives a failed run untouched.
    std::fs::write(d.join("keep.png"), b"old").unwrap();
    let o = raypipe(d, &["render", "nope.obj", "-o", "keep.png"]);
    assert!(!o.status.success());
    assert_eq!(std::fs::read(d.join("keep.png")).unwrap(), b"old");
    assert_eq!(only_files(d), vec!["keep.png".to_string()]);
}

#[test]
fn gzipped_obj_renders_like_the_plain_file() {
    use std::io::Write;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let text = std::fs::read(fixtures().join("tetra.obj")).unwrap();
    std::fs::copy(fixtures().join("tetra.mtl"), d.join("tetra.mtl")).unwrap();
    std::fs::write(d.join("tetra.obj"), &text).unwrap();
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    gz.write_all(&text).unwrap();
    std::fs::write(d.join("packed.obj.gz"), gz.finish().unwrap()).unwrap();
    let a = raypipe(d, &["render", "tetra.obj", "-o", "a.png", "--size", "40x30"]);
    let b = raypipe(d, &["render", "packed.obj.gz", "-o", "b.png", "--size", "40x30"]);
    assert!(a.status.success() && b.status.success(), "{} {}", stderr(&a), stderr(&b));
    assert_eq!(decode(&d.join("a.png")), decode(&d.join("b.png")));
    std::fs::write(d.join("broken.obj.gz"), b"\x1f\x8b\x08\x00garbage").unwrap();
    assert_one_line_error(&raypipe(d, &["build", "broken.obj.gz", "-o", "x.rpsi"]), "broken.obj.gz");
}

/// Writes a little-endian float32 .npy array of the given shape.
fn write_npy(path: &Path, shape: &[usize], data: &[f32], descr: &str) {
    let dims: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
    let shape = if dims.len() == 1 { format!("({},)", dims[0]) } else { format!("({})", dims.join(", ")) };
    let mut header = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend_from_slice(&(header.len() as u16).to_le_bytes());
    bytes.extend_from_slice(header.as_bytes());
    for v in data {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    std::fs::write(path, bytes).unwrap();
}

/// Reads the structured hits array back: (t, u, v, prim) per ray.
fn read_hits(path: &Path) -> Vec<(f32, f32, f32, i32)> {
    let bytes = std::fs::read(path).unwrap();
    let hl = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let header = String::from_utf8_lossy(&bytes[10..10 + hl]).into_owned();
    assert!(header.contains("('prim', '<i4')"), "{header}");
    bytes[10 + hl..]
        .chunks_exact(16)
        .map(|c| {
            let f = |i: usize| f32::from_le_bytes([c[i], c[i + 1], c[i + 2], c[i + 3]]);
            (f(0), f(4), f(8), i32::from_le_bytes([c[12], c[13], c[14], c[15]]))
        })
        .collect()
}

#[test]
fn trace_a_ray_batch_with_every_structure_and_packet_size() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let obj = fixtures().join("cornell_box.obj");
    let obj = obj.to_str().unwrap();
    // Rays of a view in 8×8 blocks, plus the scene's triangles.
    let o = raypipe(d, &["rays", "-o", "rays.npy", "--size", "32x24", "--block", "8", "--triangles", "tris.npy"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut reference = None;
    for accel in ["grid", "kd", "bvh", "bvh4"] {
        for packet in ["1", "4", "16", "64"] {
            let o = raypipe(
                d,
                &["trace", obj, "--rays", "rays.npy", "--hits", "hits.npy", "--accel", accel, "--packet", packet],
            );
            assert!(o.status.success(), "{accel} {packet}: {}", stderr(&o));
            let hits = read_hits(&d.join("hits.npy"));
            assert_eq!(hits.len(), 32 * 24);
            let hit_count = hits.iter().filter(|h| h.3 >= 0).count();
            assert!(hit_count > 500, "most rays of the box view hit: {hit_count}");
            assert!(hits.iter().all(|h| h.3 < 32), "ids are input triangle ids");
            match &reference {
                None => reference = Some(hits),
                Some(r) => assert!(
                    r.iter().zip(&hits).all(|(a, b)| a.0.to_bits() == b.0.to_bits() && a.3 == b.3),
                    "{accel} with packets of {packet} differs"
                ),
            }
        }
    }
    // Images with leaf triangle blocks (the wide BVHs' single rays read them) give the
    // same hits; a structure without wide leaves keeps indexed triangles and says so.
    let reference = reference.unwrap();
    for accel in ["bvh4", "bvh8"] {
        let o = raypipe(d, &["build", obj, "--accel", accel, "--triangles", "blocks", "-o", "blocks.rpsi"]);
        assert!(o.status.success(), "{}", stderr(&o));
        let o = raypipe(d, &["trace", "blocks.rpsi", "--rays", "rays.npy", "--hits", "hits.npy", "--packet", "1"]);
        assert!(String::from_utf8_lossy(&o.stdout).contains("leaf blocks"), "{}", stderr(&o));
        let hits = read_hits(&d.join("hits.npy"));
        assert!(
            reference.iter().zip(&hits).all(|(a, b)| a.0.to_bits() == b.0.to_bits() && a.3 == b.3),
            "{accel} blocks"
        );
    }
    let o = raypipe(d, &["build", obj, "--accel", "grid", "--triangles", "blocks", "-o", "grid.rpsi"]);
    assert!(o.status.success() && stderr(&o).contains("--triangles blocks applies to"), "{}", stderr(&o));
    // A ray above the blocks, straight down +z (N × 6 form), hits the back wall at z = 559.2.
    write_npy(&d.join("one.npy"), &[1, 6], &[100.0, 450.0, -800.0, 0.0, 0.0, 1.0], "<f4");
    assert!(raypipe(d, &["trace", obj, "--rays", "one.npy", "--hits", "one_hits.npy"]).status.success());
    let h = read_hits(&d.join("one_hits.npy"));
    assert!((h[0].0 - 1359.2).abs() < 1e-3, "{h:?}");
}

/// Ray queries: float64 input, rows that are no rays returned as misses
/// and counted, any-hit queries, optional fields, and the warning for incoherent packets.
#[test]
fn ray_queries_fields_and_invalid_rays() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let obj = fixtures().join("cornell_box.obj");
    let obj = obj.to_str().unwrap();
    // Down the box from above the blocks; a NaN row; a zero direction; an empty interval;
    // the same ray with an interval too short to reach anything.
    let good = [100.0, 450.0, -800.0, 0.0, 0.0, 1.0, 0.0, f32::INFINITY];
    let mut rows = good.to_vec();
    rows.extend([f32::NAN, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0]);
    rows.extend([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]);
    rows.extend([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 5.0, 1.0]);
    rows.extend([100.0, 450.0, -800.0, 0.0, 0.0, 1.0, 0.0, 10.0]);
    // As float64.
    let mut bytes = Vec::new();
    let mut header = "{'descr': '<f8', 'fortran_order': False, 'shape': (5, 8), }".to_string();
    while !(10 + header.len() + 1).is_multiple_of(64) {
        header.push(' ');
    }
    header.push('\n');
    bytes.extend_from_slice(b"\x93NUMPY\x01\x00");
    bytes.extend_from_slice(&(header.len() as u16).to_le_bytes());
    bytes.extend_from_slice(header.as_bytes());
    for v in &rows {
        bytes.extend_from_slice(&(*v as f64).to_le_bytes());
    }
    std::fs::write(d.join("rays.npy"), bytes).unwrap();
    let o = raypipe(d, &["trace", obj, "--rays", "rays.npy", "--hits", "h.npy"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("3 rows are not rays"), "{}", stderr(&o));
    let h = read_hits(&d.join("h.npy"));
    assert_eq!(h.len(), 5);
    assert!((h[0].0 - 1359.2).abs() < 1e-3 && h[0].3 >= 0, "{h:?}");
    assert!(h[1..].iter().all(|r| r.3 == -1 && r.0 == f32::INFINITY), "{h:?}");

    let o = raypipe(d, &["trace", obj, "--rays", "rays.npy", "--hits", "any.npy", "--query", "any"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let any = std::fs::read(d.join("any.npy")).unwrap();
    let hl = u16::from_le_bytes([any[8], any[9]]) as usize;
    assert!(String::from_utf8_lossy(&any[10..10 + hl]).contains("('occluded', 'u1')"));
    assert_eq!(&any[10 + hl..], &[1, 0, 0, 0, 0], "only the first ray is blocked");

    let o = raypipe(d, &["trace", obj, "--rays", "rays.npy", "--hits", "f.npy", "--fields", "prim,ng,ns,material"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let f = std::fs::read(d.join("f.npy")).unwrap();
    let hl = u16::from_le_bytes([f[8], f[9]]) as usize;
    let header = String::from_utf8_lossy(&f[10..10 + hl]).into_owned();
    assert!(header.contains("('ng', '<f4', (3,))") && header.contains("('material', '<i4')"), "{header}");
    let rec = &f[10 + hl..10 + hl + 32];
    let fl = |i: usize| f32::from_le_bytes(rec[i..i + 4].try_into().unwrap());
    // The back wall faces the ray: both normals along z, the shading one towards -z.
    assert!(fl(12).abs() > 0.99 && (fl(24) + 1.0).abs() < 1e-3, "{rec:?}");
    assert!(i32::from_le_bytes(rec[28..32].try_into().unwrap()) >= 0);
    assert_eq!(f.len() - 10 - hl, 5 * 32);

    // Object ids: the OBJ's `o` names in order (floor, light, ceiling, back_wall, …).
    let o = raypipe(d, &["trace", obj, "--rays", "rays.npy", "--hits", "o.npy", "--fields", "object"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let f = std::fs::read(d.join("o.npy")).unwrap();
    let hl = u16::from_le_bytes([f[8], f[9]]) as usize;
    assert!(String::from_utf8_lossy(&f[10..10 + hl]).contains("('object', '<i4')"));
    let ids: Vec<i32> = f[10 + hl..].chunks_exact(4).map(|c| i32::from_le_bytes(c.try_into().unwrap())).collect();
    assert_eq!(ids, [3, -1, -1, -1, -1], "the back wall is the fourth object");

    let o = raypipe(d, &["trace", obj, "--rays", "rays.npy", "--hits", "x.npy", "--fields", "t,colour"]);
    assert_one_line_error(&o, "unknown field 'colour'");
    let o = raypipe(d, &["trace", obj, "--rays", "rays.npy", "--hits", "x.npy", "--query", "any", "--fields", "t"]);
    assert_one_line_error(&o, "only 'occluded'");

    // Incoherent packets: random directions, traced as 4×4 packets, are warned about.
    let mut g = 12345u32;
    let mut next = || {
        g ^= g << 13;
        g ^= g >> 17;
        g ^= g << 5;
        g as f32 / u32::MAX as f32 * 2.0 - 1.0
    };
    let scattered: Vec<f32> = (0..64).flat_map(|_| [250.0, 250.0, 250.0, next(), next(), next()]).collect();
    write_npy(&d.join("scattered.npy"), &[64, 6], &scattered, "<f4");
    let o = raypipe(d, &["trace", obj, "--rays", "scattered.npy", "--hits", "s.npy", "--packet", "16"]);
    assert!(o.status.success() && stderr(&o).contains("incoherent"), "{}", stderr(&o));
    let o = raypipe(d, &["trace", obj, "--rays", "scattered.npy", "--hits", "s.npy"]);
    assert!(o.status.success() && !stderr(&o).contains("incoherent"), "{}", stderr(&o));
}

#[test]
fn malformed_ray_arrays() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let obj = fixtures().join("tetra.obj");
    let obj = obj.to_str().unwrap();
    let run = |name: &str| raypipe(d, &["trace", obj, "--rays", name, "--hits", "h.npy"]);
    write_npy(&d.join("cols.npy"), &[2, 5], &[0.0; 10], "<f4");
    assert_one_line_error(&run("cols.npy"), "5 columns");
    std::fs::write(d.join("i4.npy"), {
        let mut b = std::fs::read(d.join("cols.npy")).unwrap();
        let at = b.windows(3).position(|w| w == b"<f4").unwrap();
        b[at..at + 3].copy_from_slice(b"<i4");
        b
    })
    .unwrap();
    assert_one_line_error(&run("i4.npy"), "float64");
    std::fs::write(d.join("junk.npy"), b"not numpy").unwrap();
    assert_one_line_error(&run("junk.npy"), "junk.npy");
    assert_one_line_error(&run("missing.npy"), "missing.npy");
    assert!(!d.join("h.npy").exists());
}

#[test]
fn simulate_without_arguments_matches_render_and_reports() {
    let dir = tempfile::tempdir().unwrap();
    let o = raypipe(dir.path(), &["simulate", "--report", "report.json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    for needle in ["cycles", "frames/s", "traversal0", "intersection0", "memory", "distinct bytes"] {
        assert!(out.contains(needle), "{needle} missing: {out}");
    }
    let o = raypipe(dir.path(), &["render"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(decode(&dir.path().join("raypipe-sim.png")), decode(&dir.path().join("raypipe.png")));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("report.json")).unwrap()).unwrap();
    assert_eq!(json["schema"], "raypipe-hw-report/2");
    // Run identity: the scene, its image's hash, the structure and the configuration.
    assert_eq!(json["run"]["scene"], "built-in Cornell box");
    assert_eq!(json["run"]["scene_hash"].as_str().unwrap().len(), 16);
    assert!(!json["run"]["structure"].as_str().unwrap().is_empty());
    assert!(json["config"]["memory"]["model"].is_string());
    assert!(!json["bottleneck"].as_str().unwrap().is_empty());
    for u in json["units"].as_array().unwrap() {
        let sum: u64 = u["stall_reasons"].as_object().unwrap().values().map(|v| v.as_u64().unwrap()).sum();
        assert_eq!(sum, u["stall_cycles"].as_u64().unwrap(), "{}", u["name"]);
    }
    assert!(json["cycles"].as_u64().unwrap() > 0);
    assert_eq!(json["conservation"]["rays_issued"], json["conservation"]["rays_retired"]);
    assert_eq!(json["conservation"]["bytes_requested"], json["conservation"]["bytes_delivered"]);
    for key in ["units", "fifos", "caches"] {
        assert!(!json[key].as_array().unwrap().is_empty(), "{key}");
    }
    assert!(json["memory"]["bytes"]["nodes"].as_u64().unwrap() > 0);
}

#[test]
fn simulate_presets_configs_and_overrides() {
    let dir = tempfile::tempdir().unwrap();
    let tetra = fixtures().join("tetra.obj");
    let tetra = tetra.to_str().unwrap();
    let o = raypipe(dir.path(), &["render", tetra, "--accel", "bvh", "--size", "40x30", "-o", "r.png"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let cfg = write(dir.path(), "chip.toml", "packet_size = 4\n[traversal]\nunits = 2\nthreads = 3\n");
    let cfg = cfg.to_str().unwrap();
    for extra in [
        &["--preset", "saarcor"][..],
        &["--preset", "minimal", "--set", "memory.latency=3"][..],
        &["--config", cfg, "--set", "cache.nodes.size_bytes=0"][..],
    ] {
        let mut args = vec!["simulate", tetra, "--accel", "bvh", "--size", "40x30", "-o", "s.png"];
        args.extend_from_slice(extra);
        let o = raypipe(dir.path(), &args);
        assert!(o.status.success(), "{extra:?}: {}", stderr(&o));
        assert_eq!(decode(&dir.path().join("s.png")), decode(&dir.path().join("r.png")), "{extra:?}");
    }
}

#[test]
fn impossible_hardware_configurations() {
    let dir = tempfile::tempdir().unwrap();
    let typo = write(dir.path(), "typo.toml", "[traversal]\nthreds = 4\n");
    let zero = write(dir.path(), "zero.toml", "[fifo]\nleaves = 0\n");
    let broken = write(dir.path(), "broken.toml", "[traversal\n");
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["--config", typo.to_str().unwrap()], "threds"),
        (vec!["--config", zero.to_str().unwrap()], "fifo.leaves"),
        (vec!["--config", broken.to_str().unwrap()], "broken.toml"),
        (vec!["--config", "missing.toml"], "missing.toml"),
        (vec!["--preset", "nosuch"], "unknown preset"),
        (vec!["--set", "traversal.thread=2"], "no such parameter"),
        (vec!["--set", "traversal.threads"], "key=value"),
        (vec!["--set", "cache.triangles.size_bytes=8"], "smaller than one"),
        (vec!["--set", "packet_size=8"], "packet_size"),
        (vec!["--set", "traversal.threads=-1"], "traversal.threads"),
        (vec!["--set", "datapath=\"q3.3\""], "datapath"),
        // The default scene has a grid: no fixed-point box test for it.
        (vec!["--set", "datapath=\"q16.16\""], "for BVHs"),
        (vec!["--set", "datapath=\"q16.16\"", "--accel", "bvh", "--intersector", "wald"], "own triangle test"),
    ];
    for (args, needle) in cases {
        let mut all = vec!["simulate", "-o", "x.png", "--report", "x.json"];
        all.extend_from_slice(&args);
        let o = raypipe(dir.path(), &all);
        assert_one_line_error(&o, needle);
        assert!(!dir.path().join("x.png").exists() && !dir.path().join("x.json").exists(), "{args:?}");
    }
}

#[test]
fn algorithms_render_simulate_and_report_their_costs() {
    let dir = tempfile::tempdir().unwrap();
    let scene = fixtures().join("whitted.obj");
    let scene = scene.to_str().unwrap();
    for algo in ["cast", "shadow", "whitted", "path"] {
        let common = ["--algo", algo, "--size", "48x36", "--samples", "2"];
        let mut render = vec!["render", scene, "-o", "r.png"];
        render.extend_from_slice(&common);
        let o = raypipe(dir.path(), &render);
        assert!(o.status.success(), "{algo}: {}", stderr(&o));
        let mut sim = vec!["simulate", scene, "-o", "s.png", "--report", "s.json", "--preset", "saarcor"];
        sim.extend_from_slice(&common);
        let o = raypipe(dir.path(), &sim);
        assert!(o.status.success(), "{algo}: {}", stderr(&o));
        assert_eq!(decode(&dir.path().join("r.png")), decode(&dir.path().join("s.png")), "{algo}: model = host");
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.path().join("s.json")).unwrap()).unwrap();
        assert!(json["rays_by_kind"]["shadow"].as_u64().unwrap() > 0 || algo == "cast", "{algo}");
        let mut stats = vec!["stats", scene];
        stats.extend_from_slice(&common);
        let o = raypipe(dir.path(), &stats);
        assert!(o.status.success(), "{algo}: {}", stderr(&o));
        let out = String::from_utf8_lossy(&o.stdout);
        if algo != "cast" {
            assert!(out.contains("rays per pixel") && out.contains("relative to ray casting"), "{algo}: {out}");
        }
        if algo == "shadow" {
            assert!(out.contains("rasterization and ray casting disagree at"), "{out}");
        }
    }
    for (args, needle) in [
        (vec!["render", "--algo", "path", "--samples", "0"], "--samples"),
        (vec!["render", "--algo", "whitted", "--max-depth", "100"], "--max-depth"),
        (vec!["simulate", "--algo", "path", "--bounces", "99"], "--bounces"),
    ] {
        assert_one_line_error(&raypipe(dir.path(), &args), needle);
    }
}

#[test]
fn point_lights_from_the_command_line_and_enclosed_lights_are_warned_about() {
    let dir = tempfile::tempdir().unwrap();
    let scene = fixtures().join("whitted.obj");
    let scene = scene.to_str().unwrap();
    let o = raypipe(dir.path(), &["render", scene, "--algo", "whitted", "--size", "40x30", "-o", "a.png"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = raypipe(
        dir.path(),
        &["render", scene, "--algo", "whitted", "--size", "40x30", "-o", "b.png", "--light=-1.5,2.5,1.5,0.5,0.5,0.6"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert_ne!(decode(&dir.path().join("a.png")), decode(&dir.path().join("b.png")), "the light moved");
    // A light inside a closed cube lights nothing outside it: a warning, not an error.
    let mut obj = String::new();
    for v in ["-1 -1 -1", "1 -1 -1", "1 1 -1", "-1 1 -1", "-1 -1 1", "1 -1 1", "1 1 1", "-1 1 1"] {
        obj += &format!("v {v}\n");
    }
    for f in
        ["1 3 2", "1 4 3", "5 6 7", "5 7 8", "1 2 6", "1 6 5", "4 8 7", "4 7 3", "1 5 8", "1 8 4", "2 3 7", "2 7 6"]
    {
        obj += &format!("f {f}\n");
    }
    let cube = write(dir.path(), "cube.obj", &obj);
    let o = raypipe(dir.path(), &["render", cube.to_str().unwrap(), "--light", "0,0,0", "-o", "c.png"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("inside closed geometry"), "{}", stderr(&o));
    let o = raypipe(dir.path(), &["render", cube.to_str().unwrap(), "--light", "0,3,0", "-o", "c.png"]);
    assert!(!stderr(&o).contains("inside closed geometry"), "{}", stderr(&o));
    let o = raypipe(dir.path(), &["render", "--light", "0,nan,0", "-o", "c.png"]);
    assert!(!o.status.success());
}

/// A quad whose diffuse texture is a 2×2 checker (PNG): each quarter of the picture
/// takes its texel's colour; a missing texture or an unsupported format is one warning
/// and the material's own colour.
#[test]
fn diffuse_textures_are_sampled_and_bad_ones_fall_back_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let texels: [[u8; 3]; 4] = [[230, 20, 20], [20, 230, 20], [20, 20, 230], [230, 230, 230]];
    let file = std::fs::File::create(dir.path().join("checker.png")).unwrap();
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), 2, 2);
    enc.set_color(png::ColorType::Rgb);
    enc.write_header().unwrap().write_image_data(texels.as_flattened()).unwrap();
    let obj = "mtllib quad.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl tex\nf 1/1 2/2 3/3 4/4\n";
    write(dir.path(), "quad.obj", obj);
    let camera = "eye 0 0 2.2\nlook_at 0 0 0\nup 0 1 0\nfov 60\nsize 40 40\nbackground 0 0 0\n";
    write(dir.path(), "quad.camera", camera);
    let render = |mtl: &str| {
        write(dir.path(), "quad.mtl", mtl);
        let o = raypipe(dir.path(), &["render", "quad.obj", "--light", "0,0,3", "-o", "q.png"]);
        assert!(o.status.success(), "{}", stderr(&o));
        (decode(&dir.path().join("q.png")).2, stderr(&o))
    };
    let (px, err) = render("newmtl tex\nKd 1 1 1\nmap_Kd -clamp on checker.png\n");
    assert!(!err.contains("warning"), "{err}");
    let at = |x: usize, y: usize| &px[(y * 40 + x) * 3..(y * 40 + x) * 3 + 3];
    // Top-left quarter: the texture's top-left texel (red); bottom-right: white.
    let (tl, tr, bl, br) = (at(12, 12), at(27, 12), at(12, 27), at(27, 27));
    assert!(tl[0] > 2 * tl[1] && tl[0] > 2 * tl[2], "top left {tl:?}");
    assert!(tr[1] > 2 * tr[0] && tr[1] > 2 * tr[2], "top right {tr:?}");
    assert!(bl[2] > 2 * bl[0] && bl[2] > 2 * bl[1], "bottom left {bl:?}");
    assert!(br[0] > 100 && br[1] > 100 && br[2] > 100, "bottom right {br:?}");
    for (mtl, needle) in [
        ("newmtl tex\nKd 0.5 0.5 0.5\nmap_Kd missing.png\n", "missing.png"),
        ("newmtl tex\nKd 0.5 0.5 0.5\nmap_Kd checker.bmp\n", "unsupported image format"),
    ] {
        if needle.contains("unsupported") {
            std::fs::copy(dir.path().join("checker.png"), dir.path().join("checker.bmp")).unwrap();
        }
        let (px, err) = render(mtl);
        assert!(err.contains("warning") && err.contains(needle), "{err}");
        let c = &px[(20 * 40 + 20) * 3..(20 * 40 + 20) * 3 + 3];
        assert!(c[0] == c[1] && c[1] == c[2] && c[0] > 0, "grey diffuse colour: {c:?}");
    }
}

/// `raypipe fixed-point` on the built-in Cornell box: Q16.16 and Q12.12 agree with f32 on
/// (nearly) every ray; a format the scene does not fit is flagged and disagrees; bad
/// choices are one-line errors. And `simulate` with a fixed-point datapath renders.
#[test]
fn fixed_point_report_and_simulation() {
    let dir = tempfile::tempdir().unwrap();
    let o = raypipe(dir.path(), &["fixed-point", "--size", "48x48", "--datapath", "q16.16,q12.12,q8.16"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    let row = |kind: &str, d: &str| -> Vec<String> {
        let line = out
            .lines()
            .find(|l| l.contains(kind) && l.contains(&format!(" {d} ")))
            .unwrap_or_else(|| panic!("{d} {kind}: {out}"));
        line.split_whitespace().map(str::to_string).collect()
    };
    for d in ["q16.16", "q12.12"] {
        for kind in ["primary", "bounce"] {
            let r = row(kind, d);
            // "built-in Cornell box" is three words: then kind, datapath, fits, rays, agree%.
            assert_eq!(r[5], "yes", "{r:?}");
            let rays: u64 = r[6].parse().unwrap();
            let agree: f64 = r[7].parse().unwrap();
            assert!(rays > 1000 && agree >= 99.9, "{d} {kind}: {r:?}");
        }
    }
    let r = row("primary", "q8.16");
    assert_eq!(r[5], "NO", "{r:?}");
    assert!(r[7].parse::<f64>().unwrap() < 50.0, "{r:?}");
    assert!(stderr(&o).contains("do not fit q8.16"), "{}", stderr(&o));
    for (args, needle) in [
        (vec!["--datapath", "f32"], "fixed-point formats"),
        (vec!["--datapath", "q3.3"], "q3.3"),
        (vec!["--accel", "grid"], "for BVHs"),
        (vec!["--accel", "kd"], "for BVHs"),
    ] {
        let mut all = vec!["fixed-point", "--size", "8x8"];
        all.extend_from_slice(&args);
        let o = raypipe(dir.path(), &all);
        assert!(!o.status.success() && stderr(&o).contains(needle), "{args:?}: {}", stderr(&o));
        assert!(!stderr(&o).contains("panicked"));
    }
    let o = raypipe(
        dir.path(),
        &[
            "simulate",
            "--accel",
            "bvh4",
            "--size",
            "40x30",
            "--set",
            "datapath=\"q16.16\"",
            "-o",
            "s.png",
            "--report",
            "s.json",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let report = std::fs::read_to_string(dir.path().join("s.json")).unwrap();
    assert!(report.contains("\"datapath\": \"q16.16\"") && report.contains("fixed-watertight q16.16"), "{report}");
}

#[test]
fn stream_machine_tables_report_charts_and_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let o = raypipe(
        dir.path(),
        &["stream", "--size", "64x48", "--algo", "whitted", "--unroll", "traverse=4,intersect=2", "--charts", "charts"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    for needle in ["Table 2", "Table 3", "intersect", "grid_cells", "compute bound", "equals raypipe render's"] {
        assert!(
            out.contains(needle) || needle == "compute bound" && out.contains("bandwidth bound"),
            "{needle}: {out}"
        );
    }
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("raypipe-stream.json")).unwrap()).unwrap();
    assert_eq!(report["width"], 64);
    assert!(report["table2"]["traverse_passes"].as_u64().unwrap() > 0);
    assert!(report["passes"].as_array().unwrap().len() as u64 == report["table2"]["total_passes"].as_u64().unwrap());
    for name in [
        "fig7_instructions_by_kernel",
        "fig8_words_by_data_type",
        "fig9_texture_cache_bandwidth",
        "active_rays_per_pass",
    ] {
        for ext in ["svg", "png"] {
            let p = dir.path().join("charts").join(format!("{name}.{ext}"));
            assert!(std::fs::metadata(&p).map(|m| m.len() > 500).unwrap_or(false), "{}", p.display());
        }
    }
    // A cost file replaces raypipe's counts.
    std::fs::write(dir.path().join("paper.toml"), "[intersect]\ninstructions = 41\nm = 11\n").unwrap();
    let o = raypipe(
        dir.path(),
        &["stream", "--size", "32x32", "--costs", "paper.toml", "--no-charts", "--arch", "branching"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    let line = out.lines().find(|l| l.starts_with("intersect ")).unwrap();
    assert!(line.split_whitespace().nth(1) == Some("41") && line.contains("11.00"), "{line}");
    std::fs::write(dir.path().join("bad.toml"), "[intersekt]\ninstructions = 1\n").unwrap();
    for (args, needle) in [
        (vec!["--oracle", "sometimes"], "oracle"),
        (vec!["--oracle", "delany:2"], "fraction"),
        (vec!["--unroll", "traverse=0"], "traverse"),
        (vec!["--cache", "64K,3,50"], "cache"),
        (vec!["--machine", "1e9"], "machine"),
        (vec!["--costs", "bad.toml"], "intersekt"),
        (vec!["--costs", "missing.toml"], "missing.toml"),
        (vec!["--arch", "branching", "--suppress"], "multipass"),
        (vec!["--accel", "bvh"], "uniform grid"),
    ] {
        let mut all = vec!["stream", "--size", "16x16", "--no-charts"];
        all.extend(args.iter());
        let o = raypipe(dir.path(), &all);
        let err = stderr(&o);
        assert!(!o.status.success() && err.contains(needle) && !err.contains("panicked"), "{args:?}: {err}");
    }
}

#[test]
fn generated_scenes_build_with_their_views() {
    let dir = tempfile::tempdir().unwrap();
    for (spec, views) in
        [("building:floors=1,rooms=2", ["outside", "inside"]), ("forest:trees=4,leaves=20", ["top", "inside"])]
    {
        for view in views {
            let out = format!("{view}.rpsi");
            let o = raypipe(dir.path(), &["build", "--generate", spec, "--view", view, "-o", &out]);
            assert!(o.status.success(), "{spec} {view}: {}", stderr(&o));
            let o = raypipe(dir.path(), &["stream", &out, "--size", "32x32", "--no-charts"]);
            assert!(o.status.success(), "{spec} {view}: {}", stderr(&o));
        }
    }
    // The same parameters give the same image bytes.
    let a = raypipe(dir.path(), &["build", "--generate", "forest:trees=3,leaves=10,seed=7", "-o", "a.rpsi"]);
    let b = raypipe(dir.path(), &["build", "--generate", "forest:trees=3,leaves=10,seed=7", "-o", "b.rpsi"]);
    assert!(a.status.success() && b.status.success());
    assert_eq!(std::fs::read(dir.path().join("a.rpsi")).unwrap(), std::fs::read(dir.path().join("b.rpsi")).unwrap());
    for (args, needle) in [
        (vec!["--generate", "castle"], "unknown scene"),
        (vec!["--generate", "forest:trees=0"], "trees=0"),
        (vec!["--generate", "forest:height=3"], "unknown parameter"),
        (vec!["--generate", "building", "--view", "top"], "outside, inside"),
        (vec!["--generate", "forest:trees"], "key=value"),
    ] {
        let mut all = vec!["build", "-o", "x.rpsi"];
        all.extend(args.iter());
        let o = raypipe(dir.path(), &all);
        let err = stderr(&o);
        assert!(!o.status.success() && err.contains(needle) && !err.contains("panicked"), "{args:?}: {err}");
    }
}

/// HDR outputs: `.exr` and `.pfm` hold the linear framebuffer exactly;
/// exposure and tone mapping change only the PNG; outputs get the umask's permissions.
#[test]
fn hdr_outputs_hold_the_linear_framebuffer() {
    use raypipe::render::{render, Algorithm, RenderOptions};
    let dir = tempfile::tempdir().unwrap();
    let args = ["--algo", "whitted", "--size", "48x40", "--samples", "4", "--filter", "tent"];
    for out in ["a.exr", "a.pfm", "a.png", "b.png"] {
        let mut all = vec!["render", "-o", out];
        all.extend(args);
        if out == "b.png" {
            all.extend(["--exposure", "1.5", "--tonemap", "aces"]);
        }
        let o = raypipe(dir.path(), &all);
        assert!(o.status.success(), "{out}: {}", stderr(&o));
        let stdout = String::from_utf8_lossy(&o.stdout);
        assert!(stdout.contains("4 samples per pixel") && stdout.contains("Mrays/s"), "{stdout}");
        assert!(stdout.contains("load") && stdout.contains("build") && stdout.contains("render"), "{stdout}");
    }
    // The same frame in-process.
    let scene = raypipe::scene::load(None, &Default::default()).unwrap();
    let view = scene.view().unwrap();
    let cam = raypipe_core::image::CameraRecord { width: 48, height: 40, ..*view.camera().unwrap() };
    let opts = RenderOptions {
        algo: Algorithm::Whitted,
        samples: 4,
        filter: raypipe_core::pixel_filter::Filter::Tent,
        packet: raypipe::render::packets::PacketSize::auto_for(&view),
        ..Default::default()
    };
    let frame = render(&view, &cam, &opts).unwrap();

    let mut exr = vec![[f32::NAN; 3]; 48 * 40];
    let image = exr::prelude::read_first_rgba_layer_from_file(
        dir.path().join("a.exr"),
        |res, _| {
            assert_eq!((res.width(), res.height()), (48, 40));
            vec![[0.0f32; 3]; 48 * 40]
        },
        |px: &mut Vec<[f32; 3]>, pos, (r, g, b, _a): (f32, f32, f32, f32)| px[pos.y() * 48 + pos.x()] = [r, g, b],
    )
    .unwrap();
    exr.copy_from_slice(&image.layer_data.channel_data.pixels);
    assert!(exr == frame.radiance, "EXR values equal the linear framebuffer");
    assert!(frame.radiance.iter().any(|c| c.iter().any(|&v| v > 0.0 && v != 1.0)));

    let pfm = std::fs::read(dir.path().join("a.pfm")).unwrap();
    let header = b"PF\n48 40\n-1.0\n";
    assert_eq!(&pfm[..header.len()], header);
    let floats: Vec<f32> =
        pfm[header.len()..].chunks_exact(4).map(|b| f32::from_le_bytes(b.try_into().unwrap())).collect();
    for y in 0..40 {
        for x in 0..48 {
            // Rows bottom to top.
            let at = ((39 - y) * 48 + x) * 3;
            assert_eq!(&floats[at..at + 3], &frame.radiance[y * 48 + x], "pfm pixel {x},{y}");
        }
    }
    let (_, _, plain) = decode(&dir.path().join("a.png"));
    assert_eq!(plain, frame.pixels.as_flattened(), "the default PNG is the clamped sRGB image");
    let (_, _, mapped) = decode(&dir.path().join("b.png"));
    assert_ne!(plain, mapped, "exposure and tone mapping change the PNG");

    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let mode = std::fs::metadata(dir.path().join("a.png")).unwrap().permissions().mode() & 0o777;
        // SAFETY: umask has no memory-safety preconditions; it is put straight back.
        let mask = unsafe {
            let m = libc::umask(0o022);
            libc::umask(m);
            m
        } as u32;
        assert_eq!(mode, 0o666 & !mask, "output permissions follow the umask");
    }
    for (bad, what) in [("x.jpg", "must be a .png, .exr or .pfm"), ("nodir/x.exr", "does not exist")] {
        let o = raypipe(dir.path(), &["render", "-o", bad, "--size", "8x8"]);
        assert_one_line_error(&o, what);
    }
    let o = raypipe(dir.path(), &["render", "-o", "c.png", "--exposure", "inf"]);
    assert_one_line_error(&o, "--exposure");
    let o = raypipe(dir.path(), &["render", "-o", "c.png", "--filter", "lanczos"]);
    assert!(!o.status.success() && stderr(&o).contains("unknown filter"), "{}", stderr(&o));
}

/// Lights on the command line: a sun and a sky light the path tracer; on a
/// built image they replace its lights with a note; a structure flag the image cannot
/// apply is a warning; `info` describes the scene and its sections.
#[test]
fn lights_on_obj_and_image_and_info() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let tetra = fixtures().join("tetra.obj");
    let tetra = tetra.to_str().unwrap();
    let mean = |p: &Path| {
        let (_, _, px) = decode(p);
        px.iter().map(|&v| v as f64).sum::<f64>() / px.len() as f64
    };
    let o = raypipe(d, &["render", tetra, "--algo", "path", "--samples", "2", "--size", "48x36", "-o", "plain.png"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("chosen for the camera"));
    let o = raypipe(
        d,
        &[
            "render",
            tetra,
            "--algo",
            "path",
            "--samples",
            "2",
            "--size",
            "48x36",
            "--sun",
            "0.3,1,0.2,3,3,3",
            "--sky",
            "0.2,0.3,0.5,0.4,0.6,1",
            "-o",
            "sky.png",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(mean(&d.join("sky.png")) > mean(&d.join("plain.png")) + 5.0, "sun and sky brighten the scene");
    let o = raypipe(d, &["render", tetra, "--sun", "0,0,0", "-o", "x.png"]);
    assert_one_line_error(&o, "direction is zero");
    let o = raypipe(d, &["render", tetra, "--sky", "1,2", "-o", "x.png"]);
    assert!(!o.status.success() && stderr(&o).contains("expected r,g,b"), "{}", stderr(&o));

    let image = fixtures().join("tetra.rpsi");
    let image = image.to_str().unwrap();
    let o = raypipe(d, &["render", image, "--size", "48x36", "-o", "image.png"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = raypipe(
        d,
        &["render", image, "--size", "48x36", "--light", "0,3,-3,2,2,2", "--accel", "bvh", "-o", "relit.png"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(err.contains("note:") && err.contains("replace the image's"), "{err}");
    assert!(err.contains("warning:") && err.contains("--accel applies when building"), "{err}");
    assert_ne!(decode(&d.join("image.png")).2, decode(&d.join("relit.png")).2, "the new light is used");

    // The image's default light was placed for its own camera: seen from elsewhere it is
    // placed again, as for the OBJ built for that view.
    assert!(!err.contains("placed again"), "{err}");
    let moved = ["--eye", "2.5,2,2.5", "--size", "48x36"];
    let o = raypipe(d, &[&["render", image][..], &moved, &["-o", "moved.png"]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("default light is placed again for this camera"), "{}", stderr(&o));
    let obj = fixtures().join("tetra.obj");
    let o = raypipe(
        d,
        &[&["render", obj.to_str().unwrap()][..], &moved, &["--grid-min-dim", "4", "-o", "obj.png"]].concat(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(decode(&d.join("moved.png")).2, decode(&d.join("obj.png")).2, "the same light as built for that view");
    let o = raypipe(d, &["render", image, "--size", "48x36", "-o", "again.png"]);
    assert!(!stderr(&o).contains("placed again"), "its own camera keeps its light: {}", stderr(&o));

    let o = raypipe(d, &["info", image]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    for needle in ["bounds", "triangles   6", "lights", "camera", "structure   grid", "POSITIONS", "PRIM_LISTS"] {
        assert!(out.contains(needle), "{needle} in {out}");
    }
    let o = raypipe(d, &["info"]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("LIGHT_ALIAS"), "the Cornell box's emitters have a table");
    assert_one_line_error(&raypipe(d, &["info", "missing.obj"]), "missing.obj");
}

/// glTF 2.0 and PLY inputs: built, rendered and described like an OBJ;
/// the glTF's node transform, material and camera are used; malformed files are one-line
/// errors.
#[test]
fn gltf_and_ply_inputs() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A unit quad in z = 0, moved by its node to z = -5, emitting, seen by the file's
    // camera at the origin looking down -z.
    let mut bin = Vec::new();
    for p in [[-1.0f32, -1.0, 0.0], [1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0]] {
        p.iter().for_each(|c| bin.extend(c.to_le_bytes()));
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        bin.extend(i.to_le_bytes());
    }
    std::fs::write(d.join("quad.bin"), &bin).unwrap();
    let gltf = r#"{
      "asset": {"version": "2.0"},
      "scene": 0,
      "scenes": [{"nodes": [0, 1]}],
      "nodes": [
        {"mesh": 0, "translation": [0, 0, -5]},
        {"camera": 0, "translation": [0, 0, 0]}
      ],
      "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}],
      "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
      "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.8, 0.2, 1]}, "emissiveFactor": [0.5, 0.1, 0.1]}],
      "buffers": [{"uri": "quad.bin", "byteLength": 60}],
      "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 12}],
      "accessors": [
        {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-1, -1, 0], "max": [1, 1, 0]},
        {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}
      ]
    }"#;
    std::fs::write(d.join("quad.gltf"), gltf).unwrap();
    let o = raypipe(d, &["info", "quad.gltf"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("triangles   2") && out.contains("1 emissive"), "{out}");
    assert!(out.contains("-5"), "the node's translation is applied: {out}");
    assert!(out.contains("eye [0.0, 0.0, 0.0]"), "the file's camera: {out}");
    let o = raypipe(d, &["render", "quad.gltf", "--size", "32x32", "-o", "quad.png"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (_, _, px) = decode(&d.join("quad.png"));
    let centre = &px[(16 * 32 + 16) * 3..(16 * 32 + 16) * 3 + 3];
    assert!(centre[1] > centre[2] && centre[0] > centre[2], "the green, red-glowing quad fills the view: {centre:?}");
    std::fs::write(d.join("bad.gltf"), "{\"asset\": {\"version\": \"2.0\"}, \"meshes\": [{]}").unwrap();
    assert_one_line_error(&raypipe(d, &["render", "bad.gltf", "-o", "x.png"]), "malformed glTF");

    let ply = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
    std::fs::write(d.join("quad.ply"), ply).unwrap();
    let o = raypipe(d, &["build", "quad.ply", "-o", "quad.rpsi", "--accel", "bvh"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("triangles    2"));
    let o = raypipe(d, &["render", "quad.ply", "--size", "16x16", "-o", "ply.png"]);
    assert!(o.status.success(), "{}", stderr(&o));
    std::fs::write(d.join("bad.ply"), "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n")
        .unwrap();
    assert_one_line_error(&raypipe(d, &["render", "bad.ply", "-o", "x.png"]), "bad.ply");
    assert!(!d.join("x.png").exists());
}

/// A scene file: two meshes from different formats, transformed, one with
/// a material override, a sun and a camera, built into one image; bad entries are
/// one-line errors naming the file and the mesh.
#[test]
fn scene_file_assembles_meshes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let tetra = fixtures().join("tetra.obj");
    std::fs::copy(&tetra, d.join("tetra.obj")).unwrap();
    std::fs::copy(fixtures().join("tetra.mtl"), d.join("tetra.mtl")).unwrap();
    let ply = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n-5 0 -5\n5 0 -5\n5 0 5\n-5 0 5\n4 0 3 2 1\n";
    std::fs::write(d.join("floor.ply"), ply).unwrap();
    let scene = r#"
[camera]
eye = [0, 4, 8]
look_at = [0, 0.5, 0]
size = [40, 30]

[[mesh]]
file = "tetra.obj"
translate = [0, 0, 0]
rotate = [0, 45, 0]
scale = 1.5

[[mesh]]
file = "floor.ply"
translate = [0, -0.01, 0]
material = "red"

[materials.red]
diffuse = [0.8, 0.1, 0.1]

[[light]]
kind = "sun"
direction = [0.2, 1, 0.3]
color = [1.5, 1.5, 1.5]
"#;
    std::fs::write(d.join("scene.toml"), scene).unwrap();
    let o = raypipe(d, &["info", "scene.toml"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("triangles   8"), "6 of the tetra + 2 of the floor: {out}");
    assert!(out.contains("3 objects"), "the tetra's two and the floor: {out}");
    assert!(out.contains("directional"), "the file's sun: {out}");
    assert!(out.contains("40x30"), "the file's camera: {out}");
    let o = raypipe(d, &["render", "scene.toml", "-o", "scene.png"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (w, h, px) = decode(&d.join("scene.png"));
    assert_eq!((w, h), (40, 30));
    // The tetra fixture brings its own white floor (rotated under the middle); the red
    // floor shows at the sides.
    let bottom = &px[(28 * 40 + 1) * 3..(28 * 40 + 1) * 3 + 3];
    assert!(bottom[0] as u32 > 2 * (bottom[1] as u32).max(1), "the red floor under the camera: {bottom:?}");
    for (text, needle) in [
        ("[[mesh]]\nfile = \"missing.obj\"\n", "missing.obj"),
        ("[[mesh]]\nfile = \"floor.ply\"\nmaterial = \"gold\"\n", "material 'gold' is not in [materials]"),
        ("[[mesh]]\nfile = \"floor.ply\"\nscale = 0\n", "scale of zero"),
        ("[[mesh]]\nfile = \"floor.ply\"\ncolour = 1\n", "unknown field"),
        ("[camera]\nfov = 40\n", "lists no [[mesh]]"),
        ("[[mesh]]\nfile = \"floor.ply\"\n[[light]]\nkind = \"spot\"\n", "unknown kind 'spot'"),
        ("[[mesh]]\nfile = \"bad.toml\"\n", "cannot include another"),
    ] {
        std::fs::write(d.join("bad.toml"), text).unwrap();
        assert_one_line_error(&raypipe(d, &["render", "bad.toml", "-o", "x.png"]), needle);
    }
    assert!(!d.join("x.png").exists());
}

/// A small sweep: two axes crossed with two listed points, on the tetrahedron.
fn sweep_spec(dir: &Path) -> PathBuf {
    let tetra = fixtures().join("tetra.obj");
    write(
        dir,
        "spec.toml",
        &format!(
            "[fixed]\nscene = {:?}\nsize = \"24x16\"\n[grid]\n\"traversal.units\" = [1, 2]\npacket_size = [4, 16]\n\
             [[points]]\naccel = \"kd\"\n[[points]]\naccel = \"bvh4\"\n\"memory.model\" = \"dram\"\n",
            tetra.display().to_string()
        ),
    )
}

#[test]
fn sweep_points_are_stand_alone_runs_and_shards_merge_to_the_whole() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let spec = sweep_spec(d);
    std::fs::create_dir(d.join("reports")).unwrap();
    let o = raypipe(d, &["sweep", "spec.toml", "-o", "all", "--reports", "reports", "--jobs", "2"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let csv = std::fs::read_to_string(d.join("all.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 9, "{csv}");
    // Columns: parameters in spec order, then the verdict and the metrics.
    assert!(
        lines[0].starts_with("index,scene,size,traversal.units,packet_size,accel,memory.model,bottleneck,error,fps,")
    );
    // Point 7 = accel bvh4 on DRAM, units 2, packets of 16: the same report, byte for
    // byte, as the stand-alone command.
    assert_eq!(spec.parent(), Some(d));
    let tetra = fixtures().join("tetra.obj");
    let o = raypipe(
        d,
        &[
            "simulate",
            tetra.to_str().unwrap(),
            "--size",
            "24x16",
            "--set",
            "traversal.units=2",
            "--set",
            "packet_size=16",
            "--accel",
            "bvh4",
            "--set",
            "memory.model=\"dram\"",
            "--report",
            "alone.json",
            "-o",
            "alone.png",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(std::fs::read(d.join("alone.json")).unwrap(), std::fs::read(d.join("reports/point-7.json")).unwrap());
    assert!(lines[8].starts_with("7,"), "{}", lines[8]);
    // Shards (written in any order) merged = the single run, byte for byte.
    for i in 0..3 {
        let shard = format!("{i}/3");
        let out = format!("part{i}");
        let o = raypipe(d, &["sweep", "spec.toml", "--shard", &shard, "-o", &out]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let o = raypipe(d, &["sweep", "merge", "part2.jsonl", "part0.jsonl", "part1.jsonl", "-o", "merged"]);
    assert!(o.status.success(), "{}", stderr(&o));
    for ext in ["csv", "jsonl"] {
        let (a, b) = (d.join(format!("all.{ext}")), d.join(format!("merged.{ext}")));
        assert_eq!(std::fs::read(a).unwrap(), std::fs::read(b).unwrap(), "{ext}");
    }
    // Resuming recomputes nothing: no point runs (its report would be written again),
    // and the outputs are unchanged.
    std::fs::remove_dir_all(d.join("reports")).unwrap();
    std::fs::create_dir(d.join("reports")).unwrap();
    let o = raypipe(d, &["sweep", "spec.toml", "-o", "all", "--reports", "reports"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("8 already done, 0 to run"));
    assert!(only_files(&d.join("reports")).is_empty());
    assert_eq!(std::fs::read_to_string(d.join("all.csv")).unwrap(), csv);
    // A run stopped half-way resumes with the missing points only.
    let jsonl = std::fs::read_to_string(d.join("all.jsonl")).unwrap();
    let kept: Vec<&str> = jsonl.lines().take(5).collect();
    std::fs::write(d.join("all.jsonl"), format!("{}\n{{\"index\":5,\"poi", kept.join("\n"))).unwrap();
    let o = raypipe(d, &["sweep", "spec.toml", "-o", "all", "--reports", "reports"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("5 already done, 3 to run"),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    assert_eq!(only_files(&d.join("reports")), ["point-5.json", "point-6.json", "point-7.json"]);
    assert_eq!(std::fs::read_to_string(d.join("all.csv")).unwrap(), csv);
}

#[test]
fn sweep_rejects_bad_specs_before_running_anything() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cases: [(&str, &str); 6] = [
        ("[grid]\n\"traversal.unitz\" = [1]\n", "no such parameter"),
        ("[grid]\n\"traversal.units\" = []\n", "non-empty list"),
        ("[fixed]\npacket_size = 3\n", "packet_size"),
        ("[fixed]\nscene = \"missing.obj\"\n", "no such file"),
        ("[fixed]\noutput = \"x.png\"\n", "cannot be a sweep parameter"),
        ("[grids]\n", "unknown section"),
    ];
    for (text, needle) in cases {
        write(d, "bad.toml", text);
        let o = raypipe(d, &["sweep", "bad.toml", "-o", "out"]);
        assert_one_line_error(&o, needle);
        assert!(!d.join("out.csv").exists() && !d.join("out.jsonl").exists(), "{text}");
    }
    let o = raypipe(d, &["sweep", "bad.toml", "--shard", "3/3"]);
    assert!(!o.status.success());
}

#[test]
fn plots_of_a_small_sweep_decode() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    sweep_spec(d);
    let o = raypipe(d, &["sweep", "spec.toml", "-o", "s"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let plots: [&[&str]; 4] = [
        &["--x", "traversal.units", "--y", "fps", "--series", "packet_size", "--where", "accel=kd", "-o", "line.png"],
        &[
            "--x",
            "traversal.units",
            "--y",
            "packet_size",
            "--value",
            "bytes_per_ray",
            "--where",
            "accel=bvh4",
            "-o",
            "heat.svg",
        ],
        &[
            "--x",
            "packet_size",
            "--stack",
            "stall.traversal",
            "--where",
            "accel=kd",
            "--where",
            "traversal.units=2",
            "-o",
            "bars.png",
        ],
        &[
            "--x",
            "traversal.units",
            "--stack",
            "bytes_per_ray",
            "--where",
            "accel=kd",
            "--where",
            "packet_size=16",
            "-o",
            "bytes.svg",
        ],
    ];
    for args in plots {
        let mut all = vec!["plot", "s.jsonl"];
        all.extend_from_slice(args);
        let o = raypipe(d, &all);
        assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    }
    for png in ["line.png", "bars.png"] {
        let (w, h, _) = decode(&d.join(png));
        assert!(w > 100 && h > 100, "{png}");
    }
    for svg in ["heat.svg", "bytes.svg"] {
        let text = std::fs::read_to_string(d.join(svg)).unwrap();
        let png = raypipe::output::chart_raster::to_png(&text).expect("the SVG parses and renders");
        assert!(png.starts_with(b"\x89PNG"), "{svg}");
    }
    // Rows the plot cannot tell apart are refused, naming what differs.
    let o = raypipe(d, &["plot", "s.jsonl", "--x", "traversal.units", "--y", "fps", "-o", "x.svg"]);
    assert_one_line_error(&o, "differ in packet_size");
    assert!(!d.join("x.svg").exists());
}

#[test]
fn report_diff_names_the_changed_keys_and_every_ratio() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for (units, name) in [("1", "a"), ("2", "b")] {
        let report = format!("{name}.json");
        let set = format!("traversal.units={units}");
        let o = raypipe(d, &["simulate", "--size", "24x24", "--set", &set, "--report", &report, "-o", "x.png"]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let o = raypipe(d, &["report", "diff", "a.json", "b.json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout).into_owned();
    let setting = out.lines().find(|l| l.trim_start().starts_with("config.traversal.units")).expect(&out);
    assert!(setting.ends_with("1 -> 2"), "{setting}");
    assert_eq!(out.matches("  config.").count(), 1, "only one configuration key differs: {out}");
    assert!(out.contains("only in B: units.traversal1, units.intersection1"), "{out}");
    // The cycles line carries both values and their ratio.
    let cycles = |f: &str| -> f64 {
        let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(d.join(f)).unwrap()).unwrap();
        v["cycles"].as_f64().unwrap()
    };
    let (a, b) = (cycles("a.json"), cycles("b.json"));
    let line = out.lines().find(|l| l.trim_start().starts_with("cycles ")).expect(&out);
    let cols: Vec<&str> = line.split_whitespace().collect();
    assert_eq!(cols, ["cycles", &format!("{a}"), &format!("{b}"), &format!("{:.3}", b / a)]);
    // A file that is not a report is one line of error.
    write(d, "bad.json", "[1, 2]");
    assert_one_line_error(&raypipe(d, &["report", "diff", "a.json", "bad.json"]), "bad.json: not a JSON report");
    assert_one_line_error(&raypipe(d, &["report", "diff", "a.json", "missing.json"]), "missing.json");
}

#[test]
fn walkthroughs_write_every_frame_on_the_host_and_the_model() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "walk.path", "size 24 16\nframes 3\nkey 278 273 -800 278 273 0\nkey 300 273 -700 278 273 0\n");
    let o = raypipe(d, &["render", "--camera-path", "walk.path", "-o", "host.png"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("3 frames in"));
    let o = raypipe(
        d,
        &["simulate", "--camera-path", "walk.path", "--warmup-frames", "1", "--interval", "500", "-o", "sim.png"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("steady state   2 frames after 1 warm-up"));
    for k in 0..3 {
        let (host, sim) = (d.join(format!("host-000{k}.png")), d.join(format!("sim-000{k}.png")));
        assert_eq!(decode(&host), decode(&sim), "frame {k}");
        assert_eq!(decode(&host).0, 24);
    }
    let frames = std::fs::read_to_string(d.join("raypipe-sim.frames.jsonl")).unwrap();
    let rows: Vec<serde_json::Value> = frames.lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    assert_eq!(rows.len(), 3);
    assert_eq!(rows.iter().map(|r| r["warmup"].as_bool().unwrap()).collect::<Vec<_>>(), [true, false, false]);
    // Interval rows for the measured frames only, each frame's summing to its cycles.
    let intervals = std::fs::read_to_string(d.join("raypipe-sim.intervals.jsonl")).unwrap();
    let rows: Vec<serde_json::Value> = intervals.lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    for k in [1u64, 2] {
        let sum: u64 = rows.iter().filter(|r| r["frame"] == k).map(|r| r["counters"]["cycles"].as_u64().unwrap()).sum();
        let cycles = serde_json::from_str::<serde_json::Value>(frames.lines().nth(k as usize).unwrap()).unwrap()
            ["cycles"]
            .as_u64()
            .unwrap();
        assert_eq!(sum, cycles, "frame {k}");
    }
    assert!(rows.iter().all(|r| r["frame"] != 0));
    // Bad paths and measures are one line of error.
    write(d, "bad.path", "frames 2\nkey 0 0 0 0 0\n");
    assert_one_line_error(&raypipe(d, &["simulate", "--camera-path", "bad.path"]), "bad.path:2: 'key' takes");
    assert_one_line_error(&raypipe(d, &["simulate", "--roi", "50..10"]), "empty");
    assert_one_line_error(&raypipe(d, &["simulate", "--orbit", "2", "--warmup-frames", "2"]), "only 2 frames");
    assert_one_line_error(&raypipe(d, &["simulate", "--interval", "0"]), "at least one cycle");
}

/// A waveform read back: its dotted name and its (time, value) changes.
type Wave = (String, Vec<(u64, u64)>);

/// Reads a VCD back: every variable, and the last timestamp.
fn read_vcd(path: &Path) -> (Vec<Wave>, u64) {
    use vcd::{Command as Vcd, IdCode, ScopeItem};
    let mut parser = vcd::Parser::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let header = parser.parse_header().unwrap();
    let mut vars: Vec<(IdCode, String)> = Vec::new();
    fn walk(items: &[ScopeItem], prefix: &str, vars: &mut Vec<(IdCode, String)>) {
        for item in items {
            match item {
                ScopeItem::Scope(s) => walk(&s.items, &format!("{prefix}{}.", s.identifier), vars),
                ScopeItem::Var(v) => vars.push((v.code, format!("{prefix}{}", v.reference))),
                _ => {}
            }
        }
    }
    walk(&header.items, "", &mut vars);
    let mut changes: Vec<Vec<(u64, u64)>> = vec![Vec::new(); vars.len()];
    let (mut t, mut end) = (0, 0);
    for cmd in parser {
        match cmd.unwrap() {
            Vcd::Timestamp(ts) => {
                t = ts;
                end = ts;
            }
            Vcd::ChangeVector(id, v) => {
                let k = vars.iter().position(|(c, _)| *c == id).unwrap();
                let value = v.iter().fold(0u64, |acc, b| acc * 2 + u64::from(b == vcd::Value::V1));
                changes[k].push((t, value));
            }
            Vcd::ChangeScalar(id, v) => {
                let k = vars.iter().position(|(c, _)| *c == id).unwrap();
                changes[k].push((t, u64::from(v == vcd::Value::V1)));
            }
            _ => {}
        }
    }
    (vars.into_iter().map(|(_, n)| n).zip(changes).collect(), end)
}

#[test]
fn waveforms_and_traces_observe_without_changing_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let base = ["simulate", "--size", "32x24", "--algo", "whitted", "--set", "memory.model=\"dram\"", "-o", "x.png"];
    let o = raypipe(d, &[&base[..], &["--report", "plain.json"]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let o = raypipe(d, &[&base[..], &["--report", "watched.json", "--vcd", "w.vcd", "--trace", "t.json"]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let plain = std::fs::read_to_string(d.join("plain.json")).unwrap();
    assert_eq!(plain, std::fs::read_to_string(d.join("watched.json")).unwrap(), "tracing changed the report");
    let report: serde_json::Value = serde_json::from_str(&plain).unwrap();
    // The VCD parses; each FIFO's occupancy averaged over time is the report's mean.
    let (signals, end) = read_vcd(&d.join("w.vcd"));
    let fifos = report["fifos"].as_array().unwrap();
    assert_eq!(signals.iter().filter(|(n, _)| n.ends_with(".occupancy")).count(), fifos.len());
    for f in fifos {
        let name = format!("raypipe.fifos.{}.occupancy", f["name"].as_str().unwrap());
        let (_, changes) = signals.iter().find(|(n, _)| *n == name).expect(&name);
        let mut area = 0u64;
        for (k, (t, v)) in changes.iter().enumerate() {
            let next = changes.get(k + 1).map_or(end, |c| c.0);
            area += v * (next - t);
        }
        let ticked: u64 = f["occupancy"].as_array().unwrap().iter().map(|c| c.as_u64().unwrap()).sum();
        assert_eq!(end, ticked, "the VCD ends where the units stopped ticking");
        let mean = f["mean_occupancy"].as_f64().unwrap();
        assert!((area as f64 / end as f64 - mean).abs() < 1e-9, "{name}: {} vs {mean}", area as f64 / end as f64);
    }
    for n in [
        "raypipe.traversal0.activity",
        "raypipe.traversal0.threads.fetching",
        "raypipe.memory.queue",
        "raypipe.memory.requests",
    ] {
        assert!(signals.iter().any(|(s, _)| s == n), "{n}");
    }
    // The trace: valid JSON, one begin and one end per packet, begin first.
    let trace: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(d.join("t.json")).unwrap()).unwrap();
    let events = trace["traceEvents"].as_array().unwrap();
    let mut packets: std::collections::BTreeMap<String, (u32, u32, u64, u64)> = Default::default();
    for e in events.iter().filter(|e| e["name"].as_str().is_some_and(|n| n.starts_with("packet "))) {
        let p = packets.entry(e["id"].as_str().unwrap().to_string()).or_default();
        match e["ph"].as_str().unwrap() {
            "b" => (p.0, p.2) = (p.0 + 1, e["ts"].as_u64().unwrap()),
            "e" => (p.1, p.3) = (p.1 + 1, e["ts"].as_u64().unwrap()),
            ph => panic!("{ph}"),
        }
    }
    let primary = (32 / 4) * (24 / 4);
    assert!(packets.len() > primary, "primary and secondary packets: {}", packets.len());
    assert!(packets.values().all(|&(b, e, t0, t1)| b == 1 && e == 1 && t0 <= t1));
    let memory = events.iter().filter(|e| e["cat"] == "memory").count() as u64;
    assert_eq!(
        memory,
        report["memory"]["requests"].as_u64().unwrap() + report["memory"]["l2"]["hits"].as_u64().unwrap()
    );
    // A window and a unit filter narrow the VCD; an empty filter is an error.
    let o =
        raypipe(d, &[&base[..], &["--vcd", "n.vcd", "--vcd-window", "100..200", "--vcd-units", "traversal1"]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let (narrow, end) = read_vcd(&d.join("n.vcd"));
    assert!(narrow.iter().all(|(n, _)| n.starts_with("raypipe.traversal1.")) && !narrow.is_empty());
    assert!(narrow.iter().all(|(_, c)| c.iter().all(|(t, _)| (100..200).contains(t))) && end <= 200);
    assert_one_line_error(
        &raypipe(d, &[&base[..], &["--vcd", "z.vcd", "--vcd-units", "nothing"]].concat()),
        "no signal",
    );
    assert!(!d.join("z.vcd").exists());
}

#[test]
fn cost_images_are_written_by_simulate_and_stats() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let o = raypipe(d, &["simulate", "--size", "40x30", "--cost-image", "sim", "-o", "x.png"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = raypipe(d, &["stats", "--size", "40x30", "--cost-image", "host"]);
    assert!(o.status.success(), "{}", stderr(&o));
    for f in ["sim-cycles", "sim-steps", "sim-tests", "sim-bytes", "host-steps", "host-tests", "host-bytes"] {
        let (w, h, _) = decode(&d.join(format!("{f}.png")));
        assert!(w > 40 * 9 && h > 30 * 9, "{f}: {w}x{h}");
    }
    assert_one_line_error(&raypipe(d, &["stats", "--cost-image", "nowhere/x"]), "does not exist");
}
