//! The AFF reader on a small scene that uses every command (fixtures/aff): what it
//! reads, how it moves at given times, and one-line errors for malformed files.

use std::path::Path;

use raypipe::input::aff::{load_aff, load_aff_text};

fn fixture() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures/aff/scene.aff")
}

#[test]
fn the_fixture_reads_as_written() {
    let aff = load_aff(&fixture()).expect("the fixture reads");
    let s = &aff.scene;
    // Floor 2, cone 48, sphere 528, patch 1, textured triangle 1; the box 2; one
    // animated triangle.
    let counts: Vec<usize> = s.bottoms.iter().map(|b| b.triangles.len()).collect();
    assert_eq!(counts, vec![580, 2, 1]);
    assert_eq!(aff.deforming, vec![false, false, true]);
    assert_eq!(s.instances.len(), 3);
    assert_eq!(aff.frame_count(), 5);
    assert_eq!((aff.time(0), aff.time(4)), (0.0, 2.0));
    assert_eq!(s.lights.len(), 2);
    // The box's shading data and texture came with it.
    assert!(!s.bottoms[1].shading.is_empty() && s.bottoms[1].textures.len() == 1);
    // The spinner: T(0, 0.5, 0) at t = 0 inside a static 30° turn about y; at t = 2
    // scaled 1.5, turned 180° more, moved to x = 1.
    let at = |t: f64, p: [f32; 3]| {
        let m = aff.instance_transform(1, t);
        let v = raypipe_core::math::affine::point(&m, glam::Vec3::from(p));
        [v.x, v.y, v.z]
    };
    let close = |a: [f32; 3], b: [f32; 3]| a.iter().zip(&b).all(|(x, y)| (x - y).abs() < 1e-5);
    assert!(close(at(0.0, [0.0; 3]), [0.0, 0.5, 0.0]), "{:?}", at(0.0, [0.0; 3]));
    let c30 = 30f32.to_radians().cos();
    let s30 = 30f32.to_radians().sin();
    // At t = 2: the point (1, 0, 0) scaled to 1.5, turned 180° to (−1.5, 0, 0), moved
    // to (−0.5, 0.5, 0), then the static 30° turn about y.
    assert!(close(at(2.0, [1.0, 0.0, 0.0]), [-0.5 * c30, 0.5, 0.5 * s30]), "{:?}", at(2.0, [1.0, 0.0, 0.0]));
    // The animated triangle halfway between its keys at t = 1.
    let d = aff.deformed(1.0);
    assert_eq!(d.len(), 1);
    assert!(close(d[0].1[0], [0.5, 2.0, 0.0]));
    // The camera follows its track.
    assert_eq!(aff.camera(0.0).eye, [0.0, 2.0, 8.0]);
    assert!(close(aff.camera(2.0).eye, [1.0, 2.0, 7.0]));
    assert_eq!((aff.camera(0.0).width, aff.camera(0.0).height), (64, 48));
}

#[test]
fn malformed_files_are_refused_with_the_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("a.aff"), "i 0 b.aff\n").unwrap();
    std::fs::write(d.join("b.aff"), "s 0 0 0 1\ni 0 a.aff\n").unwrap();
    std::fs::write(d.join("fake.ppm"), "P5 1 1 255\n\x00").unwrap();
    let view = "v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 40\nhither 1\nresolution 8 8\n";
    let cases: Vec<(String, &str)> = vec![
        (format!("{view}zap 1 2 3\n"), "scene.aff:8: unknown command 'zap'"),
        (format!("{view}i 0 nowhere.aff\n"), "include 'nowhere.aff' does not exist"),
        (format!("{view}i 0 a.aff\n"), "include cycle"),
        (format!("{view}s 0 0 0 1\nx m {{\ns 1 1 1 1\n}}\nk m {{\nrot 3\n0 0 1 0 0 0 0 0\n1 0 1 0 9 0 0 0\n2 0 1 0 9 0 0 0\n}}\n"), "rot needs at least 4 keys, has 3"),
        (format!("{view}s 0 0 nan 1\n"), "nan is not a finite number"),
        (format!("{view}s 0 0 zero 1\n"), "'zero' is not a number"),
        (format!("{view}s 0 0 inf 1\n"), "not a finite number"),
        (format!("{view}tt missing.ppm\n0 0 0 0 0\n1 0 0 1 0\n0 1 0 0 1\n"), "texture 'missing.ppm'"),
        (format!("{view}tt fake.ppm\n0 0 0 0 0\n1 0 0 1 0\n0 1 0 0 1\n"), "not a PPM file"),
        (format!("{view}xs 1 1 1 0 1 0 0 0 0 0 {{\ns 0 0 0 1\n"), "is not closed"),
        (format!("{view}s 0 0 0 1\n}}\n"), "closes no transform block"),
        (format!("{view}tpa 2\n1\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n0\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n"), "go backwards"),
        (format!("{view}p 4\n0 0 0\n1 0 0\n"), "more than the file holds"),
        ("s 0 0 0 1\n".to_string(), "has no view"),
        (format!("{view}xs 0 1 1 0 1 0 0 0 0 0 {{\ns 0 0 0 1\n}}\n"), "scales by zero"),
        (format!("{view}a 5 1 10\ns 0 0 0 1\n"), "is impossible"),
    ];
    for (text, needle) in cases {
        let err = match load_aff_text(&d.join("scene.aff"), &text) {
            Ok(_) => panic!("accepted: {text}"),
            Err(e) => e.to_string(),
        };
        assert!(err.contains(needle), "expected '{needle}' in: {err}");
        assert!(!err.contains('\n'), "one line: {err}");
    }
}

#[test]
fn keyframes_that_jump_back_are_read_as_bart_reads_them_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let text = "v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 40\nhither 1\nresolution 8 8\n\
                x m {\ns 0 0 0 1\n}\nk m {\ntransl 6\n0 0 0 0 0 0 0\n0 0 0 0 0 0 0\n1 1 0 0 0 0 0\n2 2 0 0 0 0 0\n1 5 0 0 0 0 0\n3 6 0 0 0 0 0\n}\n";
    let aff = load_aff_text(&dir.path().join("scene.aff"), text).expect("reads with a warning");
    assert!(aff.scene.warnings.iter().any(|w| w.contains("times go back from 2 to 1")), "{:?}", aff.scene.warnings);
    // Before the jump the track is as if the later keys were not there.
    let x = |t: f64| aff.instance_transform(0, t)[3];
    assert!((x(0.5) - 0.5).abs() < 0.2 && (x(1.0) - 1.0).abs() < 1e-6);
}
