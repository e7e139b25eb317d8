//! The subcommands' bodies, a file per group; each `cmd_*` returns the library's one error.

pub(crate) mod fit;
pub(crate) mod interop;
pub(crate) mod optics;
pub(crate) mod run;
pub(crate) mod shards;
pub(crate) mod study;
pub(crate) mod sweep;
