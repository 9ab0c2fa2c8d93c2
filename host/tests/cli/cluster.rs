//! `raypipe cluster`: a recording replayed on modelled clusters; a recording that is
//! missing, malformed or impossible is one line of error.

use crate::common::*;

const RUN: &str = r#"{"identity":"t","workers":1,"host_threads":2,"hosts":1,"width":32,"height":16,"tile":16,"in_flight":4,"batch":2,"frame_seconds":[0.2],"master_seconds_per_tile":0.0,"bricks":[[1000,4000]]}"#;

fn tile(t: u32) -> String {
    format!(r#"{{"frame":0,"tile":{t},"rank":1,"seconds":0.1,"waited":0.0,"bytes":3100,"bricks":[0]}}"#)
}

#[test]
fn a_recording_is_replayed_for_every_worker_count_asked() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "r.jsonl", &format!("{RUN}\n{}\n{}\n", tile(0), tile(1)));
    let o = raypipe(d, &["cluster", "r.jsonl", "--workers", "1,2,7", "--served", "--check", "r.jsonl"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    // Two tiles of 0.1 s: one worker takes 0.2 s a frame, two (or more) 0.1 s.
    let rate = |n: &str| -> f64 {
        let row = out.lines().find(|l| l.split_whitespace().next() == Some(n)).unwrap_or_else(|| panic!("{out}"));
        row.split_whitespace().nth(2).unwrap().parse().unwrap()
    };
    assert!((rate("1") - 5.0).abs() < 0.2 && (rate("2") - 10.0).abs() < 0.5 && (rate("7") - 10.0).abs() < 0.5, "{out}");
    assert!(out.contains("check    1 worker on 1 host: measured 5.00 frames/s"), "{out}");
}

#[test]
fn bad_recordings_are_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "empty.jsonl", "");
    write(d, "short.jsonl", &format!("{RUN}\n{}\n", tile(0)));
    write(d, "nan.jsonl", &format!("{}\n{}\n{}\n", RUN.replace("0.2]", "-1]"), tile(0), tile(1)));
    for (file, says) in [
        ("missing.jsonl", "missing.jsonl"),
        ("empty.jsonl", "empty"),
        ("short.jsonl", "1 tiles, not 1 frames of 2"),
        ("nan.jsonl", "negative"),
    ] {
        let o = raypipe(d, &["cluster", file]);
        assert!(!o.status.success(), "{file}");
        let err = stderr(&o);
        assert!(err.lines().count() == 1 && err.contains(says), "{file}: {err}");
    }
    let o = raypipe(d, &["cluster", "short.jsonl", "--client-link", "fast"]);
    assert!(!o.status.success() && stderr(&o).contains("not a rate"), "{}", stderr(&o));
}
