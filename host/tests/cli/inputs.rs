//! What inputs cannot do: a device, FIFO or link to one is refused instead of read
//! until memory runs out, and a small input that would multiply into more geometry than
//! a scene may hold is refused before it is made.

use super::common::*;

#[test]
fn devices_are_not_read_as_inputs() {
    let dir = tempfile::tempdir().unwrap();
    std::os::unix::fs::symlink("/dev/zero", dir.path().join("zero.obj")).unwrap();
    std::os::unix::fs::symlink("/dev/urandom", dir.path().join("noise.gltf")).unwrap();
    let tetra = fixtures().join("tetra.obj").display().to_string();
    for (args, needle) in [
        (vec!["build", "zero.obj", "-o", "x.rpsi"], "zero.obj: is a character device"),
        (vec!["build", "noise.gltf", "-o", "x.rpsi"], "noise.gltf: is a character device"),
        (vec!["build", "/dev/zero", "-o", "x.rpsi"], "/dev/zero: is a character device"),
        (vec!["render", &tetra, "--camera", "/dev/zero", "-o", "x.png"], "/dev/zero: is a character device"),
        (vec!["trace", &tetra, "--rays", "/dev/urandom", "--hits", "h.npy"], "/dev/urandom: is a character device"),
        (vec!["simulate", "--config", "/dev/zero"], "/dev/zero: is a character device"),
        (vec!["report", "diff", "/dev/zero", "/dev/zero"], "/dev/zero: is a character device"),
        (vec!["sweep", "/dev/zero"], "/dev/zero: is a character device"),
    ] {
        let o = raypipe(dir.path(), &args);
        assert_one_line_error(&o, needle);
    }
    assert_eq!(only_files(dir.path()), ["noise.gltf", "zero.obj"]);
}

#[test]
fn a_scene_file_naming_one_mesh_many_times_is_counted_first() {
    let dir = tempfile::tempdir().unwrap();
    // A 20 k-triangle mesh listed 2,000 times: 40 M triangles from a 50 KB scene file,
    // refused at the 1,678th entry, before any copy is made.
    let mut obj = String::new();
    for i in 0..10_000 {
        let x = i as f32;
        obj.push_str(&format!("v {x} 0 0\nv {x} 1 0\nv {x} 0 1\nv {x} 1 1\n"));
        let b = 4 * i + 1;
        obj.push_str(&format!("f {} {} {}\nf {} {} {}\n", b, b + 1, b + 2, b + 1, b + 3, b + 2));
    }
    write(dir.path(), "m.obj", &obj);
    let mut spec = String::new();
    for _ in 0..2_000 {
        spec.push_str("[[mesh]]\nfile = \"m.obj\"\n");
    }
    write(dir.path(), "s.toml", &spec);
    let o = raypipe(dir.path(), &["build", "s.toml", "-o", "x.rpsi"]);
    assert_one_line_error(&o, "brings the scene to 33560000 triangles, more than 33554432");
    assert_eq!(only_files(dir.path()), ["m.obj", "s.toml"]);
}
