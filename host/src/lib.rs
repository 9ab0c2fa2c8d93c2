//! # raypipe (host)
//!
//! The `std` side of raypipe: loading OBJ/MTL scenes, building the uniform grid, writing
//! and reading scene images, the multithreaded tile renderer, Purcell's scene
//! statistics, benchmarks and the `raypipe` command line. Geometry kernels are never
//! re-implemented here: everything that touches a ray calls `raypipe-core`.

pub mod aligned;
pub mod batch;
pub mod bench;
pub mod bvh_builder;
pub mod camera_file;
pub mod camera_path;
pub mod chart_numbers;
pub mod cli;
pub mod commands;
pub mod cost_image;
pub mod default_lights;
pub mod default_scene;
pub mod fixed_point;
pub mod generate;
pub mod gltf_loader;
pub mod grid_builder;
pub mod huge_pages;
pub mod image_writer;
pub mod isa;
pub mod kd_builder;
pub mod light_distribution;
pub mod mesh;
pub mod mipmap;
pub mod npy;
pub mod obj;
pub mod obj_indices;
pub mod output;
pub mod packets;
pub mod ply;
pub mod polygon;
pub mod prefetch;
pub mod progress;
pub mod range_check;
pub mod raster;
pub mod ray_stream;
pub mod render;
pub mod report_diff;
pub mod scene;
pub mod scene_file;
pub mod simulate;
pub mod spatial_split;
pub mod stats;
pub mod stream;
pub mod stream_charts;
pub mod sweep;
pub mod sweep_plot;
pub mod sweep_table;
pub mod texture_loader;
pub mod tone_map;
pub mod trace_file;
pub mod tracer;
pub mod tri_box;
pub mod tri_clip;
pub mod waveform;
