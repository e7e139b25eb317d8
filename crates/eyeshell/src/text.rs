//! Text in messages: core's numbers and user text ([`eyeshell_core::text`], re-exported
//! here whole), and the advice a message gives, which depends on who called the library
//! (the command line's flags or the Python package's keyword arguments). The numerics
//! never give advice: only this crate's messages, about scenes, sweeps and files, do.

pub use eyeshell_core::text::*;

/// The part of a message that depends on who called the library: the command line's flags
/// (`--set`, `--out DIR`, `--force`) mean nothing to a caller of the Python package, which
/// passes keyword arguments. A message holds the situation as an `Advice`, and
/// [`advice`] words it in the caller's terms: the command line's by default, or those of
/// the wording a front end registers once with [`set_wording`].
#[derive(Clone, Copy, Debug)]
pub enum Advice<'a> {
    /// Where a key set from outside the scene file (`key=value`) comes from, as a
    /// message's origin: `--set fibres.D=-1`.
    Override { text: &'a str },
    /// A scene file with a `[sweep]` table was given where one scene is expected: how to
    /// run the sweep.
    RunSweep { origin: &'a str },
    /// An override sets a key the sweep sweeps: what to remove.
    RemoveOverride { text: &'a str },
    /// A sweep of more runs than one process runs (`max`): how to split it.
    Shards { max: usize },
    /// The option that replaces a file eyeshell did not write.
    Force,
    /// How to set a scene key from outside the scene file (to fix a fitted parameter).
    SetKey,
    /// What lists every scene key.
    ListKeys,
    /// The option that names the struct of a .mat reference holding the result, with
    /// the name given (`None`: no name given yet).
    Field { name: Option<&'a str> },
}

/// A front end's wording of an [`Advice`].
pub type Wording = fn(&Advice<'_>) -> String;

static WORDING: std::sync::OnceLock<Wording> = std::sync::OnceLock::new();

/// Word every later [`Advice`] of this process with `wording` (a front end calls it once,
/// before its first call into the library); false if a wording was registered already.
pub fn set_wording(wording: Wording) -> bool {
    WORDING.set(wording).is_ok()
}

/// `a` in the terms of this process's front end ([`set_wording`]), else the command line's.
pub fn advice(a: &Advice<'_>) -> String {
    match WORDING.get() {
        Some(w) => w(a),
        None => command_line(a),
    }
}

/// `a` in the command line's terms.
pub fn command_line(a: &Advice<'_>) -> String {
    match *a {
        Advice::Override { text } => format!("--set {}", one_line(text)),
        Advice::RunSweep { origin } => format!("run it with `eyeshell sweep {origin} --out DIR`"),
        Advice::RemoveOverride { text } => format!("remove `--set {}`", one_line(text)),
        Advice::Shards { max } => format!(
            "run it in shards (`eyeshell sweep SCENE --out DIR --shard K/N` or --slurm-script), each at most {max} runs"
        ),
        Advice::Force => "--force".into(),
        Advice::SetKey => "--set".into(),
        Advice::ListKeys => "`eyeshell keys`".into(),
        Advice::Field { name: None } => "--field".into(),
        Advice::Field { name: Some(name) } => format!("--field {}", one_line(name)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn advice_is_the_command_lines_unless_a_front_end_words_it() {
        let cases = [
            (
                Advice::Override {
                    text: "fibres.D=-1",
                },
                "--set fibres.D=-1",
            ),
            (
                Advice::RunSweep { origin: "s.toml" },
                "run it with `eyeshell sweep s.toml --out DIR`",
            ),
            (
                Advice::RemoveOverride { text: "a=1\n" },
                "remove `--set a=1\\n`",
            ),
            (Advice::Force, "--force"),
            (Advice::SetKey, "--set"),
            (Advice::ListKeys, "`eyeshell keys`"),
            (Advice::Field { name: None }, "--field"),
            (Advice::Field { name: Some("res") }, "--field res"),
        ];
        for (a, text) in cases {
            assert_eq!(command_line(&a), text);
        }
        assert!(command_line(&Advice::Shards { max: 7 }).ends_with("each at most 7 runs"));
    }
}
