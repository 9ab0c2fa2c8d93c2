//! Observing the chip without changing it: stall reasons, unit statistics, the report, its counters and metrics, energy and area, waveforms and traces.

pub mod bounds;
pub mod chip_signals;
pub mod counters;
pub mod dramsim3_report;
pub mod energy;
pub mod metrics;
pub mod report;
pub mod stall;
pub mod unit_stats;
pub mod verdict;
pub mod waves;
