//! The safe solvers against nalgebra's dense LU: random band, almost-block-diagonal and
//! bordered matrices, their structure's edge cases and near-singular ones.
//!
//! One test binary for the group: one link instead of one per module.

mod support;

mod abd;
mod band_lu;
