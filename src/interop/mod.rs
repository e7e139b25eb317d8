//! Other people's formats: MATLAB v5 .mat and NumPy .npz, read and written; `eyeshell
//! export` (a run directory as bvp4c-style files) and `eyeshell compare` (a run against
//! reference results).

pub mod compare;
pub mod export;
pub mod mat;
pub mod npz;

pub use mat::MatValue;
