//! Bad input on every command: missing files, malformed geometry, corrupted images,
//! impossible cameras, failed writes — one line of error, no half-written output.

use crate::common::*;

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

/// A command line clap refuses is one line too (exit 2, as clap's), saying what is
/// wrong with the value rather than that a negative number looks like a flag.
#[test]
fn refused_command_lines_are_one_line() {
    let dir = tempfile::tempdir().unwrap();
    for (args, needle) in [
        (vec!["render", "--size", "-5x5"], "'-5' is not a pixel count"),
        (vec!["render", "--sky", "-1,0,0"], "radiance must be finite and not negative"),
        (vec!["simulate", "--orbit", "-3"], "invalid value '-3' for '--orbit <N>'"),
        (vec!["render", "--algo", "foo"], "(possible values: cast, shadow, whitted, path)"),
        (vec!["render", "--sizee", "4x4"], "did you mean '--size'?"),
    ] {
        let o = raypipe(dir.path(), &args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
        assert!(err.starts_with("error: ") && err.contains(needle), "{args:?}: {err}");
    }
    assert_eq!(only_files(dir.path()), Vec::<String>::new());
}

/// A camera that cannot make rays is refused naming the file it came from.
#[test]
fn camera_errors_name_their_file() {
    let dir = tempfile::tempdir().unwrap();
    let tetra = fixtures().join("tetra.obj").display().to_string();
    write(dir.path(), "s.toml", &format!("[[mesh]]\nfile = {tetra:?}\n[camera]\nfov = 500\n"));
    assert_one_line_error(&raypipe(dir.path(), &["render", "s.toml", "-o", "x.png"]), "s.toml: camera: field of view");
    write(dir.path(), "c.camera", "eye 0 0 0\nlook_at 0 0 0\n");
    let o = raypipe(dir.path(), &["render", &tetra, "--camera", "c.camera", "-o", "x.png"]);
    assert_one_line_error(&o, "c.camera: camera: camera eye and look-at point coincide");
}
