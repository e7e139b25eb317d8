//! User text made into shell words: paths, `--set` values and commands that eyeshell
//! prints for a user to paste or writes into a script (`sweep --slurm-script`). Every
//! such word goes through [`word`] (or [`posix_word`] where `sh` reads it), so that what
//! a path says is never run, and a word never spans lines: a line break inside a comment
//! line would end the comment, and the rest would be a command (and sbatch stops reading
//! `#SBATCH` lines at the first command).

use std::ffi::OsStr;
use std::os::unix::ffi::OsStrExt;

/// Bytes that never need quoting in a word.
fn plain(b: u8) -> bool {
    b.is_ascii_alphanumeric() || b"/._-=+:,@%".contains(&b)
}

/// `text` as one shell word on one line, for bash (the scripts' shell) and the shells a
/// user pastes into (bash, zsh, ksh): as it is when every byte is plain, else POSIX
/// single quotes (`'` written `'\''`), or, when it holds a control character or bytes
/// that are not UTF-8, bash's `$'...'` with those escaped (`\n`, `\xHH`), which reads back
/// to exactly the same bytes.
pub(crate) fn word(text: impl AsRef<OsStr>) -> String {
    let bytes = text.as_ref().as_bytes();
    if !bytes.is_empty() && bytes.iter().all(|&b| plain(b)) {
        // Plain ASCII: the bytes are the text.
        return String::from_utf8_lossy(bytes).into_owned();
    }
    match std::str::from_utf8(bytes) {
        Ok(s) if !s.chars().any(char::is_control) => single_quoted(s),
        _ => ansi_c_quoted(bytes),
    }
}

/// `text` as one word for POSIX `sh` (which has no `$'...'`): single quotes, `'` written
/// `'\''`; a line break stays a line break inside the quotes, where sh reads it as part of
/// the word. For a command nested in another word (sbatch's `--wrap`, run by `sh`), which
/// [`word`] then quotes onto one line.
pub(crate) fn posix_word(text: impl AsRef<OsStr>) -> Vec<u8> {
    let bytes = text.as_ref().as_bytes();
    if !bytes.is_empty() && bytes.iter().all(|&b| plain(b)) {
        return bytes.to_vec();
    }
    let mut out = vec![b'\''];
    for &b in bytes {
        match b {
            b'\'' => out.extend_from_slice(br"'\''"),
            b => out.push(b),
        }
    }
    out.push(b'\'');
    out
}

fn single_quoted(s: &str) -> String {
    format!("'{}'", s.replace('\'', r"'\''"))
}

/// bash's ANSI-C quoting: printable text as it is, `\\` and `\'` escaped, every other byte
/// (controls, DEL, bytes of invalid UTF-8) as `\xHH` with both digits, so that a hex digit
/// after it is not taken into the escape. Valid non-ASCII UTF-8 stays as it is.
fn ansi_c_quoted(bytes: &[u8]) -> String {
    let mut out = String::from("$'");
    let mut rest = bytes;
    while !rest.is_empty() {
        let (valid, bad) = match std::str::from_utf8(rest) {
            Ok(s) => (s, &[][..]),
            Err(e) => {
                let (good, after) = rest.split_at(e.valid_up_to());
                // The part before the error is valid by construction.
                (std::str::from_utf8(good).unwrap_or_default(), after)
            }
        };
        for c in valid.chars() {
            match c {
                '\\' => out.push_str(r"\\"),
                '\'' => out.push_str(r"\'"),
                '\n' => out.push_str(r"\n"),
                '\t' => out.push_str(r"\t"),
                c if c.is_control() => {
                    let mut buf = [0; 4];
                    for b in c.encode_utf8(&mut buf).bytes() {
                        out.push_str(&format!("\\x{b:02x}"));
                    }
                }
                c => out.push(c),
            }
        }
        rest = match bad.first() {
            Some(&b) => {
                out.push_str(&format!("\\x{b:02x}"));
                &bad[1..]
            }
            None => &[],
        };
    }
    out.push('\'');
    out
}

/// A command line of `words`, each quoted by [`word`].
pub(crate) fn command<I, S>(words: I) -> String
where
    I: IntoIterator<Item = S>,
    S: AsRef<OsStr>,
{
    words.into_iter().map(word).collect::<Vec<_>>().join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::process::Command;

    /// What bash makes of `line`: the words it passes to a command.
    fn bash_words(line: &str) -> Vec<Vec<u8>> {
        let out = Command::new("bash")
            .arg("-c")
            .arg(format!("printf '%s\\0' {line}"))
            .output()
            .unwrap();
        assert!(out.status.success(), "{line}");
        out.stdout
            .split(|&b| b == 0)
            .filter(|w| !w.is_empty())
            .map(<[u8]>::to_vec)
            .collect()
    }

    fn hostile() -> Vec<Vec<u8>> {
        let mut cases: Vec<Vec<u8>> = [
            "plain/path-1.toml",
            "a b",
            "it's",
            "''",
            "\\'",
            "$(touch /tmp/eyeshell-canary)",
            "`touch /tmp/eyeshell-canary`",
            "line\nbreak\n#SBATCH --array=1-9\ntouch /tmp/eyeshell-canary",
            "tab\tcr\rbell\u{7}esc\u{1b}[31m del\u{7f}",
            "\\x41 \\n $HOME ${HOME} !! * ? [a] ~ & ; | < > #",
            "Σ ΔP — ünï\u{85}code",
            "\u{1b}\nx1f",
        ]
        .iter()
        .map(|s| s.as_bytes().to_vec())
        .collect();
        cases.push(b"bad \xff\xfe utf8 \xc3".to_vec());
        cases.push(b"\xff1".to_vec());
        cases
    }

    #[test]
    fn every_word_reads_back_as_itself_on_one_line() {
        for case in hostile() {
            let w = word(OsStr::from_bytes(&case));
            assert!(!w.contains('\n') && !w.contains('\r'), "{w}");
            assert!(!w.chars().any(char::is_control), "{w:?}");
            assert_eq!(bash_words(&w), vec![case.clone()], "{w}");
        }
        assert_eq!(word("out/x-1.toml"), "out/x-1.toml");
        assert_eq!(word("a b"), "'a b'");
        assert_eq!(word("it's"), r"'it'\''s'");
        assert_eq!(word("a\nb"), r"$'a\nb'");
        assert_eq!(word(""), "''");
    }

    #[test]
    fn posix_words_read_back_in_sh() {
        for case in hostile() {
            let w = posix_word(OsStr::from_bytes(&case));
            let mut script = b"printf '%s\\0' ".to_vec();
            script.extend_from_slice(&w);
            let out = Command::new("sh")
                .arg("-c")
                .arg(OsStr::from_bytes(&script))
                .output()
                .unwrap();
            assert_eq!(out.stdout[..out.stdout.len() - 1], case[..], "{w:?}");
        }
    }
}
