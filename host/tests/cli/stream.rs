//! `raypipe stream`.

use crate::common::*;

#[test]
fn stream_machine_tables_report_charts_and_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let o = raypipe(
        dir.path(),
        &["stream", "--size", "64x48", "--algo", "whitted", "--unroll", "traverse=4,intersect=2", "--charts", "charts"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    for needle in ["Table 2", "Table 3", "intersect", "grid_cells", "compute bound", "equals raypipe render's"] {
        assert!(
            out.contains(needle) || needle == "compute bound" && out.contains("bandwidth bound"),
            "{needle}: {out}"
        );
    }
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("raypipe-stream.json")).unwrap()).unwrap();
    assert_eq!(report["width"], 64);
    assert!(report["table2"]["traverse_passes"].as_u64().unwrap() > 0);
    assert!(report["passes"].as_array().unwrap().len() as u64 == report["table2"]["total_passes"].as_u64().unwrap());
    for name in [
        "fig7_instructions_by_kernel",
        "fig8_words_by_data_type",
        "fig9_texture_cache_bandwidth",
        "active_rays_per_pass",
    ] {
        for ext in ["svg", "png"] {
            let p = dir.path().join("charts").join(format!("{name}.{ext}"));
            assert!(std::fs::metadata(&p).map(|m| m.len() > 500).unwrap_or(false), "{}", p.display());
        }
    }
    // A cost file replaces raypipe's counts.
    std::fs::write(dir.path().join("paper.toml"), "[intersect]\nb_instructions = 41\nm = 11\n").unwrap();
    let o = raypipe(
        dir.path(),
        &["stream", "--size", "32x32", "--costs", "paper.toml", "--no-charts", "--arch", "branching"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    let line = out.lines().find(|l| l.starts_with("intersect ")).unwrap();
    assert!(line.split_whitespace().nth(1) == Some("41") && line.contains("11.00"), "{line}");
    std::fs::write(dir.path().join("bad.toml"), "[intersekt]\ninstructions = 1\n").unwrap();
    for (args, needle) in [
        (vec!["--oracle", "sometimes"], "oracle"),
        (vec!["--oracle", "delany:2"], "fraction"),
        (vec!["--unroll", "traverse=0"], "traverse"),
        (vec!["--cache", "64K,3,50"], "cache"),
        (vec!["--machine", "1e9"], "machine"),
        (vec!["--output-words", "6"], "output words"),
        (vec!["--isa", "vec3"], "vec3"),
        (vec!["--costs", "bad.toml"], "intersekt"),
        (vec!["--costs", "missing.toml"], "missing.toml"),
        (vec!["--arch", "branching", "--suppress"], "multipass"),
        (vec!["--accel", "bvh"], "uniform grid"),
    ] {
        let mut all = vec!["stream", "--size", "16x16", "--no-charts"];
        all.extend(args.iter());
        let o = raypipe(dir.path(), &all);
        let err = stderr(&o);
        assert!(!o.status.success() && err.contains(needle) && !err.contains("panicked"), "{args:?}: {err}");
    }
}
