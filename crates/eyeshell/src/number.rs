//! One number in eyeshell's CSV files: the shortest decimal that reads back to the same
//! f64, laid out as Python's `repr` lays it out, so that a file reads as a person (and
//! pandas, numpy, a spreadsheet) expects: `22.63564555774848`, `8.0`, `400.0`, `0.0001`,
//! `1e-05`, `1e+16`, `-2.5e+17`, `5e-324`.
//!
//! - The digits are the shortest that round-trip (ryu's); where two candidates of that
//!   length are equally near, the even one, as Python's `repr` chooses (and unlike Rust's
//!   `{:e}`, which rounds such ties away from zero; both read back exactly).
//! - Positional when the decimal exponent `x` (of `d.ddd × 10^x`) is in −4 ≤ x < 16, with
//!   at least one digit after the point (`8.0`); otherwise `d.ddde±XX`, the exponent's sign
//!   always and at least two digits (`1e-05`, `1.5e+300`). Zero is `0.0` (`-0.0`).
//! - Not a number and the infinities are written `NaN`, `inf` and `-inf`, as eyeshell always
//!   wrote them (Python writes `nan`; every reader here, Python's float() and pandas read
//!   both).
//!
//! Every reader (Rust's `str::parse::<f64>`, Python's `float`, pandas) reads these and the
//! `{:e}` form eyeshell wrote before (`2.263564555774848e1`, `8e0`) alike, and to the same
//! f64. The tests check the output against Python's own `repr` (python_repr.txt) and the
//! round trip over two million values.

/// One value as text ([`push_value`]).
pub fn format_value(x: f64) -> String {
    let mut out = Vec::with_capacity(24);
    push_value(&mut out, x);
    String::from_utf8(out).expect("digits, signs, '.', 'e', NaN and inf are ASCII")
}

/// Append [`format_value`]`(x)` to `out` without allocating: a snapshot of 501 nodes holds
/// 10 000 values and a cohort's tables millions, so this is in every row eyeshell writes.
/// ryu writes the shortest digits in nearly Python's layout (positional for
/// 1e-5 ≤ |x| < 1e16 with `.0` on an integer, else `1.5e16`, `1e-7`), so its text is
/// copied and only where the two differ rewritten: the exponent's sign and two digits, and
/// 1e-5 ≤ |x| < 1e-4, which ryu writes `0.0000ddd` and Python `d.ddde-05`.
pub fn push_value(out: &mut Vec<u8>, x: f64) {
    if !x.is_finite() {
        out.extend_from_slice(match (x.is_nan(), x > 0.0) {
            (true, _) => b"NaN",
            (false, true) => b"inf",
            (false, false) => b"-inf",
        });
        return;
    }
    let mut buffer = ryu::Buffer::new();
    let text = buffer.format_finite(x).as_bytes();
    if let Some(e) = text.iter().position(|&c| c == b'e') {
        out.extend_from_slice(&text[..=e]);
        let (sign, digits) = match &text[e + 1..] {
            [b'-', rest @ ..] => (b'-', rest),
            rest => (b'+', rest),
        };
        out.push(sign);
        if digits.len() < 2 {
            out.push(b'0');
        }
        out.extend_from_slice(digits);
        return;
    }
    let (negative, unsigned) = match text {
        [b'-', rest @ ..] => (true, rest),
        rest => (false, rest),
    };
    match unsigned.strip_prefix(b"0.0000") {
        Some([first, rest @ ..]) => {
            if negative {
                out.push(b'-');
            }
            out.push(*first);
            if !rest.is_empty() {
                out.push(b'.');
                out.extend_from_slice(rest);
            }
            out.extend_from_slice(b"e-05");
        }
        _ => out.extend_from_slice(text),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Python's own repr of 1,200 values (`python3`: random bit patterns, values as a run
    /// computes them, ties at the 17th digit, powers of ten, the edges of the positional
    /// range and of the f64s), as bits and text.
    const PYTHON_REPR: &str = include_str!("python_repr.txt");

    #[test]
    fn values_are_written_as_python_writes_them() {
        let mut n = 0;
        for line in PYTHON_REPR.lines().filter(|l| !l.starts_with('#')) {
            let (bits, repr) = line.split_once(' ').unwrap();
            let x = f64::from_bits(u64::from_str_radix(bits, 16).unwrap());
            assert_eq!(format_value(x), repr, "{x:e}");
            n += 1;
        }
        assert_eq!(n, 1200);
        for (x, text) in [
            (22.63564555774848, "22.63564555774848"),
            (8.0, "8.0"),
            (400.0, "400.0"),
            (1e-300, "1e-300"),
            (1e-5, "1e-05"),
            (1e-4, "0.0001"),
            (1e16, "1e+16"),
            (1e15, "1000000000000000.0"),
            (-2.5e17, "-2.5e+17"),
            (-0.0, "-0.0"),
            (f64::NAN, "NaN"),
            (f64::INFINITY, "inf"),
            (f64::NEG_INFINITY, "-inf"),
        ] {
            assert_eq!(format_value(x), text);
        }
    }

    /// Every value reads back to its own bits, over two million (random bit patterns of
    /// every magnitude, and values as a run computes them), in at most
    /// [`crate::rundir::growth::CELL_BYTES`] − 1 bytes, and in the layout of the module doc.
    #[test]
    fn values_read_back_exactly() {
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        let mut out = Vec::new();
        for k in 0..2_000_000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let x = if k % 2 == 0 {
                f64::from_bits(state)
            } else {
                let unit = (state >> 11) as f64 / (1u64 << 53) as f64;
                (unit - 0.5) * 10f64.powi(k % 41 - 20)
            };
            out.clear();
            push_value(&mut out, x);
            let text = std::str::from_utf8(&out).unwrap();
            let back: f64 = text.parse().unwrap();
            if x.is_nan() {
                assert!(back.is_nan() && text == "NaN");
                continue;
            }
            assert_eq!(back.to_bits(), x.to_bits(), "{text}");
            assert!(
                out.len() < crate::rundir::growth::CELL_BYTES as usize,
                "{text}"
            );
            let positional = x.is_finite() && (x == 0.0 || (1e-4..1e16).contains(&x.abs()));
            assert_eq!(!text.contains('e'), positional || !x.is_finite(), "{text}");
            if positional {
                assert!(text.contains('.'), "{text}");
            }
            // The same digits as Rust's shortest ({:e}), but at a tie of the last digit.
            let rust = format!("{:e}", x.abs());
            let rust_digits: String = rust.split('e').next().unwrap().replace('.', "");
            let ours: String = text
                .trim_start_matches('-')
                .split('e')
                .next()
                .unwrap()
                .replace('.', "")
                .trim_start_matches('0')
                .trim_end_matches('0')
                .to_string();
            if x != 0.0 && x.is_finite() {
                assert_eq!(
                    ours.len(),
                    rust_digits.trim_end_matches('0').len(),
                    "{text} {rust}"
                );
            }
        }
    }
}
