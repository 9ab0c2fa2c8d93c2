//! Rejecting a chip that cannot be built or cannot work, section by section, with the
//! reason: the clock and packets, the units' rates and capacities, the FIFOs, each cache,
//! the DRAM, the simulator's own state, and the energy figures.

use super::energy::EnergyConfig;
use super::{CacheConfig, DramConfig, FifoConfig, HwConfig, MemoryModel, MAX_MODELLED_BYTES};
use crate::chip::fifo::MAX_FIFO_DEPTH;

impl HwConfig {
    /// Rejects configurations that cannot be built or cannot work, with the reason.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.clock_mhz.is_finite() && self.clock_mhz > 0.0 && self.clock_mhz <= 1e6) {
            return Err(format!("clock_mhz must be a positive number of at most 1e6 (got {})", self.clock_mhz));
        }
        if ![1, 4, 16, 64].contains(&self.packet_size) {
            return Err(format!("packet_size must be 1, 4, 16 or 64 (got {})", self.packet_size));
        }
        if !super::STRUCTURES.contains(&self.structure.as_str()) {
            return Err(format!(
                "structure must be one of {} (got {:?})",
                super::STRUCTURES.join(", "),
                self.structure
            ));
        }
        self.validate_units()?;
        self.fifo.validate()?;
        for (name, c) in self.caches() {
            c.validate(name)?;
        }
        if self.memory.model == MemoryModel::Dramsim3 {
            if !cfg!(feature = "dramsim3") {
                return Err(super::NO_DRAMSIM3.into());
            }
            crate::memory::dramsim3_ini::load(&self.memory.dramsim3.config)?;
        }
        self.validate_hierarchy()?;
        if self.memory.model == MemoryModel::Dram {
            self.memory.dram.validate()?;
        }
        let state = self.modelled_bytes();
        if state > MAX_MODELLED_BYTES {
            return Err(format!(
                "the chip would need {:.1} GiB of simulator state (caches, thread registers), more than the {} GiB limit",
                state as f64 / (1u64 << 30) as f64,
                MAX_MODELLED_BYTES >> 30
            ));
        }
        if self.watchdog_cycles == 0 {
            return Err("watchdog_cycles must be at least 1".to_string());
        }
        self.energy.validate()
    }

    /// The units' rates, latencies and capacities (`rgs`, `traversal`, `intersection`,
    /// `memory`): each at least 1 and at most what the model supports.
    fn validate_units(&self) -> Result<(), String> {
        let positive = [
            ("rgs.rays_per_cycle", self.rgs.rays_per_cycle),
            ("rgs.shade_per_cycle", self.rgs.shade_per_cycle),
            ("rgs.shade_jobs", self.rgs.shade_jobs),
            ("traversal.units", self.traversal.units),
            ("traversal.threads", self.traversal.threads),
            ("traversal.step_latency", self.traversal.step_latency),
            ("traversal.lanes_per_cycle", self.traversal.lanes_per_cycle),
            ("intersection.latency", self.intersection.latency),
            ("intersection.initiation_interval", self.intersection.initiation_interval),
            ("intersection.lanes_per_cycle", self.intersection.lanes_per_cycle),
            ("intersection.jobs", self.intersection.jobs),
            ("transform.latency", self.transform.latency),
            ("transform.initiation_interval", self.transform.initiation_interval),
            ("transform.lanes_per_cycle", self.transform.lanes_per_cycle),
            ("memory.bytes_per_cycle", self.memory.bytes_per_cycle),
            ("memory.queue_depth", self.memory.queue_depth),
            ("memory.min_burst_bytes", self.memory.min_burst_bytes),
        ];
        for (name, v) in positive {
            if v == 0 {
                return Err(format!("{name} must be at least 1"));
            }
        }
        let capped = [
            ("traversal.units", self.traversal.units, 64),
            // A thread is a bit of the unit's 64-bit state masks.
            ("traversal.threads", self.traversal.threads, 64),
            ("traversal.lanes_per_cycle", self.traversal.lanes_per_cycle, 64),
            ("intersection.lanes_per_cycle", self.intersection.lanes_per_cycle, 4096),
            ("intersection.jobs", self.intersection.jobs, 64),
            ("transform.lanes_per_cycle", self.transform.lanes_per_cycle, 64),
            ("transform.latency", self.transform.latency, 1_000_000),
            ("transform.initiation_interval", self.transform.initiation_interval, 1_000_000),
            ("rgs.shade_jobs", self.rgs.shade_jobs, 64),
            ("rgs.rays_per_cycle", self.rgs.rays_per_cycle, 4096),
            ("rgs.shade_per_cycle", self.rgs.shade_per_cycle, 4096),
            ("memory.queue_depth", self.memory.queue_depth, 4096),
            ("memory.min_burst_bytes", self.memory.min_burst_bytes, 4096),
            ("traversal.step_latency", self.traversal.step_latency, 1_000_000),
            ("intersection.latency", self.intersection.latency, 1_000_000),
            ("intersection.initiation_interval", self.intersection.initiation_interval, 1_000_000),
            ("memory.latency", self.memory.latency, 1_000_000),
        ];
        for (name, v, max) in capped {
            if v > max {
                return Err(format!("{name} {v} is more than the {max} the model supports"));
            }
        }
        Ok(())
    }
}

