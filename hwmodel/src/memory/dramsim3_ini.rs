//! DRAMsim3's configuration files (`.ini`): found by name among the configurations
//! DRAMsim3 ships or read from a path, parsed and checked here before DRAMsim3 sees them.
//!
//! DRAMsim3 ends the process (`exit`) on a configuration it cannot use — an unknown
//! protocol, address-mapping field, queue structure or refresh policy, a file it cannot
//! read — so every value it would refuse is refused here first, in one line naming the
//! file and the key. The parser is plain Rust and is built without the `dramsim3`
//! feature, so a bad file is a bad file whatever the build.

use std::path::{Path, PathBuf};

/// Largest configuration file read (DRAMsim3's own are under 2 KiB).
const MAX_INI_BYTES: usize = 1 << 20;

/// A parsed `.ini` file: sections of `key = value` pairs, in file order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Ini {
    /// `(section, [(key, value)])`.
    pub sections: Vec<(String, Vec<(String, String)>)>,
}

impl Ini {
    /// Parses `text` (`[section]`, `key = value`, `;` and `#` comments).
    pub fn parse(text: &str) -> Result<Ini, String> {
        let mut ini = Ini::default();
        for (n, raw) in text.lines().enumerate() {
            let line = raw.split([';', '#']).next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            if let Some(name) = line.strip_prefix('[') {
                let name = name.strip_suffix(']').ok_or(format!("line {}: a section header without ']'", n + 1))?;
                ini.sections.push((name.trim().to_string(), Vec::new()));
                continue;
            }
            let (key, value) = line.split_once('=').ok_or(format!("line {}: expected key = value", n + 1))?;
            let section = ini.sections.last_mut().ok_or(format!("line {}: a key before any [section]", n + 1))?;
            section.1.push((key.trim().to_string(), value.trim().to_string()));
        }
        Ok(ini)
    }

    /// The value of `key` in `section` (the last one given, as inih reads it).
    pub fn get(&self, section: &str, key: &str) -> Option<&str> {
        let s = self.sections.iter().filter(|(name, _)| name == section);
        s.flat_map(|(_, kv)| kv.iter()).filter(|(k, _)| k == key).map(|(_, v)| v.as_str()).next_back()
    }

    /// Sets `key` in `section` (adding either if missing).
    pub fn set(&mut self, section: &str, key: &str, value: &str) {
        if !self.sections.iter().any(|(name, _)| name == section) {
            self.sections.push((section.to_string(), Vec::new()));
        }
        for (_, kv) in self.sections.iter_mut().filter(|(name, _)| name == section) {
            kv.retain(|(k, _)| k != key);
        }
        if let Some((_, kv)) = self.sections.iter_mut().rev().find(|(name, _)| name == section) {
            kv.push((key.to_string(), value.to_string()));
        }
    }

    /// The file's text.
    pub fn render(&self) -> String {
        let mut out = String::new();
        for (name, kv) in &self.sections {
            out.push_str(&format!("[{name}]\n"));
            for (k, v) in kv {
                out.push_str(&format!("{k} = {v}\n"));
            }
            out.push('\n');
        }
        out
    }

    fn int(&self, section: &str, key: &str, default: i64) -> Result<i64, String> {
        match self.get(section, key) {
            None => Ok(default),
            Some(v) => parse_int(v).ok_or(format!("[{section}] {key} = {v} is not an integer")),
        }
    }

    fn real(&self, section: &str, key: &str, default: f64) -> Result<f64, String> {
        match self.get(section, key) {
            None => Ok(default),
            Some(v) => v
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or(format!("[{section}] {key} = {v} is not a number")),
        }
    }
}

/// inih's integers: decimal, or hexadecimal with `0x`.
fn parse_int(v: &str) -> Option<i64> {
    match v.strip_prefix("0x").or_else(|| v.strip_prefix("0X")) {
        Some(hex) => i64::from_str_radix(hex, 16).ok(),
        None => v.parse().ok(),
    }
}

