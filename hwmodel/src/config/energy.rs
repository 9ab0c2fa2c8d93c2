//! The `[energy]` parameters: the energies and areas the estimate charges to the chip's
//! counters, each with its source. How they are charged is in
//! [`crate::observe::energy`].

use serde::{Deserialize, Serialize};

/// The energy and area parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EnergyConfig {
    /// Process node the defaults are for (nm; documentation, not a scale factor).
    pub process_nm: f64,
    /// 32-bit floating-point add (pJ).
    pub fp_add_pj: f64,
    /// 32-bit floating-point multiply (pJ).
    pub fp_mul_pj: f64,
    /// 32-bit floating-point adder area (µm²).
    pub fp_add_um2: f64,
    /// 32-bit floating-point multiplier area (µm²).
    pub fp_mul_um2: f64,
    /// SRAM read of 64 bits from an 8 KiB array (pJ).
    pub sram_8k_pj: f64,
    /// SRAM read of 64 bits from a 32 KiB array (pJ).
    pub sram_32k_pj: f64,
    /// SRAM read of 64 bits from a 1 MiB array (pJ).
    pub sram_1m_pj: f64,
    /// SRAM area per KiB (mm²).
    pub sram_mm2_per_kib: f64,
    /// DRAM: 64 bits read or written from an open row (pJ).
    pub dram_access_pj: f64,
    /// DRAM: opening a row, on top of the access (pJ).
    pub dram_activate_pj: f64,
    /// Leakage per mm² of the chip (mW; 0: not counted — no published figure at hand).
    pub leakage_mw_per_mm2: f64,
    /// Bytes of one ray's registers in a traversal thread (origin, direction, interval,
    /// hit), the SRAM area of threads and FIFO entries.
    pub ray_state_bytes: f64,
}

impl Default for EnergyConfig {
    fn default() -> Self {
        EnergyConfig {
            process_nm: 45.0,
            fp_add_pj: 0.9,
            fp_mul_pj: 3.7,
            fp_add_um2: 4184.0,
            fp_mul_um2: 7700.0,
            sram_8k_pj: 10.0,
            sram_32k_pj: 20.0,
            sram_1m_pj: 100.0,
            // 600 λ² per bit at λ = 45 nm, 8,192 bits.
            sram_mm2_per_kib: 600.0 * 45e-3 * 45e-3 * 8192.0 * 1e-6,
            dram_access_pj: 1300.0,
            dram_activate_pj: 1300.0,
            leakage_mw_per_mm2: 0.0,
            ray_state_bytes: 48.0,
        }
    }
}
