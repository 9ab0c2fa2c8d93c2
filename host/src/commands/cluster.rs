//! `raypipe cluster RECORDING`: a distributed run's recording replayed on modelled
//! clusters of 1…64 workers (or any list): frames per second cold and warm, parallel
//! efficiency, bytes on the network and cache hit rates. `--check` runs the model on
//! other recordings' own setups and sets each prediction beside what that run measured.

use std::path::PathBuf;

use anyhow::{bail, Result};
use clap::Args;

use crate::study::cluster::model::{frame_rate, predict, Cluster, Prediction};
use crate::study::cluster::recording::Recording;

/// `raypipe cluster`.
#[derive(Args, Debug)]
pub struct ClusterArgs {
    /// A recording of a distributed run (`render --mpi --mpi-record FILE`).
    pub recording: PathBuf,
    /// Worker counts to predict, e.g. 1,2,4,7,64.
    #[arg(long, value_name = "LIST", value_delimiter = ',', default_value = "1,2,3,4,7,8,16,32,64")]
    pub workers: Vec<usize>,
    /// Workers sharing one host's cores (1: a host each, as on a cluster).
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub workers_per_host: u32,
    /// A worker's speed against the recorded one's (2: twice as fast).
    #[arg(long, value_name = "X", default_value_t = 1.0, value_parser = positive)]
    pub speed: f64,
    /// A worker's network link, each way, e.g. 100Mbit, 1Gbit, 10Gbit or 125MB (bytes).
    #[arg(long, value_name = "RATE", default_value = "1Gbit", value_parser = parse_rate)]
    pub client_link: f64,
    /// The master's and model server's link, each way.
    #[arg(long, value_name = "RATE", default_value = "1Gbit", value_parser = parse_rate)]
    pub server_link: f64,
    /// One message's latency, e.g. 50us or 0.2ms.
    #[arg(long, value_name = "TIME", default_value = "50us", value_parser = parse_time)]
    pub latency: f64,
    /// A worker's brick cache (decompressed bytes), e.g. 64M.
    #[arg(long, value_name = "SIZE", default_value = "1G", value_parser = super::args::parse_byte_size)]
    pub cache: u64,
    /// Decompression rate, bytes out per second (default: LZ4 as `info --codecs`
    /// measured it on a 2-core x86-64 machine, 2,734 MB/s).
    #[arg(long, value_name = "RATE", default_value = "2734MB", value_parser = parse_rate)]
    pub decompress: f64,
    /// A worker's loader threads (bricks in flight at once), as `render --loaders`.
    #[arg(long, value_name = "N", default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub loaders: u32,
    /// Bricks come over the network from the model server (else each worker reads
    /// its own copy, at no network cost).
    #[arg(long)]
    pub served: bool,
    /// Recordings of other runs: each is predicted with its own workers (all sharing
    /// this machine's host, as it ran) and set beside what it measured.
    #[arg(long, value_name = "RECORDING", num_args = 1..)]
    pub check: Vec<PathBuf>,
}

fn positive(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v < 1e6 => Ok(v),
        _ => Err(format!("'{s}' is not a positive number")),
    }
}

/// A rate in bytes per second: `100Mbit`, `1Gbit`, `10Gbit`, `125MB`, `2734MB`, `1e9`.
pub fn parse_rate(s: &str) -> Result<f64, String> {
    let t = s.trim();
    let split = t.find(|c: char| c.is_ascii_alphabetic() && c != 'e').unwrap_or(t.len());
    let (num, unit) = t.split_at(split);
    let v: f64 = num.parse().map_err(|_| format!("'{s}' is not a rate such as 100Mbit or 125MB"))?;
    let scale = match unit.trim_end_matches("/s").trim_end_matches("ps") {
        "" | "B" => 1.0,
        "KB" => 1e3,
        "MB" => 1e6,
        "GB" => 1e9,
        "Kbit" => 1e3 / 8.0,
        "Mbit" => 1e6 / 8.0,
        "Gbit" => 1e9 / 8.0,
        _ => return Err(format!("'{s}': unknown unit (use B, KB, MB, GB, Kbit, Mbit or Gbit)")),
    };
    let rate = v * scale;
    if !(rate.is_finite() && (1.0..=1e15).contains(&rate)) {
        return Err(format!("'{s}' is not a rate between 1 byte and a petabyte per second"));
    }
    Ok(rate)
}

