//! Energy and area estimates from the configuration and the activity counters, in the
//! manner of SimTRaX and McPAT: every datapath operation, cache lookup and DRAM access
//! the run counted is charged a published energy, every unit and every KiB of SRAM a
//! published area, and the area leaks for the frame's duration.
//!
//! Defaults (`[energy]`, every one overridable with `--set energy.<key>=…`) are at 45 nm,
//! 0.9 V, from M. Horowitz, "Computing's energy problem (and what we can do about it)",
//! ISSCC 2014, Figure 1.1.9: 32-bit float add 0.9 pJ and 4,184 µm², multiply 3.7 pJ
//! and 7,700 µm²; SRAM reads of 64 bits 10 pJ (8 KiB), 20 pJ (32 KiB), 100 pJ (1 MiB);
//! DRAM 1.3–2.6 nJ per 64 bits. SRAM area: about 600 λ² per bit cell (CACTI's rule of
//! thumb, as given in D. J. Greaves, "System on Chip Design", Cambridge, §"45nm SRAM
//! memory area and power consumption"), λ = 45 nm.
//!
//! How the counters become operations (docs/hw-model.md, "Energy and area"):
//! - a ray–node test is a ray–box slab test per child box (6 multiplies and 12
//!   additions or comparisons each: 2 of each per axis for the distances, then min/max)
//!   for the BVHs; a kd split test is 1 multiply and 2 additions; a grid DDA step 4
//!   additions (3 compares and one increment);
//! - a ray–triangle test: 27 multiplies and 23 additions (Möller–Trumbore, counted with
//!   the division as 4 multiplies);
//! - a shaded ray: 26 multiplies and 15 additions (normal interpolation and
//!   normalisation, one light's direction and cosine, the colour product);
//! - a cache lookup reads a whole line (`line_bytes / 8` 64-bit words) and a miss writes
//!   it (as many again), at the energy of the cache's size, log-interpolated between
//!   Horowitz's three sizes;
//! - DRAM: every 8 bytes moved cost the low figure (1.3 nJ, a row-buffer hit); every
//!   row opened (DRAM model: row-empty and row-conflict accesses) costs the difference
//!   up to the high figure (1.3 nJ more). The fixed and perfect models count no rows, so
//!   their DRAM energy is a lower bound.

use crate::config::energy::EnergyConfig;
use crate::config::HwConfig;
use crate::observe::report::{EnergyReport, Report};

/// Floating-point operations: (multiplies, additions).
type Ops = (f64, f64);

/// A ray–box slab test.
const BOX_TEST: Ops = (6.0, 12.0);
/// A kd-tree split test.
const KD_TEST: Ops = (1.0, 2.0);
/// A grid DDA step.
const DDA_STEP: Ops = (0.0, 4.0);
/// A ray–triangle test.
const TRIANGLE_TEST: Ops = (27.0, 23.0);
/// Shading one ray.
const SHADE: Ops = (26.0, 15.0);

/// What one ray–node test of the traversal datapath costs, by the scene's structure.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NodeTest {
    /// A grid DDA step.
    Grid,
    /// A kd-tree split test.
    Kd,
    /// Slab tests against this many child boxes (BVH 2, BVH4 4, BVH8 8).
    Boxes(u32),
    /// No structure (brute force): no node tests.
    None,
}

impl NodeTest {
    fn ops(self) -> Ops {
        match self {
            NodeTest::Grid => DDA_STEP,
            NodeTest::Kd => KD_TEST,
            NodeTest::Boxes(n) => (BOX_TEST.0 * n as f64, BOX_TEST.1 * n as f64),
            NodeTest::None => (0.0, 0.0),
        }
    }
}

impl EnergyConfig {
    fn op_pj(&self, (mul, add): Ops) -> f64 {
        mul * self.fp_mul_pj + add * self.fp_add_pj
    }

    fn op_mm2(&self, (mul, add): Ops) -> f64 {
        (mul * self.fp_mul_um2 + add * self.fp_add_um2) * 1e-6
    }

    /// Energy of reading 64 bits from an SRAM of `bytes`: log-linear between Horowitz's
    /// sizes (and beyond them, along the nearest segment).
    pub fn sram_pj(&self, bytes: u32) -> f64 {
        let kib = (bytes as f64 / 1024.0).max(1.0);
        let points = [(8.0f64, self.sram_8k_pj), (32.0, self.sram_32k_pj), (1024.0, self.sram_1m_pj)];
        let (a, b) = if kib <= 32.0 { (points[0], points[1]) } else { (points[1], points[2]) };
        let t = (kib.ln() - a.0.ln()) / (b.0.ln() - a.0.ln());
        (a.1 + t * (b.1 - a.1)).max(0.0)
    }

    fn sram_mm2(&self, bytes: f64) -> f64 {
        bytes / 1024.0 * self.sram_mm2_per_kib
    }

