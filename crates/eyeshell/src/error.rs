//! The crate's error: one typed variant per layer, each saying what failed and where.

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(transparent)]
    Scene(#[from] crate::scene::SceneError),
    #[error(transparent)]
    Model(#[from] crate::model::ModelError),
    #[error(transparent)]
    Bvp(#[from] crate::bvp::BvpError),
    #[error(transparent)]
    Sundials(#[from] eyeshell_sundials::SundialsError),
    #[error(transparent)]
    Growth(Box<crate::growth::GrowthError>),
    #[error(transparent)]
    GrowthRhs(#[from] crate::growth::system::RhsError),
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}
