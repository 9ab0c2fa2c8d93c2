//! `raypipe fixed-point`.

use crate::common::*;

/// `raypipe fixed-point` on the built-in Cornell box: Q16.16 and Q12.12 agree with f32 on
/// (nearly) every ray; a format the scene does not fit is flagged and disagrees; bad
/// choices are one-line errors. And `simulate` with a fixed-point datapath renders.
#[test]
fn fixed_point_report_and_simulation() {
    let dir = tempfile::tempdir().unwrap();
    let o = raypipe(dir.path(), &["fixed-point", "--size", "48x48", "--datapath", "q16.16,q12.12,q8.16"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    let row = |kind: &str, d: &str| -> Vec<String> {
        let line = out
            .lines()
            .find(|l| l.contains(kind) && l.contains(&format!(" {d} ")))
            .unwrap_or_else(|| panic!("{d} {kind}: {out}"));
        line.split_whitespace().map(str::to_string).collect()
    };
    for d in ["q16.16", "q12.12"] {
        for kind in ["primary", "bounce"] {
            let r = row(kind, d);
            // "built-in Cornell box" is three words: then kind, datapath, fits, rays, agree%.
            assert_eq!(r[5], "yes", "{r:?}");
            let rays: u64 = r[6].parse().unwrap();
            let agree: f64 = r[7].parse().unwrap();
            assert!(rays > 1000 && agree >= 99.9, "{d} {kind}: {r:?}");
        }
    }
    let r = row("primary", "q8.16");
    assert_eq!(r[5], "NO", "{r:?}");
    assert!(r[7].parse::<f64>().unwrap() < 50.0, "{r:?}");
    assert!(stderr(&o).contains("do not fit q8.16"), "{}", stderr(&o));
    for (args, needle) in [
        (vec!["--datapath", "f32"], "fixed-point formats"),
        (vec!["--datapath", "q3.3"], "q3.3"),
        (vec!["--accel", "grid"], "for BVHs"),
        (vec!["--accel", "kd"], "for BVHs"),
    ] {
        let mut all = vec!["fixed-point", "--size", "8x8"];
        all.extend_from_slice(&args);
        let o = raypipe(dir.path(), &all);
        assert!(!o.status.success() && stderr(&o).contains(needle), "{args:?}: {}", stderr(&o));
        assert!(!stderr(&o).contains("panicked"));
    }
    let o = raypipe(
        dir.path(),
        &[
            "simulate",
            "--accel",
            "bvh4",
            "--size",
            "40x30",
            "--set",
            "datapath=\"q16.16\"",
            "-o",
            "s.png",
            "--report",
            "s.json",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let report = std::fs::read_to_string(dir.path().join("s.json")).unwrap();
    assert!(report.contains("\"datapath\": \"q16.16\"") && report.contains("fixed-watertight q16.16"), "{report}");
}
