//! day2night's integration tests, compiled as one test binary (`cargo test --test it`):
//! one module per topic. One binary links the crate once instead of once per file (a
//! clean `cargo test --no-run` and `target/` are measured in docs/benchmarks.md).
//! Shared helpers: `common` (paths, the CLI binary, the Python validators), `dngbuild`
//! (hand-made TIFF/DNG files), `calibrate_support`, `dataset_fake`. Run one topic with
//! `cargo test --test it synth_cli::` (the module path filters the tests).

mod calibrate_support;
mod common;
mod dataset_fake;
mod dngbuild;

mod calibrate_illuminants;
mod calibrate_merge;
mod calibrate_noise;
mod calibrate_synth;
mod checks_burst;
mod checks_inputs;
mod choices;
mod cli_dialect;
mod cli_docs;
mod cli_options;
mod cli_smoke;
mod convert_opcodes;
mod dataset_cli;
mod dataset_core;
mod dataset_memory;
mod dataset_report;
mod dataset_units;
mod deflate_zlib;
mod dng_bad_files;
mod dng_compressed;
mod dng_gps;
mod dng_opcodes;
mod dng_read;
mod dng_robustness;
mod dng_roundtrip;
mod docs_house;
mod fixtures_reproducible;
mod fuzz_regressions;
mod isp_banded;
mod isp_demosaic_accuracy;
mod isp_exr;
mod isp_opcode_checks;
mod isp_opcodes;
mod isp_opcodes_banded;
mod isp_pipeline;
mod isp_release;
mod isp_release_checks;
mod isp_render;
mod isp_warp_window;
mod layers;
mod limits_bombs;
mod limits_files;
mod limits_metadata;
mod metrics_eval;
mod metrics_eval_damaged;
mod metrics_nonfinite;
mod msrv;
mod noise_chain;
mod noise_estimate;
mod noise_physics;
mod noise_stream;
mod noise_stream_replay;
mod png_rows;
mod real_pairs;
mod real_pairs_bad;
mod release_compat;
mod release_compat_noise;
mod release_version;
mod release_workflow;
mod runs_concurrent;
mod runs_interrupt;
mod sidecar_v1;
mod synth_burst;
mod synth_cli;
mod synth_lamps;
mod synth_readiness;
mod warning_codes;