/// What the chip needs to know of a DRAMsim3 memory, read from its configuration with
/// DRAMsim3's own defaults for missing keys (`configuration.cc`).
#[derive(Clone, Debug, PartialEq)]
pub struct Dramsim3Geometry {
    /// Memory clock period in ns.
    pub t_ck_ns: f64,
    /// Channels.
    pub channels: u32,
    /// Data bus width per channel in bits.
    pub bus_bits: u32,
    /// Burst length in transfers.
    pub burst_length: u32,
    /// Read latency (AL + CL) in memory cycles.
    pub read_latency: u32,
    /// The protocol named in the file.
    pub protocol: String,
}

impl Dramsim3Geometry {
    /// Bytes one transaction moves: the bus width times the burst length, as DRAMsim3's
    /// `request_size_bytes`.
    pub fn transaction_bytes(&self) -> u64 {
        (self.bus_bits as u64 / 8 * self.burst_length as u64).max(1)
    }

    /// Peak bandwidth of all channels in bytes per ns (two transfers per clock).
    pub fn peak_bytes_per_ns(&self) -> f64 {
        self.channels as f64 * self.bus_bits as f64 / 8.0 * 2.0 / self.t_ck_ns
    }

    /// The fastest read answer in ns: a row hit's read latency and its burst.
    pub fn fastest_read_ns(&self) -> f64 {
        (self.read_latency as f64 + self.burst_length as f64 / 2.0) * self.t_ck_ns
    }
}

/// Checks `ini` as DRAMsim3 would read it, and refuses what would make DRAMsim3 end the
/// process or misbehave: every message names the section and key.
pub fn check(ini: &Ini) -> Result<Dramsim3Geometry, String> {
    let protocol = ini.get("dram_structure", "protocol").unwrap_or("DDR3").to_string();
    const JEDEC: [&str; 10] = ["DDR3", "DDR4", "GDDR5", "GDDR5X", "GDDR6", "LPDDR", "LPDDR3", "LPDDR4", "HBM", "HBM2"];
    if protocol == "HMC" {
        return Err("[dram_structure] protocol = HMC: the hybrid memory cube's packet interface is not modelled".into());
    }
    if !JEDEC.contains(&protocol.as_str()) {
        return Err(format!("[dram_structure] protocol = {protocol} is not one DRAMsim3 knows ({})", JEDEC.join(", ")));
    }
    let pow2 = |section: &str, key: &str, default: i64, max: i64| -> Result<i64, String> {
        let v = ini.int(section, key, default)?;
        if v < 1 || v > max || (v as u64).count_ones() != 1 {
            return Err(format!("[{section}] {key} = {v} must be a power of two from 1 to {max}"));
        }
        Ok(v)
    };
    let channels = pow2("system", "channels", 1, 64)?;
    let bankgroups = pow2("dram_structure", "bankgroups", 2, 64)?;
    let banks_per_group = pow2("dram_structure", "banks_per_group", 2, 64)?;
    let rows = pow2("dram_structure", "rows", 1 << 16, 1 << 24)?;
    let columns = pow2("dram_structure", "columns", 1 << 10, 1 << 16)?;
    let device_width = pow2("dram_structure", "device_width", 8, 128)?;
    let bus_bits = pow2("system", "bus_width", 64, 1024)?;
    let burst_length = pow2("dram_structure", "BL", 8, 64)?;
    if device_width > bus_bits {
        return Err(format!(
            "[dram_structure] device_width = {device_width} is wider than [system] bus_width = {bus_bits}"
        ));
    }
    if columns < burst_length {
        return Err(format!("[dram_structure] columns = {columns} is fewer than one burst (BL = {burst_length})"));
    }
    let positive = |section: &str, key: &str, default: i64, max: i64| -> Result<i64, String> {
        let v = ini.int(section, key, default)?;
        if !(1..=max).contains(&v) {
            return Err(format!("[{section}] {key} = {v} must be from 1 to {max}"));
        }
        Ok(v)
    };
    let channel_size = positive("system", "channel_size", 1024, 1 << 20)?;
    // DRAMsim3 prints a warning and picks another size when the devices do not fit the
    // channel (configuration.cc, CalculateSize): an inconsistent file, refused here.
    let devices = bus_bits / device_width;
    let megs_per_rank = columns * device_width / 8 * (rows / 1024) / 1024 * bankgroups * banks_per_group * devices;
    if megs_per_rank > channel_size {
        return Err(format!(
            "[system] channel_size = {channel_size} MB is smaller than one rank of these devices ({megs_per_rank} MB)"
        ));
    }
    positive("system", "cmd_queue_size", 16, 4096)?;
    positive("system", "trans_queue_size", 32, 4096)?;
    positive("other", "epoch_period", 100_000, i32::MAX as i64)?;
    for key in
        ["CL", "tRCD", "tRP", "tRAS", "tRFC", "REFI", "tFAW", "tWR", "tRTP", "tCCD_S", "tCCD_L", "tRRD_S", "tRRD_L"]
    {
        let v = ini.int("timing", key, 1)?;
        if !(0..=1_000_000).contains(&v) {
            return Err(format!("[timing] {key} = {v} must be from 0 to 1000000 cycles"));
        }
    }
    let cl = positive("timing", "CL", 12, 1000)?;
    let al = ini.int("timing", "AL", 0)?;
    if !(0..=1000).contains(&al) {
        return Err(format!("[timing] AL = {al} must be from 0 to 1000"));
    }
    let t_ck = ini.real("timing", "tCK", 1.0)?;
    if !(0.01..=1000.0).contains(&t_ck) {
        return Err(format!("[timing] tCK = {t_ck} ns is not a memory clock period (0.01 to 1000 ns)"));
    }
    one_of(ini, "system", "queue_structure", "PER_BANK", &["PER_BANK", "PER_RANK"])?;
    one_of(ini, "system", "row_buf_policy", "OPEN_PAGE", &["OPEN_PAGE", "CLOSE_PAGE"])?;
    let refresh = ["RANK_LEVEL_SIMULTANEOUS", "RANK_LEVEL_STAGGERED", "BANK_LEVEL_STAGGERED"];
    one_of(ini, "system", "refresh_policy", "RANK_LEVEL_STAGGERED", &refresh)?;
    let mapping = ini.get("system", "address_mapping").unwrap_or("chrobabgraco");
    let mut fields: Vec<&str> = (0..mapping.len() / 2).filter_map(|i| mapping.get(2 * i..2 * i + 2)).collect();
    fields.sort_unstable();
    if mapping.len() != 12 || fields != ["ba", "bg", "ch", "co", "ra", "ro"] {
        return Err(format!(
            "[system] address_mapping = {mapping} must name each of ch, ra, bg, ba, ro, co once (12 letters)"
        ));
    }
    for key in ["VDD", "IDD0", "IDD2P", "IDD2N", "IDD3N", "IDD4W", "IDD4R", "IDD5AB", "IDD6x"] {
        let v = ini.real("power", key, 1.0)?;
        if v < 0.0 {
            return Err(format!("[power] {key} = {v} must not be negative"));
        }
    }
    Ok(Dramsim3Geometry {
        t_ck_ns: t_ck,
        channels: channels as u32,
        bus_bits: bus_bits as u32,
        burst_length: burst_length as u32,
        read_latency: (al + cl) as u32,
        protocol,
    })
}