    /// The estimate for the run `r` of configuration `cfg` on a scene whose ray–node
    /// tests are `node`.
    pub fn estimate(&self, cfg: &HwConfig, r: &Report, node: NodeTest) -> EnergyReport {
        let mut joules = std::collections::BTreeMap::new();
        let mut area = std::collections::BTreeMap::new();
        let pj = 1e-12;
        let lanes =
            |prefix: &str| r.units.iter().filter(|u| u.name.starts_with(prefix)).map(|u| u.active_lanes).sum::<u64>();
        joules.insert("traversal".to_string(), lanes("traversal") as f64 * self.op_pj(node.ops()) * pj);
        joules.insert("intersection".to_string(), r.triangle_tests as f64 * self.op_pj(TRIANGLE_TEST) * pj);
        joules.insert("shading".to_string(), lanes("rgs.shade") as f64 * self.op_pj(SHADE) * pj);
        // Caches: a lookup reads its line, a miss also writes it.
        let mut cache_j = 0.0;
        for c in &r.caches {
            let words = c.line_bytes as f64 / 8.0;
            let (lookups, misses) =
                c.classes.values().fold((0, 0), |(l, m), k| (l + k.hits + k.merged + k.misses, m + k.misses));
            cache_j += (lookups + misses) as f64 * words * self.sram_pj(c.size_bytes) * pj;
        }
        joules.insert("caches".to_string(), cache_j);
        let l2 = &cfg.cache.l2;
        let l2_lookups: u64 = r.memory.l2.values().sum();
        let l2_misses = r.memory.l2.get("misses").copied().unwrap_or(0);
        joules.insert(
            "l2".to_string(),
            (l2_lookups + l2_misses) as f64 * l2.line_bytes as f64 / 8.0 * self.sram_pj(l2.size_bytes) * pj,
        );
        let activations: u64 =
            r.memory.dram.as_ref().map_or(0, |d| d.banks.iter().map(|b| b.row_empty + b.row_conflicts).sum());
        joules.insert(
            "dram".to_string(),
            (r.memory.total_bytes as f64 / 8.0 * self.dram_access_pj + activations as f64 * self.dram_activate_pj) * pj,
        );
        // Area: each unit's datapath lanes, the caches, and the registers of threads and
        // FIFO entries (whole packets of ray state).
        let units = cfg.traversal.units as f64;
        let node_lanes = if node == NodeTest::None { 0.0 } else { cfg.traversal.lanes_per_cycle as f64 };
        area.insert("traversal".to_string(), units * node_lanes * self.op_mm2(node.ops()));
        area.insert(
            "intersection".to_string(),
            units * cfg.intersection.lanes_per_cycle as f64 * self.op_mm2(TRIANGLE_TEST),
        );
        area.insert("shading".to_string(), cfg.rgs.shade_per_cycle as f64 * self.op_mm2(SHADE));
        let c = &cfg.cache;
        let per_unit = c.nodes.size_bytes as f64
            + c.triangles.size_bytes as f64
            + if c.lists_share_triangle_cache { 0.0 } else { c.lists.size_bytes as f64 };
        area.insert("caches".to_string(), self.sram_mm2(units * per_unit + c.shading.size_bytes as f64));
        area.insert("l2".to_string(), self.sram_mm2(c.l2.size_bytes as f64));
        let packet = cfg.packet_size as f64 * self.ray_state_bytes;
        let f = &cfg.fifo;
        let entries =
            units * (cfg.traversal.threads + f.rays + f.leaves + f.results + f.hits + cfg.intersection.jobs) as f64;
        area.insert("registers".to_string(), self.sram_mm2(entries * packet));
        let area_mm2: f64 = area.values().sum();
        let seconds = r.cycles as f64 / (cfg.clock_mhz * 1e6);
        joules.insert("leakage".to_string(), area_mm2 * self.leakage_mw_per_mm2 * 1e-3 * seconds);
        let total: f64 = joules.values().sum();
        EnergyReport {
            process_nm: self.process_nm,
            joules_per_frame: total,
            joules_per_ray: if r.rays > 0 { total / r.rays as f64 } else { 0.0 },
            watts: if seconds > 0.0 { total / seconds } else { 0.0 },
            area_mm2,
            joules,
            area,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sram_energy_meets_horowitz_at_his_sizes() {
        let e = EnergyConfig::default();
        for (bytes, pj) in [(8 << 10, 10.0), (32 << 10, 20.0), (1 << 20, 100.0)] {
            assert!((e.sram_pj(bytes) - pj).abs() < 1e-9, "{bytes}: {}", e.sram_pj(bytes));
        }
        assert!(e.sram_pj(16 << 10) > 10.0 && e.sram_pj(16 << 10) < 20.0);
        assert!(e.sram_pj(64 << 10) > 20.0 && e.sram_pj(64 << 10) < 100.0);
        // 600 λ² per bit at 45 nm: about 0.01 mm² per KiB.
        assert!((e.sram_mm2_per_kib - 0.00995).abs() < 1e-4);
    }
}
