//! `raypipe stats` and `raypipe bench`, and the cost images.

use crate::common::*;

#[test]
fn stats_and_bench_report_their_figures() {
    let dir = tempfile::tempdir().unwrap();
    let o = raypipe(dir.path(), &["stats", "--size", "64x64"]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", stderr(&o));
    for key in ["rays that hit", "nodes visited per ray", "triangles tested per ray", "list entries read"] {
        assert!(out.contains(key), "{out}");
    }
    let o = raypipe(dir.path(), &["bench", "--size", "32x32", "--runs", "1"]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.contains("Mrays/s") && out.contains("built-in Cornell box"), "{out}");
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
