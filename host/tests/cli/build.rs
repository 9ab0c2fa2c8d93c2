//! `raypipe build`: images equal to their sources, generated scenes, glTF, PLY and
//! scene files.

use crate::common::*;

#[test]
fn build_then_render_the_image_equals_rendering_the_obj() {
    let dir = tempfile::tempdir().unwrap();
    let obj = fixtures().join("cornell_box.obj");
    let obj = obj.to_str().unwrap();
    let o = raypipe(dir.path(), &["build", obj, "-o", "box.rpsi", "--accel", "grid", "--grid-min-dim", "5"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("triangles    32"), "{out}");
    assert!(out.contains("grid         5 x 5 x 5"), "{out}");
    let a = raypipe(dir.path(), &["render", "box.rpsi", "-o", "a.png", "--size", "80x60"]);
    let b = raypipe(
        dir.path(),
        &["render", obj, "-o", "b.png", "--size", "80x60", "--accel", "grid", "--grid-min-dim", "5"],
    );
    let c = raypipe(dir.path(), &["render", "-o", "c.png", "--size", "80x60"]);
    assert!(a.status.success() && b.status.success() && c.status.success());
    let (pa, pb, pc) =
        (decode(&dir.path().join("a.png")), decode(&dir.path().join("b.png")), decode(&dir.path().join("c.png")));
    assert_eq!(pa, pb);
    // The built-in default is the same box; a different grid resolution, the same image.
    assert_eq!(pa, pc);
}

#[test]
fn generated_scenes_build_with_their_views() {
    let dir = tempfile::tempdir().unwrap();
    for (spec, views) in
        [("building:floors=1,rooms=2", ["outside", "inside"]), ("forest:trees=4,leaves=20", ["top", "inside"])]
    {
        for view in views {
            let out = format!("{view}.rpsi");
            // Purcell's stream machine walks a grid.
            let o = raypipe(dir.path(), &["build", "--generate", spec, "--view", view, "--accel", "grid", "-o", &out]);
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
    // The file's own camera, impossible: refused naming the file.
    std::fs::write(d.join("wide.gltf"), gltf.replace("\"yfov\": 0.8", "\"yfov\": 3.5")).unwrap();
    assert_one_line_error(&raypipe(d, &["render", "wide.gltf", "-o", "x.png"]), "wide.gltf: camera: field of view");
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

#[test]
fn a_build_is_the_same_image_on_any_number_of_threads() {
    // 14,720 triangles: enough for the BVH builder's subtrees to run as parallel tasks.
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut images = Vec::new();
    for (accel, threads) in [("bvh8", "1"), ("bvh8", "3"), ("kd", "1"), ("kd", "2")] {
        let out = format!("{accel}-{threads}.rpsi");
        let o =
            raypipe(d, &["build", "--generate", "forest:trees=8", "--accel", accel, "--threads", threads, "-o", &out]);
        assert!(o.status.success(), "{}", stderr(&o));
        images.push(std::fs::read(d.join(out)).unwrap());
    }
    assert!(images[0] == images[1], "the 8-wide BVH depends on the thread count");
    assert!(images[2] == images[3], "the kd-tree depends on the thread count");
    let o = raypipe(d, &["build", "--generate", "forest:trees=8", "--threads", "0", "-o", "x.rpsi"]);
    assert!(!o.status.success() && stderr(&o).contains("invalid value '0' for '--threads <N>'"), "{}", stderr(&o));
    assert!(!d.join("x.rpsi").exists());
}
