//! `raypipe report diff`.

use crate::common::*;

#[test]
fn report_diff_names_the_changed_keys_and_every_ratio() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for (units, name) in [("1", "a"), ("2", "b")] {
        let report = format!("{name}.json");
        let set = format!("traversal.units={units}");
        let o = raypipe(d, &["simulate", "--size", "24x24", "--set", &set, "--report", &report, "-o", "x.png"]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let o = raypipe(d, &["report", "diff", "a.json", "b.json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout).into_owned();
    let setting = out.lines().find(|l| l.trim_start().starts_with("config.traversal.units")).expect(&out);
    assert!(setting.ends_with("1 -> 2"), "{setting}");
    assert_eq!(out.matches("  config.").count(), 1, "only one configuration key differs: {out}");
    assert!(out.contains("only in B: units.traversal1, units.intersection1"), "{out}");
    // The cycles line carries both values and their ratio.
    let cycles = |f: &str| -> f64 {
        let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(d.join(f)).unwrap()).unwrap();
        v["cycles"].as_f64().unwrap()
    };
    let (a, b) = (cycles("a.json"), cycles("b.json"));
    let line = out.lines().find(|l| l.trim_start().starts_with("cycles ")).expect(&out);
    let cols: Vec<&str> = line.split_whitespace().collect();
    assert_eq!(cols, ["cycles", &format!("{a}"), &format!("{b}"), &format!("{:.3}", b / a)]);
    // A file that is not a report is one line of error.
    write(d, "bad.json", "[1, 2]");
    assert_one_line_error(&raypipe(d, &["report", "diff", "a.json", "bad.json"]), "bad.json: not a JSON report");
    // JSON that is no simulate report (another tool's, or an older schema).
    write(d, "other.json", "{\"a\": 1}");
    assert_one_line_error(
        &raypipe(d, &["report", "diff", "a.json", "other.json"]),
        "other.json: not a simulate report",
    );
    write(d, "old.json", "{\"schema\": \"raypipe-hw-report/1\"}");
    assert_one_line_error(
        &raypipe(d, &["report", "diff", "old.json", "a.json"]),
        "old.json: a report of schema raypipe-hw-report/1",
    );
    assert_one_line_error(&raypipe(d, &["report", "diff", "a.json", "missing.json"]), "missing.json");
}
