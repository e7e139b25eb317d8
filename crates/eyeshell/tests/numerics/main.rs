//! The numerics that need the files crate: scenes read from their files or text, the facade
//! (`Scene`, `Solution`, `fit`) never panicking, and the optics of the shipped scenes. The
//! numerics that need none of it are eyeshell-core's (crates/core/tests/numerics), but for
//! the growth solver.tol sweep (`growth_tol_sweep`, about 280 s of CPU), kept here so that
//! `cargo test -p eyeshell-core` stays quick; it shares core's helpers (common.rs).
//!
//! One test binary for the group: one link instead of one per module.

#[path = "../../../core/tests/numerics/common.rs"]
mod common;

mod api_never_panics;
mod custom_eye;
mod growth_tol_sweep;
mod optics_schedule;
mod run_rays;
mod shipped_scenes;
