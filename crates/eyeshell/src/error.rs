//! The library's one error: a typed variant per layer, each saying what failed and where,
//! and each knowing whether it is the user's mistake ([`Error::is_user_error`]).
//!
//! The class is decided where the error is made, by its type or variant: a scene that does
//! not validate is the user's, a Newton iteration that does not converge is not. Callers
//! (the command line maps user errors to exit 2 and the rest to exit 1) never re-derive it
//! from the message.
//!
//! Bad input found outside a layer's own error types is an [`Error::Input`]: a
//! [`BadInput`] naming its [`Subject`] (the scene key, argument, column or file), the value
//! as the user wrote it and its [`Origin`] (a scene file, a `--set` or keyword override, an
//! argument, a data file). A failure is an [`Error::Failed`]: a [`Failure`] naming its
//! [`Stage`], with the typed error underneath as its source. [`Error::key`],
//! [`Error::value`] and [`Error::origin`] read them from any variant (Python's exceptions
//! carry them as attributes); Display is the one-line message alone.

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
    /// should be): what it is about, the value, where it came from, and the message.
    #[error(transparent)]
    Input(Box<BadInput>),
    /// A failure found by a caller: the stage that failed, the message saying where and why,
    /// and the typed error underneath as its [`source`](std::error::Error::source).
    #[error(transparent)]
    Failed(Box<Failure>),
}

/// What a bad input is about, in the user's terms.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Subject {
    /// A scene key (`fibres.D`, `optics.lenses[1].kind`).
    Key(String),
    /// An argument of a command or of a call (`--jobs`, `tol`, `data`).
    Argument(String),
    /// A file or directory (a scene, a data file, a run directory, an output).
    File(PathBuf),
    /// A column of a data file or table (`t`, `axial_length`, `sigma`).
    Column(String),
}

impl Subject {
    /// The key, argument, column or path as the user wrote it.
    pub fn text(&self) -> String {
        match self {
            Subject::Key(s) | Subject::Argument(s) | Subject::Column(s) => s.clone(),
            Subject::File(p) => p.display().to_string(),
        }
    }
}

/// Where a bad value came from.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Origin {
    /// A scene file, or the name a scene's text was given (`<string>`, `defaults`).
    Scene(String),
    /// An override as the caller gave it: `--set key=value`, a Python keyword argument.
    Override(String),
    /// A command-line argument or an argument of a call.
    Argument,
    /// A data file or other input file (observations, a run directory, a shard's list).
    File(PathBuf),
    /// An environment variable, by its name.
    Environment(String),
}

impl std::fmt::Display for Origin {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Origin::Scene(s) | Origin::Override(s) | Origin::Environment(s) => f.write_str(s),
            Origin::Argument => f.write_str("argument"),
            Origin::File(p) => write!(f, "{}", p.display()),
        }
    }
}

/// Bad input: what it is about, the value as the user wrote it (shortened to
/// [`BadInput::MAX_VALUE`] characters), where it came from; Display is the one-line message.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct BadInput {
    /// The key, argument, file or column the input is about, when there is one.
    pub subject: Option<Subject>,
    /// The value as the user wrote it, shortened; `None` when no single value is at fault.
    pub value: Option<String>,
    /// Where the value came from, when the message names it.
    pub origin: Option<Origin>,
    message: String,
}

impl BadInput {
    /// The most characters of a value kept (as the scene's own messages shorten them).
    pub const MAX_VALUE: usize = 80;

    /// The one-line message (Display).
    pub fn message(&self) -> &str {
        &self.message
    }

    /// The same input at fault, told by `message` (a caller's wording of it: the command
    /// line names an argument by its flag).
    pub fn reworded(mut self, message: impl Into<String>) -> Self {
        self.message = message.into();
        self
    }
}

impl std::fmt::Display for BadInput {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for BadInput {}

/// The stage of the work that failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Stage {
    /// The elastic solve of a shell.
    Solve,
    /// A growth run.
    Growth,
    /// The optics: tracing the eye, the best-focus surfaces.
    Optics,
    /// A fit's iterations.
    Fit,
    /// A sweep: its workers, its table, its shards.
    Sweep,
    /// Reading or writing a file.
    File,
    /// Drawing a figure.
    Plot,
    /// A study (convergence, extremes, figures).
    Study,
}

