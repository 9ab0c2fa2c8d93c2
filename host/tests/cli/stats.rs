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

#[test]
fn stats_counts_a_ray_batch() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let o = raypipe(d, &["rays", "-o", "rays.npy", "--size", "32x24"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut shares = Vec::new();
    for query in ["closest", "any"] {
        let o = raypipe(d, &["stats", "--rays", "rays.npy", "--query", query]);
        assert!(o.status.success(), "{}", stderr(&o));
        let out = String::from_utf8_lossy(&o.stdout);
        assert!(out.contains("768 from rays.npy"), "{out}");
        for key in ["nodes visited per ray", "triangles tested per ray", "reads per ray", "bytes read per ray"] {
            assert!(out.contains(key), "{out}");
        }
        let what = if query == "any" { "rays blocked" } else { "rays that hit" };
        let line = out.lines().find(|l| l.starts_with(what)).unwrap_or_else(|| panic!("{out}"));
        shares.push(line.split_whitespace().last().unwrap_or_default().to_string());
    }
    // A ray is blocked exactly when it hits; the open box lets some eye rays out.
    assert_eq!(shares[0], shares[1]);
    assert!(shares[0] != "0.00%" && shares[0] != "100.00%", "{shares:?}");
    assert_one_line_error(&raypipe(d, &["stats", "--rays", "missing.npy"]), "missing.npy");
    std::fs::write(d.join("bad.npy"), b"\x93NUMPY not really").unwrap();
    assert_one_line_error(&raypipe(d, &["stats", "--rays", "bad.npy"]), "bad.npy");
}
