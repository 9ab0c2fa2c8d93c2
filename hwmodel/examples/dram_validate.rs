//! raypipe's DRAM model against DRAMsim3 on one request stream: prints one JSON line
//! with both memories' figures (mean and p99 latency, bandwidth, row-hit rate).
//!
//!     cargo run --release -p raypipe-hw --features dramsim3 --example dram_validate -- \
//!         ddr3 sequential [INTERVAL]       # a synthetic stream, one request every INTERVAL cycles
//!     ... --example dram_validate -- ddr4 trace.txt MHZ
//!                                          # a frame's requests (raypipe simulate --memory-trace)
//!
//! `bench/dram_validate.sh` runs every stream on DDR3-1600 and DDR4-2400 and writes the
//! table of docs/hw-model.md.

use raypipe_hw::config::{DramConfig, Dramsim3Config};
use raypipe_hw::memory::replay::{self, ReplayFigures};

fn main() {
    if let Err(e) = run() {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: dram_validate ddr3|ddr4 STREAM|TRACE.txt [INTERVAL|MHZ]";
    let (memory, source) = match args.as_slice() {
        [m, s, ..] => (m.as_str(), s.as_str()),
        _ => return Err(usage.into()),
    };
    let (own, ds3) = match memory {
        "ddr3" => (DramConfig { controller_latency: 0, ..DramConfig::default() }, "DDR3_4Gb_x8_1600"),
        "ddr4" => (replay::ddr4_2400(), "DDR4_8Gb_x8_2400"),
        _ => return Err(format!("{memory}: not ddr3 or ddr4 ({usage})")),
    };
    let third = args.get(2).map(|v| v.parse::<f64>().map_err(|_| format!("{v}: not a number")));
    let (stream, mhz) = match replay::synthetic(source, 20_000, 1, own.row_bytes as u64, (own.banks * own.ranks) as u64)
    {
        Some(_) => {
            // Synthetic streams run at the memory's own clock, one request per INTERVAL.
            let interval = third.transpose()?.unwrap_or(4.0).max(1.0) as u64;
            let s = replay::synthetic(source, 20_000, interval, own.row_bytes as u64, (own.banks * own.ranks) as u64);
            (s.unwrap_or_default(), own.clock_mhz)
        }
        None => {
            let text = std::fs::read_to_string(source).map_err(|e| format!("{source}: {e}"))?;
            let s = replay::parse_trace(&text).map_err(|e| format!("{source}: {e}"))?;
            let mhz = third.ok_or(format!("{source}: give the chip's clock in MHz"))??;
            (s, mhz)
        }
    };
    let a = replay::replay_dram(&own, mhz, &stream);
    let b = replay::replay_dramsim3(&Dramsim3Config { config: ds3.into() }, mhz, &stream)?;
    let row = serde_json::json!({
        "memory": memory, "stream": source, "requests": stream.len(),
        "raypipe": a, "dramsim3": b, "ratio": ratios(&a, &b),
    });
    println!("{row}");
    Ok(())
}

/// raypipe's figure over DRAMsim3's, per figure.
fn ratios(a: &ReplayFigures, b: &ReplayFigures) -> serde_json::Value {
    let r = |x: f64, y: f64| if y > 0.0 { x / y } else { f64::NAN };
    serde_json::json!({
        "mean_ns": r(a.mean_ns, b.mean_ns), "p99_ns": r(a.p99_ns, b.p99_ns),
        "bandwidth_gb_s": r(a.bandwidth_gb_s, b.bandwidth_gb_s), "row_hit_rate": r(a.row_hit_rate, b.row_hit_rate),
    })
}
