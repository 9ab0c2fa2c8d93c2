//! The chip on two-level scenes from the command line: `simulate` of a scene file of
//! instances draws the host's image with transformation units in its report and
//! waveforms; `simulate --animate` runs the AFF fixture's frames through the chip, each
//! frame the host's `animate` frame bit for bit, with the host's update time beside the
//! chip's cycles; what `--animate` cannot do is refused with one line.

use crate::common::*;

/// Two tetrahedra placed by instances, one scaled and turned, one red.
fn instances(d: &std::path::Path) {
    let t = fixtures().join("tetra.obj");
    let t = t.display();
    let text = format!(
        "[camera]\neye = [0, 4, 9]\nlook_at = [0, 0.5, 0]\nfov = 50\nsize = [48, 32]\n\n\
         [materials.red]\ndiffuse = [0.9, 0.1, 0.1]\n\n[[light]]\nkind = \"point\"\nposition = [2, 8, 6]\n\n\
         [[instance]]\nfile = \"{t}\"\ntranslate = [-2, 0, 0]\nrotate = [0, 30, 0]\n\n\
         [[instance]]\nfile = \"{t}\"\ntranslate = [2, 0.5, -1]\nscale = [1, 1.5, 0.8]\nmaterial = \"red\"\n"
    );
    write(d, "inst.toml", &text);
}

#[test]
fn a_scene_of_instances_simulates_to_the_host_image() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    instances(d);
    for (accel, algo) in [("bvh", "cast"), ("grid", "whitted"), ("kd", "whitted")] {
        let o = raypipe(d, &["render", "inst.toml", "--accel", accel, "--algo", algo, "-o", "host.png"]);
        assert!(o.status.success(), "{}", stderr(&o));
        let o = raypipe(
            d,
            &["simulate", "inst.toml", "--accel", accel, "--algo", algo, "-o", "chip.png", "--vcd", "w.vcd"],
        );
        assert!(o.status.success(), "{accel} {algo}: {}", stderr(&o));
        assert!(decode(&d.join("chip.png")) == decode(&d.join("host.png")), "{accel} {algo}: the images differ");
        let report: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(d.join("raypipe-sim.json")).unwrap()).unwrap();
        let units = report["units"].as_array().unwrap();
        let rays: u64 = units.iter().filter_map(|u| u["transform"]["rays"].as_u64()).sum();
        assert!(rays > 0, "{accel} {algo}: no ray transformed");
        let transform = |u: &&serde_json::Value| u["name"].as_str().unwrap().starts_with("transform");
        assert_eq!(units.iter().filter(transform).count(), 4, "{accel} {algo}: one per traversal unit");
        assert!(units.iter().filter(transform).any(|u| u["busy_cycles"].as_u64().unwrap() > 0));
        let vcd = std::fs::read_to_string(d.join("w.vcd")).unwrap();
        let scope = vcd.find("$scope module transform0").expect("the transformation unit's signals");
        assert!(vcd[scope..].lines().nth(1).unwrap().contains(" activity "), "{accel} {algo}");
        assert!(vcd.contains(" transforming "), "{accel} {algo}: threads by state");
    }
}

#[test]
fn animated_frames_on_the_chip_are_the_hosts() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = fixtures().join("aff/scene.aff");
    let scene = scene.to_str().unwrap();
    for (algo, update) in [("cast", "refit"), ("whitted", "rebuild"), ("whitted", "reinhard")] {
        let o = raypipe(d, &["animate", scene, "--algo", algo, "--update", update, "--frames", "0..3", "-o", "host"]);
        assert!(o.status.success(), "{}", stderr(&o));
        let args = ["simulate", scene, "--animate", "0..3", "--algo", algo, "--update", update, "-o", "chip/f.png"];
        std::fs::create_dir_all(d.join("chip")).unwrap();
        let o = raypipe(d, &[&args[..], &["--preset", "saarcor", "--frames", "frames.jsonl"]].concat());
        assert!(o.status.success(), "{algo}: {}", stderr(&o));
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(text.contains("host update ms") && text.contains("total    chip"), "{text}");
        for k in 0..3 {
            let host = decode(&d.join(format!("host/frame-{k:04}.png")));
            let chip = decode(&d.join(format!("chip/f-{k:04}.png")));
            assert!(host == chip, "{algo} frame {k}: the chip's image is not the host's");
        }
        let lines = std::fs::read_to_string(d.join("frames.jsonl")).unwrap();
        let rows: Vec<serde_json::Value> = lines.lines().map(|l| serde_json::from_str(l).unwrap()).collect();
        assert_eq!(rows.len(), 3);
        for (k, r) in rows.iter().enumerate() {
            assert_eq!(r["frame"].as_u64(), Some(k as u64));
            assert!(r["cycles"].as_u64().unwrap() > 0 && r["host_update_ms"].as_f64().unwrap() >= 0.0, "{r}");
        }
    }
}

#[test]
fn what_animate_cannot_do_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = fixtures().join("aff/scene.aff");
    let scene = scene.to_str().unwrap();
    let cases: [(&[&str], &str); 5] = [
        (&["simulate", "missing.aff", "--animate"], "missing.aff"),
        (&["simulate", scene, "--animate", "2..99"], "--animate 2..99"),
        (&["simulate", scene, "--animate", "0..2", "--vcd", "w.vcd"], "name it (--animate K)"),
        (&["simulate", scene, "--animate", "--algo", "path"], "--algo path"),
        (&["simulate", scene, "--animate", "--eye", "1,2,3"], "camera track"),
    ];
    for (args, needle) in cases {
        let o = raypipe(d, args);
        assert_one_line_error(&o, needle);
        assert!(only_files(d).is_empty(), "{args:?} wrote {:?}", only_files(d));
    }
}
