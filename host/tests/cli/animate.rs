//! `raypipe animate` on the AFF fixture: frames in order with their times, the same
//! frames whatever the update, and bad input refused with one line.

use crate::common::*;

#[test]
fn every_update_renders_the_same_frames() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = fixtures().join("aff/scene.aff");
    let scene = scene.to_str().unwrap();
    let mut first: Option<Vec<(u32, u32, Vec<u8>)>> = None;
    for update in ["refit", "rebuild", "full", "auto", "parker", "reinhard"] {
        let out = d.join(update);
        let o = raypipe(
            d,
            &[
                "animate",
                scene,
                "--update",
                update,
                "--algo",
                "whitted",
                "--frames",
                "1..4",
                "-o",
                out.to_str().unwrap(),
                "--times",
                "t.csv",
            ],
        );
        assert!(o.status.success(), "{update}: {}", stderr(&o));
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(text.contains("frames   3: total"), "{text}");
        assert!(text.contains(&format!("update   {update}")), "{text}");
        let frames: Vec<_> = (1..4).map(|k| decode(&out.join(format!("frame-{k:04}.png")))).collect();
        assert!(frames.iter().all(|f| (f.0, f.1) == (64, 48)));
        assert_eq!(only_files(&out).len(), 3);
        let csv = std::fs::read_to_string(d.join("t.csv")).unwrap();
        assert_eq!(csv.lines().count(), 4, "{csv}");
        assert!(csv.lines().nth(1).unwrap().starts_with("1,0.5,"), "{csv}");
        match &first {
            None => first = Some(frames),
            Some(f) => assert!(*f == frames, "{update} renders other frames"),
        }
    }
    // The frames move: the spinner and the animated triangle change the picture.
    let f = first.unwrap();
    assert_ne!(f[0].2, f[2].2);
}

#[test]
fn bad_animations_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = fixtures().join("aff/scene.aff");
    let scene = scene.to_str().unwrap();
    let o = raypipe(d, &["animate", "missing.aff", "-o", "out"]);
    assert_one_line_error(&o, "missing.aff");
    let o = raypipe(d, &["animate", scene, "--frames", "3..9", "-o", "out"]);
    assert_one_line_error(&o, "frames 0..5");
    let o = raypipe(d, &["animate", scene, "--auto-threshold", "0.5", "-o", "out"]);
    assert_one_line_error(&o, "--auto-threshold");
    let o = raypipe(d, &["animate", scene, "--algo", "path", "-o", "out"]);
    assert_one_line_error(&o, "--algo cast or whitted");
    write(d, "bad.aff", "v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 40\nhither 1\nresolution 8 8\nsphere 0 0 0 1\n");
    let o = raypipe(d, &["animate", "bad.aff", "-o", "out"]);
    assert_one_line_error(&o, "bad.aff:8: unknown command 'sphere'");
    assert_eq!(only_files(d), ["bad.aff"]);
}
