//! Instanced scenes on the command line: a scene file's `[[instance]]` entries and a
//! glTF file's shared meshes built into `.rpsx`, described by `info`, rendered like the
//! same copies merged into one flat mesh; bad transforms and corrupted files refused
//! with one line.

use crate::common::*;

/// Three tetrahedra scenes placed by instances (one with an override material), and the
/// same placements as merged `[[mesh]]` entries.
fn scene_files(d: &std::path::Path) {
    let tetra = fixtures().join("tetra.obj");
    let t = tetra.display();
    let placements = [
        ("translate = [-4.5, 0, 0]\nrotate = [0, 30, 0]", ""),
        ("translate = [0, 0, 0]\nscale = [1, 1.5, 1]", "material = \"red\""),
        ("translate = [4.5, 0.5, -1]\nrotate = [10, -45, 0]\nscale = 0.8", ""),
    ];
    let head = "[camera]\neye = [0, 6, 12]\nlook_at = [0, 0.5, 0]\nfov = 50\nsize = [96, 64]\n\n[materials.red]\ndiffuse = [0.9, 0.1, 0.1]\n\n[[light]]\nkind = \"point\"\nposition = [2, 8, 6]\n";
    let mut inst = head.to_string();
    let mut flat = head.to_string();
    for (p, m) in placements {
        inst += &format!("\n[[instance]]\nfile = \"{t}\"\n{p}\n{m}\n");
        flat += &format!("\n[[mesh]]\nfile = \"{t}\"\n{p}\n{m}\n");
    }
    write(d, "inst.toml", &inst);
    write(d, "flat.toml", &flat);
}

#[test]
fn a_scene_file_of_instances_builds_describes_and_renders_as_its_flat_copy() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    scene_files(d);
    for accel in ["bvh", "bvh4", "kd", "grid"] {
        let o = raypipe(d, &["build", "inst.toml", "--accel", accel, "-o", "inst.rpsx"]);
        assert!(o.status.success(), "{}", stderr(&o));
        let out = String::from_utf8_lossy(&o.stdout);
        assert!(out.contains("instances    3 of 1 meshes"), "{out}");
        let o = raypipe(d, &["info", "inst.rpsx"]);
        let out = String::from_utf8_lossy(&o.stdout);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(out.contains("instances   3 of 1 meshes (1 with an override material)"), "{out}");
        assert!(out.contains("placed 3×"), "{out}");
        for algo in ["cast", "whitted"] {
            let o = raypipe(d, &["render", "inst.rpsx", "--algo", algo, "-o", "inst.png"]);
            assert!(o.status.success(), "{}", stderr(&o));
            // The scene file itself renders the same image, built in memory.
            let o = raypipe(d, &["render", "inst.toml", "--accel", accel, "--algo", algo, "-o", "mem.png"]);
            assert!(o.status.success(), "{}", stderr(&o));
            assert_eq!(decode(&d.join("inst.png")), decode(&d.join("mem.png")), "{accel} {algo}");
            let o = raypipe(d, &["render", "flat.toml", "--accel", accel, "--algo", algo, "-o", "flat.png"]);
            assert!(o.status.success(), "{}", stderr(&o));
            let (w, h, a) = decode(&d.join("inst.png"));
            let (_, _, b) = decode(&d.join("flat.png"));
            // Copies transformed once (flat) or rays transformed per instance differ by
            // rounding only: at silhouettes and edges, a few pixels by a few levels.
            let differ =
                a.chunks(3).zip(b.chunks(3)).filter(|(p, q)| p.iter().zip(q.iter()).any(|(x, y)| x.abs_diff(*y) > 2));
            let n = differ.count();
            assert!(n * 100 <= (w * h) as usize, "{accel} {algo}: {n} of {} pixels differ", w * h);
        }
    }
}

#[test]
fn a_gltf_files_shared_mesh_becomes_instances() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let gltf = fixtures().join("shared-quad.gltf");
    let o = raypipe(d, &["build", gltf.to_str().unwrap(), "--instances", "--accel", "bvh", "-o", "q.rpsx"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("instances    2 of 1 meshes"), "{out}");
    let o = raypipe(d, &["render", "q.rpsx", "--size", "32x32", "-o", "q.png"]);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn bad_instances_and_corrupted_files_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let t = fixtures().join("tetra.obj");
    let t = t.display();
    let cases = [
        (format!("[[instance]]\nfile = \"{t}\"\nscale = [1, 0, 1]\n"), "instance 1"),
        (format!("[[instance]]\nfile = \"{t}\"\ntranslate = [nan, 0, 0]\n"), "NaN or infinite"),
        (format!("[[instance]]\nfile = \"{t}\"\nscale = 1e-40\n"), "singular"),
        (format!("[[instance]]\nfile = \"{t}\"\nmaterial = \"gold\"\n"), "material 'gold'"),
        ("[[instance]]\nfile = \"missing.obj\"\n".to_string(), "missing.obj"),
        ("[[instance]]\nfile = \"inst.toml\"\n".to_string(), "cannot include another"),
    ];
    for (text, needle) in cases {
        write(d, "inst.toml", &text);
        let o = raypipe(d, &["build", "inst.toml", "-o", "out.rpsx"]);
        assert_one_line_error(&o, needle);
        let o = raypipe(d, &["render", "inst.toml", "-o", "out.png"]);
        assert_one_line_error(&o, needle);
        assert_eq!(only_files(d), ["inst.toml"]);
    }
    // A good file, then damaged: truncated, and a flipped byte in the index and in a mesh.
    write(
        d,
        "inst.toml",
        &format!("[[instance]]\nfile = \"{t}\"\n[[instance]]\nfile = \"{t}\"\ntranslate = [5, 0, 0]\n"),
    );
    let o = raypipe(d, &["build", "inst.toml", "-o", "good.rpsx"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let good = std::fs::read(d.join("good.rpsx")).unwrap();
    let damaged = [
        (good[..good.len() / 2].to_vec(), "truncated"),
        (
            {
                let mut b = good.clone();
                b[200] ^= 0x40;
                b
            },
            "checksum",
        ),
        (
            {
                let mut b = good.clone();
                let n = b.len();
                b[n - 100] ^= 0x40;
                b
            },
            "bottom image 0",
        ),
    ];
    for (bytes, needle) in damaged {
        std::fs::write(d.join("bad.rpsx"), bytes).unwrap();
        for cmd in ["render", "info"] {
            let mut args = vec![cmd, "bad.rpsx"];
            if cmd == "render" {
                args.extend(["-o", "bad.png"]);
            }
            let o = raypipe(d, &args);
            assert_one_line_error(&o, needle);
        }
        assert!(!d.join("bad.png").exists());
    }
    // Algorithms that need one flat triangle list say so.
    let o = raypipe(d, &["render", "good.rpsx", "--algo", "path", "-o", "p.png"]);
    assert_one_line_error(&o, "--algo cast or whitted");
}
