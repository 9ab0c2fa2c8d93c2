//! A run's trace in the Chrome trace-event format (JSON), which Perfetto and
//! chrome://tracing open: each packet is an async slice from its issue to the end of its
//! shading, with nested slices for its time in traversal, at the intersection unit and
//! in shading; each memory request is a complete slice from the request to its data, on
//! one of its port's tracks — as many tracks as the port ever had requests outstanding
//! at once, so that slices never overlap on a track (Perfetto's importer requires
//! complete slices on a track to nest). One microsecond on the timeline is one clock
//! cycle; a window keeps the packets and requests that overlap it.

use std::collections::BTreeMap;

use raypipe_hw::observe::waves::{TraceEvent, TraceLog};
use serde_json::{json, Value};

/// One memory request, before it is given a track.
struct Request<'a> {
    port: &'a str,
    issued: u64,
    ready: u64,
    name: String,
    bytes: u32,
    frame: u32,
}

/// The trace as a trace-event JSON document, of the cycles in `window` (all if `None`).
pub fn to_json(log: &TraceLog, clock_mhz: f64, window: Option<(u64, u64)>) -> Value {
    let (from, to) = window.unwrap_or((0, u64::MAX));
    let overlaps = |a: u64, b: u64| a < to && b.max(a + 1) > from;
    let mut events: Vec<Value> = Vec::new();
    let mut requests: Vec<Request> = Vec::new();
    // Packets, numbered per frame: their events in order.
    // (frame, packet) → (cycle, FIFO or "shaded", entered).
    type Steps<'a> = Vec<(u64, &'a str, bool)>;
    let mut packets: BTreeMap<(u32, u32), Steps> = BTreeMap::new();
    let mut tracks: BTreeMap<String, usize> = BTreeMap::new();
    for (e, &frame) in log.events.iter().zip(&log.frames) {
        match e {
            TraceEvent::Fifo { cycle, fifo, push, packet } => {
                packets.entry((frame, *packet)).or_default().push((*cycle, fifo.as_str(), *push));
            }
            TraceEvent::Shaded { cycle, packet } => {
                packets.entry((frame, *packet)).or_default().push((*cycle, "shaded", true));
            }
            TraceEvent::Memory { port, issued, ready, class, bytes, write } if overlaps(*issued, *ready) => {
                requests.push(Request {
                    port,
                    issued: *issued,
                    ready: (*ready).max(issued + 1),
                    name: if *write { format!("{class} write") } else { (*class).to_string() },
                    bytes: *bytes,
                    frame,
                });
            }
            TraceEvent::Memory { .. } => {}
        }
    }
    // Each port's requests in issue order, each on the first of its tracks free by then.
    requests.sort_by(|a, b| (a.port, a.issued, a.ready).cmp(&(b.port, b.issued, b.ready)));
    let mut lanes: BTreeMap<&str, Vec<u64>> = BTreeMap::new();
    for r in &requests {
        let ends = lanes.entry(r.port).or_default();
        let lane = match ends.iter().position(|&end| end <= r.issued) {
            Some(k) => k,
            None => {
                ends.push(0);
                ends.len() - 1
            }
        };
        ends[lane] = r.ready;
        let n = tracks.len();
        let tid = *tracks.entry(format!("{} #{lane}", r.port)).or_insert(n + 1);
        events.push(json!({
            "name": r.name, "cat": "memory", "ph": "X", "pid": 2, "tid": tid,
            "ts": r.issued, "dur": r.ready - r.issued,
            "args": { "bytes": r.bytes, "frame": r.frame },
        }));
    }
    for ((frame, packet), evs) in &packets {
        let id = format!("{frame}.{packet}");
        let slice = |name: &str, ph: &str, ts: u64| json!({ "name": name, "cat": "packet", "ph": ph, "id": id, "pid": 1, "tid": 1, "ts": ts });
        let first = evs.first().map_or(0, |e| e.0);
        let last = evs.last().map_or(first, |e| e.0);
        if !overlaps(first, last) {
            continue;
        }
        events.push(slice(&format!("packet {packet} (frame {frame})"), "b", first));
        // Nested phases: traversal from leaving the ray FIFO to entering the hit FIFO,
        // within it each visit to the intersection unit (leaving a leaf FIFO to entering
        // the result FIFO), then shading from leaving the hit FIFO to its end.
        let mut open: Vec<&str> = Vec::new();
        for &(cycle, fifo, push) in evs {
            let (name, begin) = match (fifo.trim_end_matches(|c: char| c.is_ascii_digit()), push) {
                ("rays", false) => ("traversal", true),
                ("leaves", false) => ("intersection", true),
                ("results", true) => ("intersection", false),
                ("hits", true) => ("traversal", false),
                ("hits", false) => ("shading", true),
                ("shaded", _) => ("shading", false),
                _ => continue,
            };
            if begin {
                events.push(slice(name, "b", cycle));
                open.push(name);
            } else if open.last() == Some(&name) {
                events.push(slice(name, "e", cycle));
                open.pop();
            }
        }
        while let Some(name) = open.pop() {
            events.push(slice(name, "e", last));
        }
        events.push(slice(&format!("packet {packet} (frame {frame})"), "e", last));
    }
    let mut meta = vec![
        json!({ "name": "process_name", "ph": "M", "pid": 1, "args": { "name": "packets" } }),
        json!({ "name": "process_name", "ph": "M", "pid": 2, "args": { "name": "memory" } }),
    ];
    for (port, tid) in &tracks {
        meta.push(json!({ "name": "thread_name", "ph": "M", "pid": 2, "tid": tid, "args": { "name": port } }));
    }
    meta.extend(events);
    json!({
        "traceEvents": meta,
        "displayTimeUnit": "ns",
        "otherData": { "time_unit": "1 us = 1 clock cycle", "clock_mhz": clock_mhz },
    })
}