impl Stage {
    /// The stage's name in lower case (`solve`, `growth`, ...).
    pub fn name(self) -> &'static str {
        match self {
            Stage::Solve => "solve",
            Stage::Growth => "growth",
            Stage::Optics => "optics",
            Stage::Fit => "fit",
            Stage::Sweep => "sweep",
            Stage::File => "file",
            Stage::Plot => "plot",
            Stage::Study => "study",
        }
    }
}

/// A failure that is not the user's: its stage, the one-line message (Display) and the
/// typed error underneath, when there is one ([`source`](std::error::Error::source)).
#[derive(Debug)]
#[non_exhaustive]
pub struct Failure {
    /// The stage that failed.
    pub stage: Stage,
    message: String,
    source: Option<Box<dyn std::error::Error + Send + Sync + 'static>>,
}

impl Failure {
    /// The one-line message (Display).
    pub fn message(&self) -> &str {
        &self.message
    }
}

impl std::fmt::Display for Failure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for Failure {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        self.source
            .as_deref()
            .map(|e| e as &(dyn std::error::Error + 'static))
    }
}

impl Error {
    /// Bad input about `subject`, with the message naming what is wrong and where; add the
    /// value and its origin with [`Error::with_value`] and [`Error::with_origin`].
    pub fn input(subject: Subject, message: impl Into<String>) -> Self {
        Error::Input(Box::new(BadInput {
            subject: Some(subject),
            value: None,
            origin: None,
            message: message.into(),
        }))
    }

    /// Bad input about no one key, argument or file (a call that gives nothing to do).
    pub fn input_about_nothing(message: impl Into<String>) -> Self {
        Error::Input(Box::new(BadInput {
            subject: None,
            value: None,
            origin: None,
            message: message.into(),
        }))
    }

    /// A failure of `stage` that is not the user's, with the message saying where and why;
    /// add the typed error underneath with [`Error::with_source`].
    pub fn failed(stage: Stage, message: impl Into<String>) -> Self {
        Error::Failed(Box::new(Failure {
            stage,
            message: message.into(),
            source: None,
        }))
    }

    /// A failure of `stage` whose message is `source`'s, kept as its source.
    pub fn failed_by(stage: Stage, source: impl std::error::Error + Send + Sync + 'static) -> Self {
        Error::failed(stage, source.to_string()).with_source(source)
    }

    /// This bad input with the value as the user wrote it (shortened); other errors as
    /// they are.
    pub fn with_value(mut self, value: impl std::fmt::Display) -> Self {
        if let Error::Input(b) = &mut self {
            b.value = Some(crate::text::excerpt(
                &value.to_string(),
                BadInput::MAX_VALUE,
            ));
        }
        self
    }

    /// This bad input with where its value came from; other errors as they are.
    pub fn with_origin(mut self, origin: Origin) -> Self {
        if let Error::Input(b) = &mut self {
            b.origin = Some(origin);
        }
        self
    }

