//! The numerics that need the files crate: scenes read from their files or text, the facade
//! (`Scene`, `Solution`, `fit`) never panicking, and the optics of the shipped scenes. The
//! numerics that need none of it are eyeshell-core's (crates/core/tests/numerics).
//!
//! One test binary for the group: one link instead of one per module.

mod api_never_panics;
mod custom_eye;
mod run_rays;
mod shipped_scenes;
