//! `raypipe sweep` and `raypipe plot`.

use crate::common::*;
use std::path::{Path, PathBuf};

/// A small sweep: two axes crossed with two listed points, on the tetrahedron.
fn sweep_spec(dir: &Path) -> PathBuf {
    let tetra = fixtures().join("tetra.obj");
    write(
        dir,
        "spec.toml",
        &format!(
            "[fixed]\nscene = {:?}\nsize = \"24x16\"\n[grid]\n\"traversal.units\" = [1, 2]\npacket_size = [4, 16]\n\
             [[points]]\naccel = \"kd\"\n[[points]]\naccel = \"bvh4\"\n\"memory.model\" = \"dram\"\n",
            tetra.display().to_string()
        ),
    )
}

#[test]
fn sweep_points_are_stand_alone_runs_and_shards_merge_to_the_whole() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let spec = sweep_spec(d);
    std::fs::create_dir(d.join("reports")).unwrap();
    let o = raypipe(d, &["sweep", "spec.toml", "-o", "all", "--reports", "reports", "--jobs", "2"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let csv = std::fs::read_to_string(d.join("all.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 9, "{csv}");
    // Columns: parameters in spec order, then the verdict and the metrics.
    assert!(
        lines[0].starts_with("index,scene,size,traversal.units,packet_size,accel,memory.model,bottleneck,error,fps,")
    );
    // Point 7 = accel bvh4 on DRAM, units 2, packets of 16: the same report, byte for
    // byte, as the stand-alone command.
    assert_eq!(spec.parent(), Some(d));
    let tetra = fixtures().join("tetra.obj");
    let o = raypipe(
        d,
        &[
            "simulate",
            tetra.to_str().unwrap(),
            "--size",
            "24x16",
            "--set",
            "traversal.units=2",
            "--set",
            "packet_size=16",
            "--accel",
            "bvh4",
            "--set",
            "memory.model=\"dram\"",
            "--report",
            "alone.json",
            "-o",
            "alone.png",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(std::fs::read(d.join("alone.json")).unwrap(), std::fs::read(d.join("reports/point-7.json")).unwrap());
    assert!(lines[8].starts_with("7,"), "{}", lines[8]);
    // Shards (written in any order) merged = the single run, byte for byte.
    for i in 0..3 {
        let shard = format!("{i}/3");
        let out = format!("part{i}");
        let o = raypipe(d, &["sweep", "spec.toml", "--shard", &shard, "-o", &out]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let o = raypipe(d, &["sweep", "merge", "part2.jsonl", "part0.jsonl", "part1.jsonl", "-o", "merged"]);
    assert!(o.status.success(), "{}", stderr(&o));
    for ext in ["csv", "jsonl"] {
        let (a, b) = (d.join(format!("all.{ext}")), d.join(format!("merged.{ext}")));
        assert_eq!(std::fs::read(a).unwrap(), std::fs::read(b).unwrap(), "{ext}");
    }
    // Resuming recomputes nothing: no point runs (its report would be written again),
    // and the outputs are unchanged.
    std::fs::remove_dir_all(d.join("reports")).unwrap();
    std::fs::create_dir(d.join("reports")).unwrap();
    let o = raypipe(d, &["sweep", "spec.toml", "-o", "all", "--reports", "reports"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("8 already done, 0 to run"));
    assert!(only_files(&d.join("reports")).is_empty());
    assert_eq!(std::fs::read_to_string(d.join("all.csv")).unwrap(), csv);
    // A run stopped half-way resumes with the missing points only.
    let jsonl = std::fs::read_to_string(d.join("all.jsonl")).unwrap();
    let kept: Vec<&str> = jsonl.lines().take(5).collect();
    std::fs::write(d.join("all.jsonl"), format!("{}\n{{\"index\":5,\"poi", kept.join("\n"))).unwrap();
    let o = raypipe(d, &["sweep", "spec.toml", "-o", "all", "--reports", "reports"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("5 already done, 3 to run"),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    assert_eq!(only_files(&d.join("reports")), ["point-5.json", "point-6.json", "point-7.json"]);
    assert_eq!(std::fs::read_to_string(d.join("all.csv")).unwrap(), csv);
}

#[test]
fn sweep_rejects_bad_specs_before_running_anything() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cases: [(&str, &str); 7] = [
        ("", "the spec sets no parameter"),
        ("[grid]\n\"traversal.unitz\" = [1]\n", "no such parameter"),
        ("[grid]\n\"traversal.units\" = []\n", "non-empty list"),
        ("[fixed]\npacket_size = 3\n", "packet_size"),
        ("[fixed]\nscene = \"missing.obj\"\n", "no such file"),
        ("[fixed]\noutput = \"x.png\"\n", "cannot be a sweep parameter"),
        ("[grids]\n", "unknown section"),
    ];
    for (text, needle) in cases {
        write(d, "bad.toml", text);
        let o = raypipe(d, &["sweep", "bad.toml", "-o", "out"]);
        assert_one_line_error(&o, needle);
        assert!(!d.join("out.csv").exists() && !d.join("out.jsonl").exists(), "{text}");
    }
    let o = raypipe(d, &["sweep", "bad.toml", "--shard", "3/3"]);
    assert!(!o.status.success());
}

#[test]
fn plots_of_a_small_sweep_decode() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    sweep_spec(d);
    let o = raypipe(d, &["sweep", "spec.toml", "-o", "s"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let plots: [&[&str]; 4] = [
        &["--x", "traversal.units", "--y", "fps", "--series", "packet_size", "--where", "accel=kd", "-o", "line.png"],
        &[
            "--x",
            "traversal.units",
            "--y",
            "packet_size",
            "--value",
            "bytes_per_ray",
            "--where",
            "accel=bvh4",
            "-o",
            "heat.svg",
        ],
        &[
            "--x",
            "packet_size",
            "--stack",
            "stall.traversal",
            "--where",
            "accel=kd",
            "--where",
            "traversal.units=2",
            "-o",
            "bars.png",
        ],
        &[
            "--x",
            "traversal.units",
            "--stack",
            "bytes_per_ray",
            "--where",
            "accel=kd",
            "--where",
            "packet_size=16",
            "-o",
            "bytes.svg",
        ],
    ];
    for args in plots {
        let mut all = vec!["plot", "s.jsonl"];
        all.extend_from_slice(args);
        let o = raypipe(d, &all);
        assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    }
    for png in ["line.png", "bars.png"] {
        let (w, h, _) = decode(&d.join(png));
        assert!(w > 100 && h > 100, "{png}");
    }
    for svg in ["heat.svg", "bytes.svg"] {
        let text = std::fs::read_to_string(d.join(svg)).unwrap();
        let png = raypipe::output::chart_raster::to_png(&text).expect("the SVG parses and renders");
        assert!(png.starts_with(b"\x89PNG"), "{svg}");
    }
    // Rows the plot cannot tell apart are refused, naming what differs.
    let o = raypipe(d, &["plot", "s.jsonl", "--x", "traversal.units", "--y", "fps", "-o", "x.svg"]);
    assert_one_line_error(&o, "differ in packet_size");
    assert!(!d.join("x.svg").exists());
}

#[test]
fn shards_on_one_prefix_keep_each_others_rows_and_runs_do_not_overlap() {
    use std::os::unix::io::AsRawFd;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    sweep_spec(d);
    let o = raypipe(d, &["sweep", "spec.toml", "-o", "all"]);
    assert!(o.status.success(), "{}", stderr(&o));
    // Shard 0 then shard 1 on the same prefix: the second keeps the first's rows, and
    // the prefix ends up with the whole table.
    let mut stdout = String::new();
    for shard in ["0/2", "1/2"] {
        let o = raypipe(d, &["sweep", "spec.toml", "--shard", shard, "-o", "shared"]);
        assert!(o.status.success(), "{}", stderr(&o));
        stdout = String::from_utf8_lossy(&o.stdout).into_owned();
    }
    assert!(stdout.contains("(4 rows of other shards kept)"), "{stdout}");
    for ext in ["csv", "jsonl"] {
        let (a, b) = (d.join(format!("all.{ext}")), d.join(format!("shared.{ext}")));
        assert_eq!(std::fs::read(a).unwrap(), std::fs::read(b).unwrap(), "{ext}");
    }
    // Another spec's rows are not dropped quietly: refused, or replaced on --restart.
    write(d, "other.toml", &std::fs::read_to_string(d.join("spec.toml")).unwrap().replace("[1, 2]", "[1, 3]"));
    let o = raypipe(d, &["sweep", "other.toml", "-o", "shared"]);
    assert_one_line_error(&o, "rows are not points of this spec");
    assert_eq!(std::fs::read(d.join("all.jsonl")).unwrap(), std::fs::read(d.join("shared.jsonl")).unwrap());
    // While a run holds the journal, a second one is refused at once.
    let lock = std::fs::File::open(d.join("shared.jsonl.lock")).unwrap();
    // SAFETY: flock on an open descriptor.
    assert_eq!(unsafe { libc::flock(lock.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) }, 0);
    let o = raypipe(d, &["sweep", "spec.toml", "-o", "shared"]);
    assert_one_line_error(&o, "another sweep");
    drop(lock);
    let o = raypipe(d, &["sweep", "other.toml", "-o", "shared", "--restart"]);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn a_plot_of_more_series_than_a_chart_can_show_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "one.toml", "[fixed]\nsize = \"8x8\"\n");
    let o = raypipe(d, &["sweep", "one.toml", "-o", "one"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let row: serde_json::Value =
        serde_json::from_str(std::fs::read_to_string(d.join("one.jsonl")).unwrap().trim()).unwrap();
    let mut rows = String::new();
    for i in 0..2_000 {
        let mut r = row.clone();
        r["index"] = i.into();
        r["point"] = format!("seed={}, x={}", i % 1000, i / 1000).into();
        r["params"] = serde_json::json!({ "seed": i % 1000, "x": i / 1000 });
        rows.push_str(&format!("{r}\n"));
    }
    write(d, "many.jsonl", &rows);
    let o = raypipe(d, &["plot", "many.jsonl", "--x", "x", "--y", "fps", "--series", "seed", "-o", "p.svg"]);
    assert_one_line_error(&o, "1000 series (seed has that many values) is more than the 40");
    // Narrowed to 11 series (seeds 99 and 990-999), the same rows are drawn.
    let args =
        ["plot", "many.jsonl", "--x", "x", "--y", "fps", "--series", "seed", "--where", "seed=99*", "-o", "p.svg"];
    let o = raypipe(d, &args);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(std::fs::read_to_string(d.join("p.svg")).unwrap().contains("seed = 995"));
}

/// A point without the plotted metric (no node cache, no node hit rate) is left out
/// with a word, as is a log axis over zero; `--reports` makes its folder.
#[test]
fn plots_leave_out_points_without_the_metric_and_say_so() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let tetra = fixtures().join("tetra.obj");
    write(
        d,
        "cache.toml",
        &format!(
            "[fixed]\nscene = {:?}\nsize = \"16x16\"\naccel = \"bvh4\"\n[grid]\n\"cache.nodes.size_bytes\" = [0, 4096, 8192]\n",
            tetra.display().to_string()
        ),
    );
    let o = raypipe(d, &["sweep", "cache.toml", "-o", "c", "--reports", "new/reports"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(std::fs::read_dir(d.join("new/reports")).unwrap().count(), 3, "one report per point");
    let o = raypipe(
        d,
        &["plot", "c.jsonl", "--x", "cache.nodes.size_bytes", "--y", "hit_rate.nodes", "--log-x", "-o", "p.svg"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(err.contains("1 point without a value of \"hit_rate.nodes\" left out"), "{err}");
    assert!(!err.contains("--log-x"), "the points left have positive x: {err}");
    assert!(d.join("p.svg").exists());
    let o = raypipe(d, &["plot", "c.jsonl", "--x", "cache.nodes.size_bytes", "--y", "fps", "--log-x", "-o", "q.svg"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("--log-x needs positive numbers"), "{}", stderr(&o));
}
