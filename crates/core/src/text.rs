//! Numbers in messages: exact where it matters and never 300 digits long (a subnormal or a
//! value near the float maximum printed with `{}` or `{:.6}` fills a terminal).

/// `x` exactly (the shortest form that reads back to the same f64), in scientific notation
/// outside [1e-4, 1e15): `2.5`, `0.001`, `1e-300`, `2.5e307`. At most about 24 characters.
pub fn number(x: f64) -> String {
    if x.is_nan() {
        "nan".into() // as TOML spells it
    } else if x == 0.0 || x.is_infinite() || (1e-4..1e15).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// `x` as TOML writes a float: the shortest form that reads back to the same f64, with
/// `nan`, `inf` and `-inf` for the values JSON lacks (`2.5`, `1e-300`, `inf`).
pub fn toml_float(x: f64) -> String {
    if x.is_nan() {
        "nan".into()
    } else if x.is_infinite() {
        (if x > 0.0 { "inf" } else { "-inf" }).into()
    } else {
        format!("{x:?}")
    }
}

/// `x` with 6 decimals where that shows it (|x| in [1e-4, 1e9), or 0), else 6 significant
/// digits in scientific notation: `5.932091`, `1.234568e-7`. At most about 17 characters.
pub fn decimals6(x: f64) -> String {
    decimals(x, 6)
}

/// `x` with `places` decimals where that shows it (|x| in [1e-4, 1e9), or 0), else
/// `places` significant digits after the point in scientific notation: `decimals(2.5, 4)`
/// is `2.5000`, `decimals(1e300, 4)` is `1.0000e300`.
pub fn decimals(x: f64, places: usize) -> String {
    if x == 0.0 || !x.is_finite() || (1e-4..1e9).contains(&x.abs()) {
        format!("{x:.places$}")
    } else {
        format!("{x:.places$e}")
    }
}

/// Text from a user's file, made safe to print on one line: every control character
/// (line breaks, escape sequences that would drive the terminal) is shown escaped, `\n`,
/// `\u{1b}`, instead of acting.
pub fn one_line(s: &str) -> String {
    s.chars()
        .flat_map(|c| {
            let escaped: Vec<char> = if c.is_control() {
                c.escape_debug().collect()
            } else {
                vec![c]
            };
            escaped
        })
        .collect()
}

/// At most `max` characters of text from a user's file, on one line ([`one_line`]), with
/// `…` where it was cut: what a message quotes of a line that may be a megabyte long.
pub fn excerpt(s: &str, max: usize) -> String {
    match s.char_indices().nth(max) {
        Some((cut, _)) => format!("{}…", one_line(&s[..cut])),
        None => one_line(s),
    }
}

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

    #[test]
    fn excerpts_are_short_and_clean() {
        assert_eq!(excerpt("abc", 3), "abc");
        assert_eq!(excerpt("abcd", 3), "abc…");
        assert_eq!(excerpt("ΣΣΣΣ", 2), "ΣΣ…");
        assert_eq!(excerpt("a\nb", 10), "a\\nb");
        assert_eq!(excerpt("a\nb", 10).len(), 4);
        assert_eq!(excerpt(&"1".repeat(1 << 20), 80).chars().count(), 81);
    }

    #[test]
    fn control_characters_are_shown_not_obeyed() {
        assert_eq!(one_line("a\nb\u{1b}[31mred\r"), "a\\nb\\u{1b}[31mred\\r");
        assert_eq!(one_line("Σ = 1, ΔP"), "Σ = 1, ΔP");
    }

    #[test]
    fn short_and_exact() {
        assert_eq!(number(2.5), "2.5");
        assert_eq!(number(0.001), "0.001");
        assert_eq!(number(1e-300), "1e-300");
        assert_eq!(number(-2.5e307), "-2.5e307");
        assert_eq!(number(5e-324), "5e-324");
        assert_eq!(number(f64::MAX).parse::<f64>().unwrap(), f64::MAX);
        assert_eq!(number(f64::INFINITY), "inf");
        assert_eq!(number(f64::NEG_INFINITY), "-inf");
        assert_eq!(number(f64::NAN), "nan");
        assert_eq!(decimals6(5.9320914), "5.932091");
        assert_eq!(decimals6(0.0), "0.000000");
        assert_eq!(decimals6(1.2345678e-7), "1.234568e-7");
        assert_eq!(decimals6(1e300), "1.000000e300");
        assert_eq!(decimals(1e300, 4), "1.0000e300");
        assert_eq!(decimals(2.5, 4), "2.5000");
        for x in [f64::MIN_POSITIVE, 1e-310, 1e308, -1e-100, 123456789012.0] {
            assert!(number(x).len() <= 24 && decimals6(x).len() <= 17, "{x:e}");
        }
    }
}
