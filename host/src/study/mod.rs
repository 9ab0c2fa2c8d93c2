//! Measuring scenes and models: statistics, benchmarks, the fixed-point comparison, sweeps, plots, report diffs and cost images.

pub mod animation_report;
pub mod batch_stats;
pub mod bench;
pub mod cluster;
pub mod cost_image;
pub mod fixed_point;
pub mod report_diff;
pub mod scene_stats;
pub mod sweep;
pub mod sweep_journal;
pub mod sweep_plot;
pub mod sweep_table;
pub mod update_bench;
