//! `raypipe info` and lights on meshes and images.

use crate::common::*;
use std::path::Path;

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