/// A time in seconds: `50us`, `0.2ms`, `1s`, `0.00005`.
pub fn parse_time(s: &str) -> Result<f64, String> {
    let t = s.trim();
    let (num, scale) = if let Some(n) = t.strip_suffix("us") {
        (n, 1e-6)
    } else if let Some(n) = t.strip_suffix("ms") {
        (n, 1e-3)
    } else if let Some(n) = t.strip_suffix("ns") {
        (n, 1e-9)
    } else {
        (t.strip_suffix('s').unwrap_or(t), 1.0)
    };
    match num.parse::<f64>() {
        Ok(v) if v.is_finite() && (0.0..=3600.0).contains(&(v * scale)) => Ok(v * scale),
        _ => Err(format!("'{s}' is not a time such as 50us or 0.2ms")),
    }
}

/// `raypipe cluster`.
pub fn cmd_cluster(a: ClusterArgs) -> Result<()> {
    let rec = Recording::read(&a.recording)?;
    if a.workers.iter().any(|&n| n == 0 || n > 65536) {
        bail!("--workers: every count must be between 1 and 65536");
    }
    let cluster = |workers: usize| Cluster {
        workers,
        workers_per_host: a.workers_per_host as usize,
        speed: a.speed,
        client_bandwidth: a.client_link,
        server_bandwidth: a.server_link,
        latency: a.latency,
        cache_bytes: a.cache,
        decompress_rate: a.decompress,
        loaders: a.loaders as usize,
        served: a.served,
    };
    let r = &rec.run;
    println!(
        "recording {}: {} frames of {}x{}, {} tiles of {} px, by {} worker{} ({})",
        a.recording.display(),
        rec.frames(),
        r.width,
        r.height,
        rec.tiles_per_frame(),
        r.tile,
        r.workers,
        if r.workers == 1 { "" } else { "s" },
        r.identity
    );
    let measured = frame_rate(&r.frame_seconds);
    println!("measured  {measured:.2} frames/s over the run");
    println!(
        "cluster   links {:.0}/{:.0} Mbit/s (worker/server), latency {:.0} us, {} worker{} per host, speed {}, cache {} MiB, bricks {}",
        a.client_link * 8e-6,
        a.server_link * 8e-6,
        a.latency * 1e6,
        a.workers_per_host,
        if a.workers_per_host == 1 { "" } else { "s" },
        a.speed,
        a.cache >> 20,
        if a.served { "served" } else { "local" }
    );
    println!("workers  frames/s cold  frames/s warm  efficiency  MB/frame  hit rate   busy");
    let mut one: Option<f64> = None;
    for &n in &a.workers {
        let p = predict(&rec, &cluster(n));
        let base =
            *one.get_or_insert_with(|| if n == 1 { p.warm_fps() } else { predict(&rec, &cluster(1)).warm_fps() });
        print_row(n, &p, p.warm_fps() / (n as f64 * base));
    }
    for path in &a.check {
        let other = Recording::read(path)?;
        let o = &other.run;
        let n = o.workers as usize;
        let c = Cluster { workers_per_host: n.div_ceil(o.hosts.max(1) as usize), ..cluster(n) };
        let p = predict(&rec, &c);
        let got = frame_rate(&o.frame_seconds);
        println!(
            "check    {} worker{} on {} host{}: measured {got:.2} frames/s, predicted {:.2} ({:+.0}%)  [{}]",
            n,
            if n == 1 { "" } else { "s" },
            o.hosts,
            if o.hosts == 1 { "" } else { "s" },
            p.fps(),
            (p.fps() / got - 1.0) * 100.0,
            path.display()
        );
    }
    Ok(())
}

fn print_row(n: usize, p: &Prediction, efficiency: f64) {
    let frames = p.frame_seconds.len().max(1) as f64;
    let mb = p.frame_bytes.iter().sum::<u64>() as f64 / frames / 1e6;
    let hit = p.hit_rate.iter().sum::<f64>() / frames;
    println!(
        "{n:>7}  {:>13.2}  {:>13.2}  {:>9.0}%  {mb:>8.2}  {:>7.1}%  {:>4.0}%",
        p.cold_fps(),
        p.warm_fps(),
        efficiency * 100.0,
        hit * 100.0,
        p.busy * 100.0
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rates_and_times_read_as_people_write_them() {
        assert_eq!(parse_rate("100Mbit").unwrap(), 12.5e6);
        assert_eq!(parse_rate("1Gbit/s").unwrap(), 125e6);
        assert_eq!(parse_rate("125MB").unwrap(), 125e6);
        assert_eq!(parse_rate("2e9").unwrap(), 2e9);
        assert!(parse_rate("fast").is_err() && parse_rate("0Mbit").is_err() && parse_rate("NaNMB").is_err());
        assert!((parse_time("50us").unwrap() - 50e-6).abs() < 1e-15);
        assert!((parse_time("0.2ms").unwrap() - 2e-4).abs() < 1e-15);
        assert!(parse_time("-1s").is_err() && parse_time("soon").is_err());
    }
}