impl FifoConfig {
    /// Every FIFO holds at least one entry and no more than a FIFO can.
    fn validate(&self) -> Result<(), String> {
        let fifos = [
            ("fifo.rays", self.rays),
            ("fifo.leaves", self.leaves),
            ("fifo.results", self.results),
            ("fifo.hits", self.hits),
        ];
        for (name, depth) in fifos {
            if depth == 0 {
                return Err(format!("{name}: a FIFO needs a depth of at least 1"));
            }
            if depth as usize > MAX_FIFO_DEPTH {
                return Err(format!("{name}: depth {depth} exceeds the {MAX_FIFO_DEPTH} entries a FIFO can hold"));
            }
        }
        Ok(())
    }
}

impl HwConfig {
    /// Each level no slower than the one behind it: a cache whose hit takes longer than
    /// the L2 behind it, or than the memory's fastest answer (fixed: its latency and one
    /// transfer cycle; DRAM: the controller and the CAS latency, in chip cycles), is no
    /// cache anyone would build, and would make a miss cheaper than a hit.
    fn validate_hierarchy(&self) -> Result<(), String> {
        let memory = self.memory_fastest_answer();
        let l2 = &self.cache.l2;
        for (name, c) in self.caches().into_iter().filter(|(_, c)| c.size_bytes > 0) {
            let h = c.hit_latency as f64;
            if name != "cache.l2" && l2.size_bytes > 0 && c.hit_latency > l2.hit_latency {
                return Err(format!(
                    "{name}.hit_latency {} is longer than the L2's ({}): a cache slower than the one behind it",
                    c.hit_latency, l2.hit_latency
                ));
            }
            if let Some(fastest) = memory.filter(|&f| h > f) {
                return Err(format!(
                    "{name}.hit_latency {} is longer than the memory's fastest answer ({fastest:.1} cycles): \
                     a cache slower than the memory behind it",
                    c.hit_latency
                ));
            }
        }
        Ok(())
    }
}

impl HwConfig {
    /// The memory's fastest answer in chip cycles (fixed: its latency and one transfer
    /// cycle; DRAM: the controller and CL; DRAMsim3: its read latency and one burst), or
    /// `None` for perfect memory (or a DRAMsim3 configuration that cannot be read).
    pub fn memory_fastest_answer(&self) -> Option<f64> {
        let m = &self.memory;
        match m.model {
            MemoryModel::Perfect => None,
            MemoryModel::Fixed => Some(m.latency as f64 + 1.0),
            MemoryModel::Dram => {
                let d = &m.dram;
                Some(d.controller_latency as f64 + d.t_cl as f64 * self.clock_mhz / d.clock_mhz)
            }
            MemoryModel::Dramsim3 => crate::memory::dramsim3_ini::load(&m.dramsim3.config)
                .ok()
                .map(|(_, _, g)| g.fastest_read_ns() * self.clock_mhz / 1e3),
        }
    }
}

