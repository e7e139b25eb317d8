//! Other people's formats: MATLAB v5 .mat and NumPy .npz, read and written; `eyeshell
//! export` (a run directory as bvp4c-style files) and `eyeshell compare` (a run against
//! reference results).

pub mod compare;
pub mod export;
pub mod interp;
pub mod mat;
pub mod npz;

pub use mat::MatValue;

/// What the .mat and .npz readers may spend on one file, whatever the file says.
///
/// Every size a file declares (dimensions, element lengths, zip members) is checked against
/// the bytes actually present and against this budget before anything is allocated; the
/// arithmetic is checked, so an overflowing product is an error like any other.
///
/// The defaults, and why:
/// - `max_bytes` = 1 GiB: everything a reader allocates beyond the file's own bytes, that
///   is decompressed data and decoded values (8 bytes per value, whatever the stored type)
///   together. A bvp4c solution of a million mesh points (x, y and yp: 88 MB) fits ten
///   times over; peak memory of a read stays under the file plus 1 GiB. A file larger than
///   this is refused before it is read.
/// - `max_ratio` = 128: decompressed bytes at most 128 times the file's size (plus 1 MiB,
///   so that small files of constant arrays pass). Solutions compress about 1.1–5:1
///   (double precision noise does not compress); only constant arrays approach deflate's
///   own ceiling of 1032:1, and a file refused for this can be saved uncompressed
///   (`save -v6`, `np.savez`). A 3 MB bomb gets at most 385 MB, not the 1 GiB.
/// - `max_depth` = 32: structs and cells nested deeper are refused (bvp4c's `sol.stats` is
///   depth 2); recursion stays far from the stack's end.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ReadLimits {
    pub max_bytes: u64,
    pub max_ratio: u64,
    pub max_depth: usize,
}

impl Default for ReadLimits {
    fn default() -> Self {
        ReadLimits {
            max_bytes: 1 << 30,
            max_ratio: 128,
            max_depth: 32,
        }
    }
}

/// Decompressed bytes always allowed on top of `max_ratio` times the file's size.
const RATIO_SLACK: u64 = 1 << 20;

/// The allowance of one read: bytes left to allocate, and to inflate.
#[derive(Debug)]
pub(crate) struct Budget {
    limits: ReadLimits,
    bytes_left: u64,
    inflate_left: u64,
    inflate_by_ratio: bool,
}

impl Budget {
    /// The budget for reading a file of `input_len` bytes.
    pub(crate) fn new(limits: &ReadLimits, input_len: usize) -> Budget {
        let by_ratio = limits
            .max_ratio
            .saturating_mul(input_len as u64)
            .saturating_add(RATIO_SLACK);
        Budget {
            limits: *limits,
            bytes_left: limits.max_bytes,
            inflate_left: by_ratio.min(limits.max_bytes),
            inflate_by_ratio: by_ratio < limits.max_bytes,
        }
    }

    /// Charge `bytes` about to be allocated.
    pub(crate) fn take(&mut self, bytes: u64) -> Result<(), String> {
        match self.bytes_left.checked_sub(bytes) {
            Some(left) => {
                self.bytes_left = left;
                Ok(())
            }
            None => Err(format!(
                "holds more than {} once decoded (the limit of eyeshell's readers)",
                human_bytes(self.limits.max_bytes)
            )),
        }
    }

    /// Charge `bytes` about to be decompressed (they count against both allowances).
    pub(crate) fn inflate(&mut self, bytes: u64) -> Result<(), String> {
        match self.inflate_left.checked_sub(bytes) {
            Some(left) => {
                self.inflate_left = left;
                self.take(bytes)
            }
            None if self.inflate_by_ratio => Err(format!(
                "compressed data inflates to more than {} times the file's size (refused as a \
                 decompression bomb; save the data uncompressed if it is genuine)",
                self.limits.max_ratio
            )),
            None => self.take(u64::MAX),
        }
    }
}

/// `n` bytes in the largest binary unit that divides them into a number of at least 1.
pub(crate) fn human_bytes(n: u64) -> String {
    const UNITS: [&str; 4] = ["GiB", "MiB", "KiB", "bytes"];
    for (k, unit) in UNITS.iter().enumerate() {
        let scale = 1u64 << (10 * (3 - k));
        if n >= scale && k < 3 {
            return if n.is_multiple_of(scale) {
                format!("{} {unit}", n / scale)
            } else {
                format!("{:.1} {unit}", n as f64 / scale as f64)
            };
        }
    }
    format!("{n} bytes")
}

/// `s` safe to print on one line of a terminal: control characters (newlines, escapes)
/// spelled as Rust escapes, everything else as it is.
pub(crate) fn printable(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_control() {
                c.escape_default().to_string()
            } else {
                c.to_string()
            }
        })
        .collect()
}

/// Read `n` more bytes from `r` onto the end of `out`, growing `out` geometrically but
/// never beyond what is asked for (a stream that lies about its length costs what it
/// delivers, not what it claims). Fails if the stream ends early.
pub(crate) fn read_exact_capped<R: std::io::Read>(
    r: &mut R,
    out: &mut Vec<u8>,
    n: usize,
) -> Result<(), String> {
    let target = out
        .len()
        .checked_add(n)
        .ok_or_else(|| "a length overflows".to_string())?;
    let mut got = 0usize;
    while out.len() < target {
        let step = (target - out.len()).min(out.len().max(1 << 16));
        out.reserve_exact(step);
        let start = out.len();
        out.resize(start + step, 0);
        r.read_exact(&mut out[start..]).map_err(|e| {
            if e.kind() == std::io::ErrorKind::UnexpectedEof {
                format!("data ends after fewer than {} of {n} bytes", got + step)
            } else {
                e.to_string()
            }
        })?;
        got += step;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn budgets_and_units() {
        assert_eq!(human_bytes(1 << 30), "1 GiB");
        assert_eq!(human_bytes(3 << 19), "1.5 MiB");
        assert_eq!(human_bytes(100), "100 bytes");
        let mut b = Budget::new(&ReadLimits::default(), 1000);
        // 128 x 1000 + 1 MiB may be inflated.
        assert!(b.inflate(128_000).is_ok());
        assert!(b.inflate(1 << 20).is_ok());
        assert!(b.inflate(1).unwrap_err().contains("128 times"));
        assert!(b.take(u64::MAX).unwrap_err().contains("1 GiB"));
        let mut b = Budget::new(&ReadLimits::default(), 1 << 30);
        assert!(b.inflate((1 << 30) + 1).unwrap_err().contains("1 GiB"));
        assert_eq!(printable("a\nb\x1b[31m"), "a\\nb\\u{1b}[31m");
        let mut out = vec![1u8];
        let mut src: &[u8] = &[2, 3, 4];
        read_exact_capped(&mut src, &mut out, 3).unwrap();
        assert_eq!(out, [1, 2, 3, 4]);
        assert!(out.capacity() < 16);
        let mut src: &[u8] = &[2, 3];
        assert!(read_exact_capped(&mut src, &mut out, 3).is_err());
    }
}
