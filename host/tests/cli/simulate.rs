//! `raypipe simulate`: presets, configurations, walkthroughs, waveforms and traces.

use crate::common::*;
use std::path::Path;

#[test]
fn simulate_without_arguments_matches_render_and_reports() {
    let dir = tempfile::tempdir().unwrap();
    let o = raypipe(dir.path(), &["simulate", "--report", "report.json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    for needle in ["cycles", "frames/s", "traversal0", "intersection0", "memory", "distinct bytes"] {
        assert!(out.contains(needle), "{needle} missing: {out}");
    }
    let o = raypipe(dir.path(), &["render"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(decode(&dir.path().join("raypipe-sim.png")), decode(&dir.path().join("raypipe.png")));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("report.json")).unwrap()).unwrap();
    assert_eq!(json["schema"], "raypipe-hw-report/2");
    // Run identity: the scene, its image's hash, the structure and the configuration.
    assert_eq!(json["run"]["scene"], "built-in Cornell box");
    assert_eq!(json["run"]["scene_hash"].as_str().unwrap().len(), 16);
    assert!(!json["run"]["structure"].as_str().unwrap().is_empty());
    assert!(json["config"]["memory"]["model"].is_string());
    assert!(!json["bottleneck"].as_str().unwrap().is_empty());
    for u in json["units"].as_array().unwrap() {
        let sum: u64 = u["stall_reasons"].as_object().unwrap().values().map(|v| v.as_u64().unwrap()).sum();
        assert_eq!(sum, u["stall_cycles"].as_u64().unwrap(), "{}", u["name"]);
    }
    assert!(json["cycles"].as_u64().unwrap() > 0);
    assert_eq!(json["conservation"]["rays_issued"], json["conservation"]["rays_retired"]);
    assert_eq!(json["conservation"]["bytes_requested"], json["conservation"]["bytes_delivered"]);
    for key in ["units", "fifos", "caches"] {
        assert!(!json[key].as_array().unwrap().is_empty(), "{key}");
    }
    assert!(json["memory"]["bytes"]["nodes"].as_u64().unwrap() > 0);
}

#[test]
fn simulate_presets_configs_and_overrides() {
    let dir = tempfile::tempdir().unwrap();
    let tetra = fixtures().join("tetra.obj");
    let tetra = tetra.to_str().unwrap();
    let o = raypipe(dir.path(), &["render", tetra, "--accel", "bvh", "--size", "40x30", "-o", "r.png"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let cfg = write(dir.path(), "chip.toml", "packet_size = 4\n[traversal]\nunits = 2\nthreads = 3\n");
    let cfg = cfg.to_str().unwrap();
    for extra in [
        &["--preset", "saarcor"][..],
        &["--preset", "minimal", "--set", "memory.latency=3"][..],
        &["--config", cfg, "--set", "cache.nodes.size_bytes=0"][..],
    ] {
        let mut args = vec!["simulate", tetra, "--accel", "bvh", "--size", "40x30", "-o", "s.png"];
        args.extend_from_slice(extra);
        let o = raypipe(dir.path(), &args);
        assert!(o.status.success(), "{extra:?}: {}", stderr(&o));
        assert_eq!(decode(&dir.path().join("s.png")), decode(&dir.path().join("r.png")), "{extra:?}");
    }
    // A preset brings its structure and says so; --accel overrides it, and says that.
    let o = raypipe(dir.path(), &["simulate", tetra, "--preset", "saarcor", "--size", "16x16", "-o", "k.png"]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("(kd ") && out.contains("the structure of preset saarcor"), "{out}");
    let o = raypipe(dir.path(), &["simulate", tetra, "--preset", "saarcor", "--accel", "grid", "--size", "16x16"]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("(grid ") && out.contains("from --accel (preset saarcor names \"kd\")"), "{out}");
    // A bare word is a string value.
    let o = raypipe(dir.path(), &["simulate", tetra, "--set", "memory.model=dram", "--size", "16x16", "-o", "d.png"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = raypipe(dir.path(), &["simulate", tetra, "--set", "structure=octree", "--size", "16x16"]);
    assert_one_line_error(&o, "structure must be one of");
}

#[test]
fn impossible_hardware_configurations() {
    let dir = tempfile::tempdir().unwrap();
    let typo = write(dir.path(), "typo.toml", "[traversal]\nthreds = 4\n");
    let zero = write(dir.path(), "zero.toml", "[fifo]\nleaves = 0\n");
    let broken = write(dir.path(), "broken.toml", "[traversal\n");
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["--config", typo.to_str().unwrap()], "threds"),
        (vec!["--config", zero.to_str().unwrap()], "fifo.leaves"),
        (vec!["--config", broken.to_str().unwrap()], "broken.toml"),
        (vec!["--config", "missing.toml"], "missing.toml"),
        (vec!["--preset", "nosuch"], "unknown preset"),
        (vec!["--set", "traversal.thread=2"], "no such parameter"),
        (vec!["--set", "traversal.threads"], "key=value"),
        (vec!["--set", "cache.triangles.size_bytes=8"], "smaller than one"),
        (vec!["--set", "packet_size=8"], "packet_size"),
        (vec!["--set", "traversal.threads=-1"], "traversal.threads"),
        (vec!["--set", "datapath=\"q3.3\""], "datapath"),
        // The default scene has a grid: no fixed-point box test for it.
        (vec!["--set", "datapath=\"q16.16\""], "for BVHs"),
        (vec!["--set", "datapath=\"q16.16\"", "--accel", "bvh", "--intersector", "wald"], "own triangle test"),
    ];
    for (args, needle) in cases {
        let mut all = vec!["simulate", "-o", "x.png", "--report", "x.json"];
        all.extend_from_slice(&args);
        let o = raypipe(dir.path(), &all);
        assert_one_line_error(&o, needle);
        assert!(!dir.path().join("x.png").exists() && !dir.path().join("x.json").exists(), "{args:?}");
    }
}

#[test]
fn walkthroughs_write_every_frame_on_the_host_and_the_model() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "walk.path", "size 24 16\nframes 3\nkey 278 273 -800 278 273 0\nkey 300 273 -700 278 273 0\n");
    let o = raypipe(d, &["render", "--camera-path", "walk.path", "-o", "host.png"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("3 frames in"));
    let o = raypipe(
        d,
        &["simulate", "--camera-path", "walk.path", "--warmup-frames", "1", "--interval", "500", "-o", "sim.png"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("steady state   2 frames after 1 warm-up"));
    for k in 0..3 {
        let (host, sim) = (d.join(format!("host-000{k}.png")), d.join(format!("sim-000{k}.png")));
        assert_eq!(decode(&host), decode(&sim), "frame {k}");
        assert_eq!(decode(&host).0, 24);
    }
    let frames = std::fs::read_to_string(d.join("raypipe-sim.frames.jsonl")).unwrap();
    let rows: Vec<serde_json::Value> = frames.lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    assert_eq!(rows.len(), 3);
    assert_eq!(rows.iter().map(|r| r["warmup"].as_bool().unwrap()).collect::<Vec<_>>(), [true, false, false]);
    // Interval rows for the measured frames only, each frame's summing to its cycles.
    let intervals = std::fs::read_to_string(d.join("raypipe-sim.intervals.jsonl")).unwrap();
    let rows: Vec<serde_json::Value> = intervals.lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    for k in [1u64, 2] {
        let sum: u64 = rows.iter().filter(|r| r["frame"] == k).map(|r| r["counters"]["cycles"].as_u64().unwrap()).sum();
        let cycles = serde_json::from_str::<serde_json::Value>(frames.lines().nth(k as usize).unwrap()).unwrap()
            ["cycles"]
            .as_u64()
            .unwrap();
        assert_eq!(sum, cycles, "frame {k}");
    }
    assert!(rows.iter().all(|r| r["frame"] != 0));
    // Bad paths and measures are one line of error.
    write(d, "bad.path", "frames 2\nkey 0 0 0 0 0\n");
    assert_one_line_error(&raypipe(d, &["simulate", "--camera-path", "bad.path"]), "bad.path:2: 'key' takes");
    assert_one_line_error(&raypipe(d, &["simulate", "--roi", "50..10"]), "empty");
    assert_one_line_error(&raypipe(d, &["simulate", "--orbit", "2", "--warmup-frames", "2"]), "only 2 frames");
    assert_one_line_error(&raypipe(d, &["simulate", "--interval", "0"]), "at least one cycle");
}

/// A waveform read back: its dotted name and its (time, value) changes.
type Wave = (String, Vec<(u64, u64)>);

/// Reads a VCD back: every variable, and the last timestamp.
fn read_vcd(path: &Path) -> (Vec<Wave>, u64) {
    use vcd::{Command as Vcd, IdCode, ScopeItem};
    let mut parser = vcd::Parser::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let header = parser.parse_header().unwrap();
    let mut vars: Vec<(IdCode, String)> = Vec::new();
    fn walk(items: &[ScopeItem], prefix: &str, vars: &mut Vec<(IdCode, String)>) {
        for item in items {
            match item {
                ScopeItem::Scope(s) => walk(&s.items, &format!("{prefix}{}.", s.identifier), vars),
                ScopeItem::Var(v) => vars.push((v.code, format!("{prefix}{}", v.reference))),
                _ => {}
            }
        }
    }
    walk(&header.items, "", &mut vars);
    let mut changes: Vec<Vec<(u64, u64)>> = vec![Vec::new(); vars.len()];
    let (mut t, mut end) = (0, 0);
    for cmd in parser {
        match cmd.unwrap() {
            Vcd::Timestamp(ts) => {
                t = ts;
                end = ts;
            }
            Vcd::ChangeVector(id, v) => {
                let k = vars.iter().position(|(c, _)| *c == id).unwrap();
                let value = v.iter().fold(0u64, |acc, b| acc * 2 + u64::from(b == vcd::Value::V1));
                changes[k].push((t, value));
            }
            Vcd::ChangeScalar(id, v) => {
                let k = vars.iter().position(|(c, _)| *c == id).unwrap();
                changes[k].push((t, u64::from(v == vcd::Value::V1)));
            }
            _ => {}
        }
    }
    (vars.into_iter().map(|(_, n)| n).zip(changes).collect(), end)
}

#[test]
fn waveforms_and_traces_observe_without_changing_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let base = ["simulate", "--size", "32x24", "--algo", "whitted", "--set", "memory.model=\"dram\"", "-o", "x.png"];
    let o = raypipe(d, &[&base[..], &["--report", "plain.json"]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let o = raypipe(d, &[&base[..], &["--report", "watched.json", "--vcd", "w.vcd", "--trace", "t.json"]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let plain = std::fs::read_to_string(d.join("plain.json")).unwrap();
    assert_eq!(plain, std::fs::read_to_string(d.join("watched.json")).unwrap(), "tracing changed the report");
    let report: serde_json::Value = serde_json::from_str(&plain).unwrap();
    // The VCD parses, in picoseconds at the clock's period; each FIFO's occupancy
    // averaged over time is the report's mean.
    let text = std::fs::read_to_string(d.join("w.vcd")).unwrap();
    assert!(text.contains("$timescale 1 ps $end"), "true time: {}", &text[..300.min(text.len())]);
    let period = (1e6 / report["config"]["clock_mhz"].as_f64().unwrap()).round() as u64;
    let (signals, end) = read_vcd(&d.join("w.vcd"));
    assert_eq!(end % period, 0, "every change on a clock edge ({period} ps)");
    let cycles = |t: u64| t / period;
    let signals: Vec<Wave> =
        signals.into_iter().map(|(n, c)| (n, c.into_iter().map(|(t, v)| (cycles(t), v)).collect())).collect();
    let end = cycles(end);
    // GTKWave's save file groups the signals and decodes the activities.
    let save = std::fs::read_to_string(d.join("w.gtkw")).unwrap();
    assert!(save.contains("[dumpfile]") && save.contains("-traversal0") && save.contains("activity.txt"), "{save}");
    let filter = std::fs::read_to_string(d.join("w.activity.txt")).unwrap();
    assert!(filter.contains("0 idle") && filter.contains("1 busy") && filter.contains("node_data"), "{filter}");
    let fifos = report["fifos"].as_array().unwrap();
    assert_eq!(signals.iter().filter(|(n, _)| n.ends_with(".occupancy")).count(), fifos.len());
    for f in fifos {
        let name = format!("raypipe.fifos.{}.occupancy", f["name"].as_str().unwrap());
        let (_, changes) = signals.iter().find(|(n, _)| *n == name).expect(&name);
        let mut area = 0u64;
        for (k, (t, v)) in changes.iter().enumerate() {
            let next = changes.get(k + 1).map_or(end, |c| c.0);
            area += v * (next - t);
        }
        let ticked: u64 = f["occupancy"].as_array().unwrap().iter().map(|c| c.as_u64().unwrap()).sum();
        assert_eq!(end, ticked, "the VCD ends where the units stopped ticking");
        let mean = f["mean_occupancy"].as_f64().unwrap();
        assert!((area as f64 / end as f64 - mean).abs() < 1e-9, "{name}: {} vs {mean}", area as f64 / end as f64);
    }
    for n in [
        "raypipe.traversal0.activity",
        "raypipe.traversal0.threads.fetching",
        "raypipe.memory.queue",
        "raypipe.memory.requests",
    ] {
        assert!(signals.iter().any(|(s, _)| s == n), "{n}");
    }
    // The trace: valid JSON, one begin and one end per packet, begin first.
    let trace: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(d.join("t.json")).unwrap()).unwrap();
    let events = trace["traceEvents"].as_array().unwrap();
    let mut packets: std::collections::BTreeMap<String, (u32, u32, u64, u64)> = Default::default();
    for e in events.iter().filter(|e| e["name"].as_str().is_some_and(|n| n.starts_with("packet "))) {
        let p = packets.entry(e["id"].as_str().unwrap().to_string()).or_default();
        match e["ph"].as_str().unwrap() {
            "b" => (p.0, p.2) = (p.0 + 1, e["ts"].as_u64().unwrap()),
            "e" => (p.1, p.3) = (p.1 + 1, e["ts"].as_u64().unwrap()),
            ph => panic!("{ph}"),
        }
    }
    let primary = (32 / 4) * (24 / 4);
    assert!(packets.len() > primary, "primary and secondary packets: {}", packets.len());
    assert!(packets.values().all(|&(b, e, t0, t1)| b == 1 && e == 1 && t0 <= t1));
    let memory = events.iter().filter(|e| e["cat"] == "memory").count() as u64;
    assert_eq!(
        memory,
        report["memory"]["requests"].as_u64().unwrap() + report["memory"]["l2"]["hits"].as_u64().unwrap()
    );
    // No two memory slices overlap on a track (Perfetto's importer requires it).
    let mut tracks: std::collections::BTreeMap<u64, Vec<(u64, u64)>> = Default::default();
    for e in events.iter().filter(|e| e["cat"] == "memory") {
        let (ts, dur) = (e["ts"].as_u64().unwrap(), e["dur"].as_u64().unwrap());
        tracks.entry(e["tid"].as_u64().unwrap()).or_default().push((ts, ts + dur));
    }
    assert!(tracks.len() > 1, "outstanding requests spread over tracks");
    for (tid, mut slices) in tracks {
        slices.sort();
        assert!(slices.windows(2).all(|w| w[0].1 <= w[1].0), "track {tid} overlaps");
    }
    // A trace window keeps only what overlaps it.
    let o = raypipe(d, &[&base[..], &["--trace", "tw.json", "--trace-window", "100..300"]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let tw: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(d.join("tw.json")).unwrap()).unwrap();
    let tw = tw["traceEvents"].as_array().unwrap();
    assert!(tw.len() < events.len());
    for e in tw.iter().filter(|e| e["cat"] == "memory") {
        let (ts, dur) = (e["ts"].as_u64().unwrap(), e["dur"].as_u64().unwrap());
        assert!(ts < 300 && ts + dur > 100, "{e}");
    }
    // A window and a unit filter narrow the VCD; an empty filter is an error.
    let o =
        raypipe(d, &[&base[..], &["--vcd", "n.vcd", "--vcd-window", "100..200", "--vcd-units", "traversal1"]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let (narrow, end) = read_vcd(&d.join("n.vcd"));
    assert!(narrow.iter().all(|(n, _)| n.starts_with("raypipe.traversal1.")) && !narrow.is_empty());
    let window = 100 * period..200 * period;
    assert!(narrow.iter().all(|(_, c)| c.iter().all(|(t, _)| window.contains(t))) && end <= 200 * period);
    assert_one_line_error(
        &raypipe(d, &[&base[..], &["--vcd", "z.vcd", "--vcd-units", "nothing"]].concat()),
        "no signal",
    );
    assert!(!d.join("z.vcd").exists());
}

#[test]
fn the_memory_trace_lists_every_request_the_memory_served() {
    let dir = tempfile::tempdir().unwrap();
    let args = ["simulate", "--size", "16x16", "--report", "r.json", "--memory-trace", "m.txt"];
    let o = raypipe(dir.path(), &args);
    assert!(o.status.success(), "{}", stderr(&o));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("r.json")).unwrap()).unwrap();
    let text = std::fs::read_to_string(dir.path().join("m.txt")).unwrap();
    let lines: Vec<&str> = text.lines().filter(|l| !l.starts_with('#')).collect();
    assert_eq!(lines.len() as u64, json["memory"]["requests"].as_u64().unwrap());
    // The requests' bytes are the memory's (before rounding to bursts): all requested.
    let bytes: u64 = lines.iter().map(|l| l.split(' ').nth(2).unwrap().parse::<u64>().unwrap()).sum();
    assert_eq!(bytes, json["conservation"]["bytes_requested"].as_u64().unwrap());
    assert!(lines.iter().any(|l| l.ends_with(" W")) && lines.iter().any(|l| l.ends_with(" R")));
    // The report's bounds: the achieved cycles are at least the largest.
    assert!(json["bounds"]["achieved_over_largest"].as_f64().unwrap() >= 1.0);
    // Without the dramsim3 feature, DRAMsim3 is refused in one line.
    if !cfg!(feature = "dramsim3") {
        let o = raypipe(dir.path(), &["simulate", "--size", "8x8", "--set", "memory.model=dramsim3"]);
        assert!(!o.status.success());
        assert_eq!(stderr(&o).trim().lines().count(), 1, "{}", stderr(&o));
        assert!(stderr(&o).contains("dramsim3 feature"), "{}", stderr(&o));
    }
}
