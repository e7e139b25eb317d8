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

#[cfg(test)]
mod tests {
    use super::*;

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