fn one_of(ini: &Ini, section: &str, key: &str, default: &str, allowed: &[&str]) -> Result<(), String> {
    let v = ini.get(section, key).unwrap_or(default);
    if !allowed.contains(&v) {
        return Err(format!("[{section}] {key} = {v} must be one of {}", allowed.join(", ")));
    }
    Ok(())
}

/// The folder of DRAMsim3's shipped configurations, if this build knows one:
/// `RAYPIPE_DRAMSIM3_CONFIGS` at run time, else the one found when the crate was built.
pub fn shipped_dir() -> Option<PathBuf> {
    let at_run = std::env::var_os("RAYPIPE_DRAMSIM3_CONFIGS").map(PathBuf::from);
    let at_build = option_env!("RAYPIPE_DRAMSIM3_CONFIGS").map(PathBuf::from);
    at_run.or(at_build).filter(|d| d.is_dir())
}

/// The file `name` means: a path to an existing file, or a shipped configuration's name
/// with or without `.ini` (`DDR4_8Gb_x8_2400`).
pub fn resolve(name: &str) -> Result<PathBuf, String> {
    let path = Path::new(name);
    if path.is_file() {
        return Ok(path.to_path_buf());
    }
    let file = if name.ends_with(".ini") { name.to_string() } else { format!("{name}.ini") };
    let plain = !file.contains(['/', '\\']);
    if let Some(dir) = shipped_dir().filter(|_| plain) {
        let p = dir.join(&file);
        if p.is_file() {
            return Ok(p);
        }
        return Err(format!(
            "memory.dramsim3.config: {name} is neither a file nor one of DRAMsim3's configurations in {}",
            dir.display()
        ));
    }
    Err(format!(
        "memory.dramsim3.config: {name} is not a file (and this build knows no folder of DRAMsim3's \
         configurations: set RAYPIPE_DRAMSIM3_CONFIGS)"
    ))
}