impl CacheConfig {
    /// Lines, ports and MSHRs within the model's range, and (unless the cache is off) a
    /// whole number of sets.
    fn validate(&self, name: &str) -> Result<(), String> {
        let c = self;
        if c.line_bytes < 4 || !c.line_bytes.is_multiple_of(4) || c.line_bytes > 4096 {
            return Err(format!("{name}.line_bytes must be a multiple of 4 from 4 to 4096 (got {})", c.line_bytes));
        }
        for (key, v, max) in
            [("ports", c.ports, 64), ("mshrs", c.mshrs, 1024), ("hit_latency", c.hit_latency, 1_000_000)]
        {
            if v > max {
                return Err(format!("{name}.{key} {v} is more than the {max} the model supports"));
            }
        }
        if c.ports == 0 {
            return Err(format!("{name}.ports must be at least 1"));
        }
        if c.size_bytes == 0 {
            return Ok(());
        }
        if c.mshrs == 0 {
            return Err(format!("{name}.mshrs must be at least 1"));
        }
        if c.size_bytes < c.line_bytes {
            return Err(format!("{name}: {} bytes is smaller than one {}-byte line", c.size_bytes, c.line_bytes));
        }
        if c.ways == 0 {
            return Err(format!("{name}.ways must be at least 1"));
        }
        let lines = c.size_bytes / c.line_bytes;
        if !c.size_bytes.is_multiple_of(c.line_bytes) || !lines.is_multiple_of(c.ways) {
            return Err(format!(
                "{name}: {} bytes in {}-byte lines and {} ways does not give a whole number of sets",
                c.size_bytes, c.line_bytes, c.ways
            ));
        }
        Ok(())
    }
}

impl DramConfig {
    /// A clock, geometry and timings the DRAM model can run.
    fn validate(&self) -> Result<(), String> {
        let d = self;
        if !(d.clock_mhz.is_finite() && d.clock_mhz > 0.0 && d.clock_mhz <= 1e5) {
            return Err(format!("memory.dram.clock_mhz must be a positive number (got {})", d.clock_mhz));
        }
        for (key, v, max) in [
            ("channels", d.channels, 64),
            ("ranks", d.ranks, 16),
            ("banks", d.banks, 256),
            ("bus_bytes", d.bus_bytes, 1024),
            ("burst_length", d.burst_length, 64),
            ("row_bytes", d.row_bytes, 1 << 20),
        ] {
            if v == 0 || v > max {
                return Err(format!("memory.dram.{key} must be from 1 to {max} (got {v})"));
            }
        }
        if !d.burst_length.is_multiple_of(2) {
            return Err(format!("memory.dram.burst_length must be even (got {})", d.burst_length));
        }
        if !d.row_bytes.is_multiple_of(d.bus_bytes * d.burst_length) {
            return Err(format!(
                "memory.dram.row_bytes {} is not a whole number of {}-byte bursts",
                d.row_bytes,
                d.bus_bytes * d.burst_length
            ));
        }
        if d.t_refi > 0 && d.t_rfc >= d.t_refi {
            return Err(format!("memory.dram.t_rfc {} must be shorter than t_refi {}", d.t_rfc, d.t_refi));
        }
        for (key, v) in [
            ("t_rcd", d.t_rcd),
            ("t_rp", d.t_rp),
            ("t_cl", d.t_cl),
            ("t_cwl", d.t_cwl),
            ("t_wtr", d.t_wtr),
            ("t_ras", d.t_ras),
            ("t_wr", d.t_wr),
            ("t_rfc", d.t_rfc),
            ("t_rrd", d.t_rrd),
            ("t_faw", d.t_faw),
            ("t_rtrs", d.t_rtrs),
            ("row_hit_cap", d.row_hit_cap),
            ("controller_latency", d.controller_latency),
        ] {
            if v > 100_000 {
                return Err(format!("memory.dram.{key} {v} is more than the 100000 cycles the model supports"));
            }
        }
        Ok(())
    }
}

impl EnergyConfig {
    /// Every figure finite and from 0 to 1e12.
    fn validate(&self) -> Result<(), String> {
        let e = self;
        for (key, v) in [
            ("process_nm", e.process_nm),
            ("fp_add_pj", e.fp_add_pj),
            ("fp_mul_pj", e.fp_mul_pj),
            ("fp_add_um2", e.fp_add_um2),
            ("fp_mul_um2", e.fp_mul_um2),
            ("sram_8k_pj", e.sram_8k_pj),
            ("sram_32k_pj", e.sram_32k_pj),
            ("sram_1m_pj", e.sram_1m_pj),
            ("sram_mm2_per_kib", e.sram_mm2_per_kib),
            ("dram_access_pj", e.dram_access_pj),
            ("dram_activate_pj", e.dram_activate_pj),
            ("leakage_mw_per_mm2", e.leakage_mw_per_mm2),
            ("ray_state_bytes", e.ray_state_bytes),
        ] {
            if !(v.is_finite() && (0.0..=1e12).contains(&v)) {
                return Err(format!("energy.{key} must be a finite number from 0 to 1e12 (got {v})"));
            }
        }
        Ok(())
    }
}
