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
    for sub in ["build", "render", "stats", "bench"] {
        let o = raypipe(dir.path(), &[sub, "--help"]);
        assert!(o.status.success());
        let out = String::from_utf8_lossy(&o.stdout);
        assert!(out.contains("Usage: raypipe"), "{sub}: {out}");
    }
    let o = raypipe(dir.path(), &["--help"]);
    let out = String::from_utf8_lossy(&o.stdout);
    for sub in ["build", "render", "stats", "bench"] {
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
    assert!(!d.join("o.png").exists());
}

#[test]
fn failed_writes_leave_no_half_written_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
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
