//! Any text as a distributed run's recording: read and checked, then replayed on a
//! small cluster, or a one-line error; never a panic, and never a runaway (the checks
//! bound what the model is given).
#![no_main]

use libfuzzer_sys::fuzz_target;
use raypipe::study::cluster::model::{predict, Cluster};
use raypipe::study::cluster::recording::Recording;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    match Recording::parse(text, "fuzz") {
        Ok(rec) => {
            for workers in [1, 3] {
                let c = Cluster {
                    workers,
                    workers_per_host: 1,
                    speed: 1.0,
                    client_bandwidth: 12.5e6,
                    server_bandwidth: 125e6,
                    latency: 1e-4,
                    cache_bytes: 1 << 20,
                    decompress_rate: 2.7e9,
                    loaders: 2,
                    served: true,
                };
                let p = predict(&rec, &c);
                assert_eq!(p.frame_seconds.len(), rec.frames() as usize);
            }
        }
        Err(e) => assert!(!format!("{e:#}").contains('\n'), "one-line error: {e:#}"),
    }
});
