//! The command line and what it writes: exit codes, one-line errors, run directories, exports, comparisons, studies and figures.
//!
//! One test binary for the group: one link instead of one per module.

mod support;

mod absurd;
mod bad_input;
mod cohorts;
mod destinations;
mod docs;
mod drawn_optics;
mod export_bvp4c;
mod export_compare;
mod export_roundtrip;
mod export_scipy;
mod extremes;
mod eyewear;
mod figures;
mod fit;
mod fuzz_eye;
mod fuzz_readers;
mod fuzz_run_files;
mod fuzz_scene;
mod golden;
mod grow;
mod hostile;
mod image;
mod keys_check;
mod layers;
mod max_seconds;
mod optics;
mod ownership;
mod peer;
mod plan;
mod readers;
mod refraction;
mod rerun;
mod rooms;
mod rules;
mod sensitivities;
mod shards;
mod signatures;
mod slurm;
mod solve;
mod status;
mod study;
mod sweep;
mod through;
mod trials;
mod typed_errors;
mod years;
