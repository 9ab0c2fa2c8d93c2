//! `raypipe render --ray-log`: every ray a frame traced, by query, for other tracers to
//! be timed on.

use crate::common::*;

/// The numbers in `rays    N traced (E eye, S secondary)` and `ray log  E eye, B
/// secondary, S shadow rays`.
fn numbers(out: &str, prefix: &str) -> Vec<u64> {
    let line = out.lines().find(|l| l.starts_with(prefix)).unwrap_or_else(|| panic!("no '{prefix}' line in {out}"));
    line.split(|c: char| !c.is_ascii_digit()).filter(|w| !w.is_empty()).map(|w| w.parse().unwrap()).collect()
}

/// Rows of an (N, 8) float32 .npy array.
fn rows(path: &std::path::Path) -> usize {
    let bytes = std::fs::read(path).unwrap();
    let header_len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    (bytes.len() - 10 - header_len) / 32
}

#[test]
fn a_path_traced_frame_logs_exactly_the_rays_it_traced_for_any_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut logs = Vec::new();
    for threads in ["1", "3"] {
        let log = format!("log{threads}");
        let obj = fixtures().join("cornell_box.obj");
        let obj = obj.to_str().unwrap();
        let args = ["render", obj, "--algo", "path", "--size", "40x30", "--samples", "2", "--threads", threads];
        let o = raypipe(d, &[&args[..], &["--ray-log", &log, "-o", "f.png"]].concat());
        assert!(o.status.success(), "{}", stderr(&o));
        let out = String::from_utf8_lossy(&o.stdout).into_owned();
        let (traced, logged) = (numbers(&out, "rays "), numbers(&out, "ray log "));
        // total, eye, secondary (and the Mrays/s figure after them)
        let (eye, secondary) = (traced[1], traced[2]);
        assert_eq!(logged[0], eye, "{out}");
        assert_eq!(logged[1] + logged[2], secondary, "{out}");
        assert!(logged[1] > 0 && logged[2] > 0, "bounces and shadow rays: {out}");
        let files = ["eye.npy", "secondary.npy", "shadow.npy"];
        for (file, n) in files.iter().zip(&logged) {
            assert_eq!(rows(&d.join(&log).join(file)) as u64, *n, "{file}");
        }
        logs.push(files.map(|f| std::fs::read(d.join(&log).join(f)).unwrap()));
    }
    // Tile order, not the order threads finished in.
    assert!(logs[0] == logs[1], "the log depends on the thread count");
    // The logged rays are `trace` input, every one of them a ray.
    let obj = fixtures().join("cornell_box.obj");
    let o =
        raypipe(d, &["trace", obj.to_str().unwrap(), "--rays", "log1/shadow.npy", "--query", "any", "--hits", "h.npy"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout).into_owned();
    let shadow = rows(&d.join("log1/shadow.npy"));
    assert!(out.starts_with(&format!("traced {shadow} rays (any-hit query)")) && !out.contains("no ray"), "{out}");
}

#[test]
fn a_ray_log_of_many_frames_or_ranks_is_refused_in_one_line_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for (extra, what) in [(&["--orbit", "3"][..], "a walkthrough"), (&["--mpi"][..], "--mpi")] {
        let o = raypipe(d, &[&["render", "--size", "16x16", "--ray-log", "log", "-o", "f.png"][..], extra].concat());
        assert_one_line_error(
            &o,
            &format!("--ray-log log: logs one frame of a flat scene on this machine, not {what}"),
        );
        assert!(only_files(d).is_empty(), "{:?}", only_files(d));
    }
}