    /// This failure with the typed error underneath as its source; other errors as they
    /// are.
    pub fn with_source(mut self, source: impl std::error::Error + Send + Sync + 'static) -> Self {
        if let Error::Failed(f) = &mut self {
            f.source = Some(Box::new(source));
        }
        self
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

    /// The scene key, argument, column or file the error is about, when there is one (a
    /// scene's error names its key; a failure of the computation names none).
    pub fn key(&self) -> Option<String> {
        match self {
            Error::Scene(e) => e.key().map(str::to_string),
            Error::Input(b) => b.subject.as_ref().map(Subject::text),
            Error::Output(OutputError::Refused { path }) => Some(path.display().to_string()),
            _ => None,
        }
    }

    /// The value at fault as the user wrote it (shortened), when one is.
    pub fn value(&self) -> Option<String> {
        match self {
            Error::Scene(e) => e
                .value()
                .map(|v| crate::text::excerpt(v, BadInput::MAX_VALUE)),
            Error::Input(b) => b.value.clone(),
            _ => None,
        }
    }

    /// Where the input at fault came from (a scene file's path, `--set key=value` or its
    /// Python keyword, a data file), when the error names it.
    pub fn origin(&self) -> Option<String> {
        match self {
            Error::Scene(e) => Some(e.origin().to_string()),
            Error::Input(b) => b.origin.as_ref().map(Origin::to_string),
            _ => None,
        }
    }

    /// The stage a failure stopped in (`None` for bad input).
    pub fn stage(&self) -> Option<Stage> {
        match self {
            Error::Failed(f) => Some(f.stage),
            Error::Bvp(_) | Error::Sundials(_) => Some(Stage::Solve),
            Error::Growth(_) | Error::GrowthRhs(_) => Some(Stage::Growth),
            Error::Io { .. } => Some(Stage::File),
            Error::Output(e) if !e.is_refusal() => Some(Stage::File),
            Error::Read(e) if !e.bad_input => Some(Stage::File),
            _ => None,
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
        let jobs = Error::input(Subject::Argument("--jobs".into()), "--jobs 0").with_value(0);
        assert!(jobs.is_user_error());
        assert_eq!(jobs.key().as_deref(), Some("--jobs"));
        assert_eq!(jobs.value().as_deref(), Some("0"));
        assert_eq!(jobs.origin(), None);
        let shard = crate::sweep::shard::Shard::new(4, 3).unwrap_err();
        assert!(Error::from(shard).is_user_error());
        assert!(!Error::failed(Stage::Solve, "diverged").is_user_error());
        assert!(Error::from(crate::rundir::read::bad("no summary.json")).is_user_error());
        assert!(Error::from(ModelError::NegativePressure { dp: -1.0 }).is_user_error());
        assert!(!Error::Io {
            path: PathBuf::from("f"),
            source: std::io::Error::other("x")
        }
        .is_user_error());
        assert_eq!(
            Error::failed(Stage::Fit, "one line").to_string(),
            "one line"
        );
    }

    #[test]
    fn bad_input_keeps_its_subject_value_and_origin_and_shortens_the_value() {
        let long = "9".repeat(500);
        let e = Error::input(Subject::Key("fibres.D".into()), "f.toml: fibres.D = … bad")
            .with_value(&long)
            .with_origin(Origin::Scene("f.toml".into()));
        assert_eq!(e.to_string(), "f.toml: fibres.D = … bad");
        assert_eq!(e.key().as_deref(), Some("fibres.D"));
        assert_eq!(e.value(), Some(format!("{}…", "9".repeat(80))));
        assert_eq!(e.origin().as_deref(), Some("f.toml"));
        assert_eq!(e.stage(), None);
        let file = Error::input(Subject::File("obs.csv".into()), "obs.csv: empty file")
            .with_origin(Origin::File("obs.csv".into()));
        assert_eq!(
            (file.key().as_deref(), file.origin().as_deref()),
            (Some("obs.csv"), Some("obs.csv"))
        );
        // A value or origin given to a failure is not kept: a failure is not about input.
        let f = Error::failed(Stage::Fit, "x")
            .with_value(1)
            .with_origin(Origin::Argument);
        assert_eq!((f.key(), f.value(), f.origin()), (None, None, None));
    }

    #[test]
    fn a_failure_names_its_stage_and_keeps_its_source() {
        use std::error::Error as _;
        let io = std::io::Error::other("disk full");
        let e = Error::failed(Stage::File, "out.csv: disk full").with_source(io);
        assert_eq!(e.to_string(), "out.csv: disk full");
        assert_eq!(e.stage(), Some(Stage::File));
        let source = e.source().expect("the io error underneath");
        assert_eq!(source.to_string(), "disk full");
        assert!(source.downcast_ref::<std::io::Error>().is_some());
        let by = Error::failed_by(Stage::Solve, ModelError::NegativePressure { dp: -1.0 });
        assert_eq!(
            by.to_string(),
            ModelError::NegativePressure { dp: -1.0 }.to_string()
        );
        assert!(by.source().unwrap().downcast_ref::<ModelError>().is_some());
        assert!(Error::failed(Stage::Fit, "x").source().is_none());
        assert_eq!(Stage::Growth.name(), "growth");
    }

    #[test]
    fn a_scenes_error_gives_its_key_value_and_origin() {
        let e: Error = crate::Scene::from_toml_str("[fibres]\nD = -3\n", "s.toml", &[])
            .unwrap_err()
            .into();
        assert_eq!(e.key().as_deref(), Some("fibres.D"));
        assert_eq!(e.value().as_deref(), Some("-3"));
        assert_eq!(e.origin().as_deref(), Some("s.toml"));
        let e: Error = crate::Scene::from_toml_str("", "s.toml", &["fibres.D=-1".into()])
            .unwrap_err()
            .into();
        assert_eq!(e.origin().as_deref(), Some("--set fibres.D=-1"));
        let reworded = match Error::input(Subject::Argument("x".into()), "a") {
            Error::Input(b) => b.reworded("b"),
            _ => unreachable!(),
        };
        assert_eq!(
            (reworded.message(), reworded.subject.clone()),
            ("b", Some(Subject::Argument("x".into())))
        );
    }
}
