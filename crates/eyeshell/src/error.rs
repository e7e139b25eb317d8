//! The library's one error: a typed variant per layer, each saying what failed and where,
//! and each knowing whether it is the user's mistake ([`Error::is_user_error`]).
//!
//! The class is decided where the error is made, by its type or variant: a scene that does
//! not validate is the user's, a Newton iteration that does not converge is not. Callers
//! (the command line maps user errors to exit 2 and the rest to exit 1) never re-derive it
//! from the message.

use std::path::PathBuf;

use crate::bvp::BvpError;
use crate::growth::system::RhsError;
use crate::growth::GrowthError;
use crate::model::ModelError;
use crate::rundir::read::ReadError;
use crate::rundir::OutputError;
use crate::scene::SceneError;
use eyeshell_sundials::SundialsError;

/// Everything that can go wrong in eyeshell, one line each (Display has no line breaks of
/// its own; a message quoting a file may, and printers escape it).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A scene that does not parse or validate, or overrides that do not apply (user).
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// Parameters for which the model has no answer, e.g. ΔP above the cornea's limit (user).
    #[error(transparent)]
    Model(#[from] ModelError),
    /// The elastic solve failed: where, and why (not the user's).
    #[error(transparent)]
    Bvp(#[from] BvpError),
    /// SUNDIALS refused or failed (not the user's).
    #[error(transparent)]
    Sundials(#[from] SundialsError),
    /// A growth run stopped: when, why, and the work done (not the user's).
    #[error(transparent)]
    Growth(Box<GrowthError>),
    /// A growth right-hand side could not be evaluated (not the user's).
    #[error(transparent)]
    GrowthRhs(#[from] RhsError),
    /// Writing results: the user's when the target may not be written (a foreign file or
    /// directory, a path without a name), otherwise a failure of the file system.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// Reading a run directory back: the user's when the run is missing or malformed,
    /// otherwise a failure.
    #[error(transparent)]
    Read(#[from] ReadError),
    /// A sweep's shard that cannot be had: `--shard K/N` out of range, or a Slurm job
    /// array's environment that does not give one (user).
    #[error(transparent)]
    Shard(#[from] crate::sweep::shard::ShardError),
    /// A file that could not be read or written (not the user's).
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    /// Bad input found by a caller (an argument out of range, a file that is not what it
    /// should be): the message says what and where.
    #[error("{0}")]
    Input(String),
    /// A failure found by a caller: the message says where and why.
    #[error("{0}")]
    Failed(String),
}

impl Error {
    /// Bad input, with the message naming what is wrong and where.
    pub fn input(message: impl Into<String>) -> Self {
        Error::Input(message.into())
    }

    /// A failure that is not the user's, with the message saying where and why.
    pub fn failed(message: impl Into<String>) -> Self {
        Error::Failed(message.into())
    }

    /// Is this the user's mistake (bad input: the command line exits 2), rather than a
    /// failure of the computation or of the machine (exit 1)?
    pub fn is_user_error(&self) -> bool {
        match self {
            Error::Scene(_) | Error::Model(_) | Error::Shard(_) | Error::Input(_) => true,
            Error::Output(e) => e.is_refusal(),
            Error::Read(e) => e.bad_input,
            Error::Bvp(_)
            | Error::Sundials(_)
            | Error::Growth(_)
            | Error::GrowthRhs(_)
            | Error::Io { .. }
            | Error::Failed(_) => false,
        }
    }
}

impl From<GrowthError> for Error {
    fn from(e: GrowthError) -> Self {
        Error::Growth(Box::new(e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_class_follows_the_variant() {
        let refused = OutputError::Refused {
            path: PathBuf::from("x"),
        };
        let io = OutputError::Io {
            path: PathBuf::from("x"),
            source: std::io::Error::other("disk full"),
        };
        assert!(Error::from(refused).is_user_error());
        assert!(!Error::from(io).is_user_error());
        assert!(Error::input("--jobs 0").is_user_error());
        let shard = crate::sweep::shard::Shard::new(4, 3).unwrap_err();
        assert!(Error::from(shard).is_user_error());
        assert!(!Error::failed("diverged").is_user_error());
        assert!(Error::from(crate::rundir::read::bad("no summary.json")).is_user_error());
        assert!(Error::from(ModelError::NegativePressure { dp: -1.0 }).is_user_error());
        assert!(!Error::Io {
            path: PathBuf::from("f"),
            source: std::io::Error::other("x")
        }
        .is_user_error());
        assert_eq!(Error::failed("one line").to_string(), "one line");
    }
}