/// Reads, parses and checks the configuration `name` names.
pub fn load(name: &str) -> Result<(PathBuf, Ini, Dramsim3Geometry), String> {
    let path = resolve(name)?;
    let shown = path.display();
    let bytes = std::fs::read(&path).map_err(|e| format!("{shown}: {e}"))?;
    if bytes.len() > MAX_INI_BYTES {
        return Err(format!("{shown}: {} bytes is too large for a DRAMsim3 configuration", bytes.len()));
    }
    let text = String::from_utf8(bytes).map_err(|_| format!("{shown}: not UTF-8 text"))?;
    let ini = Ini::parse(&text).map_err(|e| format!("{shown}: {e}"))?;
    let geometry = check(&ini).map_err(|e| format!("{shown}: {e}"))?;
    Ok((path, ini, geometry))
}

#[cfg(test)]
mod tests {
    use super::*;

    const DDR3: &str = "[dram_structure]\nprotocol = DDR3\nbankgroups = 1\nbanks_per_group = 8\nrows = 65536\n\
        columns = 1024\ndevice_width = 8\nBL = 8\n\n[timing]\ntCK = 1.25\nAL = 0\nCL = 11\n\n[system]\n\
        channel_size = 4096\nchannels = 1\nbus_width = 64\naddress_mapping = rochrababgco\n\n[other]\n\
        epoch_period = 800000\noutput_level = 1\n";

    #[test]
    fn a_shipped_style_file_parses_and_gives_its_geometry() {
        let g = check(&Ini::parse(DDR3).unwrap()).unwrap();
        assert_eq!(g.transaction_bytes(), 64);
        assert_eq!(g.read_latency, 11);
        assert!((g.peak_bytes_per_ns() - 12.8).abs() < 1e-9);
        assert!((g.fastest_read_ns() - 15.0 * 1.25).abs() < 1e-9);
    }

    #[test]
    fn what_dramsim3_would_exit_on_is_refused_with_its_key() {
        for (from, to, key) in [
            ("protocol = DDR3", "protocol = DDR9", "protocol"),
            ("protocol = DDR3", "protocol = HMC", "HMC"),
            ("address_mapping = rochrababgco", "address_mapping = rochrababgxx", "address_mapping"),
            ("address_mapping = rochrababgco", "address_mapping = roch", "address_mapping"),
            ("banks_per_group = 8", "banks_per_group = 6", "banks_per_group"),
            ("tCK = 1.25", "tCK = nan", "tCK"),
            ("CL = 11", "CL = eleven", "CL"),
            ("BL = 8", "BL = 0", "BL"),
            ("channels = 1", "channels = 1\nqueue_structure = PER_CHIP", "queue_structure"),
        ] {
            let text = DDR3.replace(from, to);
            let err = Ini::parse(&text).and_then(|i| check(&i)).unwrap_err();
            assert!(err.contains(key), "{to}: {err}");
        }
        assert!(Ini::parse("key = 1\n").unwrap_err().contains("before any [section]"));
        assert!(Ini::parse("[open\n").unwrap_err().contains("']'"));
    }

    #[test]
    fn set_replaces_a_key_and_render_round_trips() {
        let mut ini = Ini::parse(DDR3).unwrap();
        ini.set("other", "epoch_period", "1000");
        ini.set("other", "output_prefix", "x");
        let again = Ini::parse(&ini.render()).unwrap();
        assert_eq!(again.get("other", "epoch_period"), Some("1000"));
        assert_eq!(again.get("other", "output_prefix"), Some("x"));
        assert_eq!(again.get("timing", "CL"), Some("11"));
        assert_eq!(again, ini);
    }
}
