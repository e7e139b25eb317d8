//! NumPy .npz files: a zip archive of .npy arrays (`NAME.npy`), as `numpy.savez` writes.
//!
//! Every array is written as NPY format version 1.0: the magic `\x93NUMPY`, version 1.0, a
//! little-endian u16 header length, the header dict
//! `{'descr': '<f8', 'fortran_order': False, 'shape': (...), }` padded with spaces and a
//! newline so that the data starts at a multiple of 64 bytes, then the little-endian f64
//! values in C (row-major) order. Members are deflate-compressed (`numpy.load` reads both).
//!
//! What is read: `.npz` archives stored (`numpy.savez`) or deflated
//! (`numpy.savez_compressed`), and `.npy` arrays of format versions 1.0 to 3.0, C or Fortran
//! order (Fortran arrays are transposed into C order), either byte order, of float32,
//! float64, int8…int64, uint8…uint64 or bool, as f64, of any number of dimensions (0-D for
//! a scalar). Every size is checked (checked arithmetic, against the bytes present and the
//! [`ReadLimits`] budget) before anything is allocated, every member's inflated size is
//! capped, and every error is one line naming the file and the member.

use std::io::{Read, Write};
use std::path::Path;

use crate::rundir::write_atomic;

use super::mat::values;
use super::{human_bytes, printable, read_exact_capped, Budget, ReadLimits};

/// One array: its shape (`[]` for a scalar) and its values in C order.
#[derive(Clone, Debug, PartialEq)]
pub struct NpyArray {
    pub shape: Vec<usize>,
    pub data: Vec<f64>,
}

impl NpyArray {
    /// A 1-D array.
    pub fn vector(values: &[f64]) -> NpyArray {
        NpyArray {
            shape: vec![values.len()],
            data: values.to_vec(),
        }
    }
    /// A 0-D array (a scalar).
    pub fn scalar(x: f64) -> NpyArray {
        NpyArray {
            shape: vec![],
            data: vec![x],
        }
    }
    /// A 2-D array from its rows.
    pub fn from_rows(rows: &[Vec<f64>]) -> NpyArray {
        NpyArray {
            shape: vec![rows.len(), rows.first().map_or(0, Vec::len)],
            data: rows.iter().flatten().copied().collect(),
        }
    }
}

/// Why a .npz file could not be written or read. Display names the file.
#[derive(Debug, thiserror::Error)]
#[error("{}: {reason}", printable(&path.display().to_string()))]
pub struct NpzError {
    pub path: std::path::PathBuf,
    pub reason: String,
}

/// The bytes of one .npy file.
pub fn npy_bytes(a: &NpyArray) -> Vec<u8> {
    let shape = match a.shape.len() {
        0 => "()".to_string(),
        1 => format!("({},)", a.shape[0]),
        _ => format!(
            "({})",
            a.shape
                .iter()
                .map(usize::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    let mut header = format!("{{'descr': '<f8', 'fortran_order': False, 'shape': {shape}, }}");
    let total = 10 + header.len() + 1;
    header.push_str(&" ".repeat((64 - total % 64) % 64));
    header.push('\n');
    let mut out = Vec::with_capacity(10 + header.len() + 8 * a.data.len());
    out.extend_from_slice(b"\x93NUMPY\x01\x00");
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    for x in &a.data {
        out.extend_from_slice(&x.to_le_bytes());
    }
    out
}

/// A value of the header dict (a Python literal).
#[derive(Debug, PartialEq)]
enum Py {
    Str(String),
    Bool(bool),
    Int(u64),
    Tuple(Vec<Py>),
    List(Vec<Py>),
    Dict(Vec<(String, Py)>),
    None,
}

/// A parser of the Python literals NumPy writes in .npy headers (`repr` of a dict of
/// strings, booleans, ints and tuples), nesting bounded.
struct PyParser<'a> {
    s: &'a [u8],
    pos: usize,
}

/// Deeper than any header NumPy writes (a structured dtype's list of tuples is 3 deep).
const PY_MAX_DEPTH: usize = 16;

impl PyParser<'_> {
    fn skip_ws(&mut self) {
        while self.s.get(self.pos).is_some_and(u8::is_ascii_whitespace) {
            self.pos += 1;
        }
    }

    fn peek(&mut self) -> Option<u8> {
        self.skip_ws();
        self.s.get(self.pos).copied()
    }

    fn expect(&mut self, c: u8) -> Result<(), String> {
        if self.peek() == Some(c) {
            self.pos += 1;
            Ok(())
        } else {
            Err(format!(
                "expected '{}' at byte {} of the header",
                c as char, self.pos
            ))
        }
    }

    /// Items up to `close`, separated by commas (a trailing comma allowed).
    fn items<T>(
        &mut self,
        close: u8,
        mut item: impl FnMut(&mut Self) -> Result<T, String>,
    ) -> Result<Vec<T>, String> {
        let mut out = Vec::new();
        loop {
            if self.peek() == Some(close) {
                self.pos += 1;
                return Ok(out);
            }
            out.push(item(self)?);
            match self.peek() {
                Some(b',') => self.pos += 1,
                Some(c) if c == close => {}
                _ => return Err(format!("expected ',' at byte {} of the header", self.pos)),
            }
        }
    }

    fn value(&mut self, depth: usize) -> Result<Py, String> {
        if depth > PY_MAX_DEPTH {
            return Err("the header nests too deep".into());
        }
        match self.peek() {
            Some(q @ (b'\'' | b'"')) => {
                self.pos += 1;
                let start = self.pos;
                let len = self.s[start..]
                    .iter()
                    .position(|&c| c == q)
                    .ok_or("an unterminated string in the header")?;
                self.pos = start + len + 1;
                Ok(Py::Str(
                    String::from_utf8_lossy(&self.s[start..start + len]).into(),
                ))
            }
            Some(b'(') => {
                self.pos += 1;
                Ok(Py::Tuple(self.items(b')', |p| p.value(depth + 1))?))
            }
            Some(b'[') => {
                self.pos += 1;
                Ok(Py::List(self.items(b']', |p| p.value(depth + 1))?))
            }
            Some(b'{') => {
                self.pos += 1;
                Ok(Py::Dict(self.items(b'}', |p| {
                    let Py::Str(key) = p.value(depth + 1)? else {
                        return Err("a header key that is not a string".into());
                    };
                    p.expect(b':')?;
                    Ok((key, p.value(depth + 1)?))
                })?))
            }
            Some(c) if c.is_ascii_alphanumeric() => {
                let start = self.pos;
                while self
                    .s
                    .get(self.pos)
                    .is_some_and(|c| c.is_ascii_alphanumeric() || *c == b'_')
                {
                    self.pos += 1;
                }
                let word = String::from_utf8_lossy(&self.s[start..self.pos]);
                match &*word {
                    "True" => Ok(Py::Bool(true)),
                    "False" => Ok(Py::Bool(false)),
                    "None" => Ok(Py::None),
                    // Python 2's NumPy wrote long ints as `3L`.
                    w => w
                        .strip_suffix('L')
                        .unwrap_or(w)
                        .parse::<u64>()
                        .map(Py::Int)
                        .map_err(|_| format!("{:?} in the header", printable(w))),
                }
            }
            _ => Err(format!(
                "unexpected text at byte {} of the header",
                self.pos
            )),
        }
    }
}

/// The element types read: (kind, size) of a descr such as `<f8`.
fn dtype(descr: &str) -> Result<(bool, char, usize), String> {
    let unsupported = || {
        format!(
            "dtype {:?} is not read (float32/64, int8…64, uint8…64 and bool are)",
            printable(descr)
        )
    };
    let mut cs = descr.chars();
    let order = cs.next().ok_or_else(unsupported)?;
    let kind = cs.next().ok_or_else(unsupported)?;
    let size: usize = cs.as_str().parse().map_err(|_| unsupported())?;
    let ok = match kind {
        'f' => matches!(size, 4 | 8),
        'i' | 'u' => matches!(size, 1 | 2 | 4 | 8),
        'b' => size == 1,
        _ => false,
    };
    // '|' (no byte order) is what NumPy writes for one-byte types.
    let big = match order {
        '<' => false,
        '>' => true,
        '|' if size == 1 => false,
        _ => return Err(unsupported()),
    };
    if ok {
        Ok((big, kind, size))
    } else {
        Err(unsupported())
    }
}

/// Why bytes are not a .npy array eyeshell reads, or why a .npz archive could not be
/// assembled: the reason, in the format's terms (a reader adds the file's name).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{reason}")]
#[non_exhaustive]
pub struct NpyError {
    pub reason: String,
}

impl From<String> for NpyError {
    fn from(reason: String) -> Self {
        NpyError { reason }
    }
}

/// Parse one .npy file within the default [`ReadLimits`].
///
/// # Errors
/// [`NpyError`] for bytes that are not such an array, or that decode to more than the
/// limits allow.
pub fn parse_npy(bytes: &[u8]) -> Result<NpyArray, NpyError> {
    Ok(parse_npy_in(
        bytes,
        &mut Budget::new(&ReadLimits::default(), bytes.len()),
    )?)
}

/// Parse one .npy file: any version (1.0, 2.0, 3.0), C or Fortran order (Fortran is
/// transposed into C order), either byte order, float32/float64, int8…int64,
/// uint8…uint64 and bool, as f64; any number of dimensions (0-D is a scalar).
fn parse_npy_in(bytes: &[u8], budget: &mut Budget) -> Result<NpyArray, String> {
    if !bytes.starts_with(b"\x93NUMPY") {
        return Err("not an .npy array (no \\x93NUMPY magic)".into());
    }
    let (hlen, start) = match bytes.get(6) {
        Some(1) => (
            bytes
                .get(8..10)
                .map(|b| u16::from_le_bytes([b[0], b[1]]) as usize),
            10usize,
        ),
        Some(2 | 3) => (
            bytes
                .get(8..12)
                .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize),
            12,
        ),
        v => {
            return Err(format!(
                "unsupported .npy version {}",
                v.copied().unwrap_or(0)
            ))
        }
    };
    let hlen = hlen.ok_or("the .npy header is cut short")?;
    let header = start
        .checked_add(hlen)
        .and_then(|end| bytes.get(start..end))
        .ok_or("the .npy header is cut short")?;
    let mut p = PyParser { s: header, pos: 0 };
    let Py::Dict(dict) = p.value(0)? else {
        return Err("the .npy header is not a dict".into());
    };
    let get = |k: &str| {
        dict.iter()
            .find(|(n, _)| n == k)
            .map(|(_, v)| v)
            .ok_or_else(|| format!("no '{k}' in the .npy header"))
    };
    let (big, kind, size) = match get("descr")? {
        Py::Str(d) => dtype(d)?,
        _ => return Err("structured dtypes are not read (a plain numeric array is)".into()),
    };
    let fortran = match get("fortran_order")? {
        Py::Bool(b) => *b,
        _ => return Err("'fortran_order' is not True or False".into()),
    };
    let shape = match get("shape")? {
        Py::Tuple(dims) => dims
            .iter()
            .map(|d| match d {
                Py::Int(n) => usize::try_from(*n).map_err(|_| format!("dimension {n} overflows")),
                _ => Err("a shape that is not a tuple of integers".into()),
            })
            .collect::<Result<Vec<usize>, String>>()?,
        _ => return Err("a shape that is not a tuple of integers".into()),
    };
    let n = shape
        .iter()
        .try_fold(1usize, |n, &d| n.checked_mul(d))
        .ok_or_else(|| format!("shape {shape:?} overflows"))?;
    let body = &bytes[start + hlen..];
    if n.checked_mul(size) != Some(body.len()) {
        return Err(format!(
            "{} data bytes for shape {shape:?} of {size}-byte values",
            body.len()
        ));
    }
    // The values, and their transpose for a Fortran-order array.
    let cost = if fortran && shape.len() > 1 { 16 } else { 8 };
    budget.take(cost * n as u64)?;
    let b = body;
    let data: Vec<f64> = match (kind, size) {
        ('f', 4) => values!(b, f32, big),
        ('f', _) => values!(b, f64, big),
        ('i', 1) => b.iter().map(|&x| x as i8 as f64).collect(),
        ('u', 1) => b.iter().map(|&x| x as f64).collect(),
        ('b', _) => b.iter().map(|&x| if x != 0 { 1.0 } else { 0.0 }).collect(),
        ('i', 2) => values!(b, i16, big),
        ('u', 2) => values!(b, u16, big),
        ('i', 4) => values!(b, i32, big),
        ('u', 4) => values!(b, u32, big),
        ('i', _) => values!(b, i64, big),
        _ => values!(b, u64, big),
    };
    let data = if fortran && shape.len() > 1 {
        to_c_order(&shape, &data)
    } else {
        data
    };
    Ok(NpyArray { shape, data })
}

/// The values of an array of `shape` in C order from its values in Fortran order.
fn to_c_order(shape: &[usize], f: &[f64]) -> Vec<f64> {
    // Strides of the Fortran layout: the first index varies fastest.
    let mut stride = Vec::with_capacity(shape.len());
    let mut s = 1usize;
    for &d in shape {
        stride.push(s);
        s = s.saturating_mul(d);
    }
    let mut idx = vec![0usize; shape.len()];
    let mut src = 0usize;
    let mut out = Vec::with_capacity(f.len());
    for _ in 0..f.len() {
        out.push(f.get(src).copied().unwrap_or(f64::NAN));
        // The next C-order index: the last index varies fastest.
        for k in (0..shape.len()).rev() {
            idx[k] += 1;
            src += stride[k];
            if idx[k] < shape[k] {
                break;
            }
            src -= stride[k] * shape[k];
            idx[k] = 0;
        }
    }
    out
}

/// The archive comment of every .npz eyeshell writes, by which it knows its own files.
pub const COMMENT: &str = "written by eyeshell export";

/// Does the file at `path` end with eyeshell's archive comment (the last bytes of a zip
/// archive are its comment)?
pub fn has_signature(path: &Path) -> bool {
    use std::io::{Read, Seek, SeekFrom};
    let Ok(mut f) = std::fs::File::open(path) else {
        return false;
    };
    let n = COMMENT.len() as i64;
    let mut tail = Vec::new();
    f.seek(SeekFrom::End(-n)).is_ok()
        && f.take(n as u64).read_to_end(&mut tail).is_ok()
        && tail == COMMENT.as_bytes()
}

/// The bytes of a .npz archive of `arrays` (member `NAME.npy` each), with eyeshell's
/// [`COMMENT`].
///
/// # Errors
/// [`NpyError`] if the archive cannot be assembled (a member's name the zip writer
/// refuses).
pub fn encode(arrays: &[(String, NpyArray)]) -> Result<Vec<u8>, NpyError> {
    Ok(encode_zip(arrays)?)
}

fn encode_zip(arrays: &[(String, NpyArray)]) -> Result<Vec<u8>, String> {
    let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    zip.set_comment(COMMENT).map_err(|e| e.to_string())?;
    let options = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated);
    for (name, a) in arrays {
        zip.start_file(format!("{name}.npy"), options)
            .map_err(|e| e.to_string())?;
        zip.write_all(&npy_bytes(a)).map_err(|e| e.to_string())?;
    }
    Ok(zip.finish().map_err(|e| e.to_string())?.into_inner())
}

/// Write `arrays` to the .npz file `path` (atomically).
pub fn write(path: &Path, arrays: &[(String, NpyArray)]) -> Result<(), NpzError> {
    let err = |reason: String| NpzError {
        path: path.to_path_buf(),
        reason,
    };
    let bytes = encode(arrays).map_err(|e| err(e.reason))?;
    write_atomic(path, &bytes).map_err(|e| err(e.to_string()))
}

/// Read every `NAME.npy` member of the .npz file `path`, in archive order, within the
/// default [`ReadLimits`].
pub fn read(path: &Path) -> Result<Vec<(String, NpyArray)>, NpzError> {
    read_with(path, &ReadLimits::default())
}

/// Read the .npz file `path` within `limits` (a file larger than `limits.max_bytes` is
/// refused before it is read).
pub fn read_with(path: &Path, limits: &ReadLimits) -> Result<Vec<(String, NpyArray)>, NpzError> {
    let err = |reason: String| NpzError {
        path: path.to_path_buf(),
        reason,
    };
    let size = std::fs::metadata(path)
        .map_err(|e| err(e.to_string()))?
        .len();
    if size > limits.max_bytes {
        return Err(err(format!(
            "{size} bytes, larger than the readers' limit of {}",
            human_bytes(limits.max_bytes)
        )));
    }
    let bytes = std::fs::read(path).map_err(|e| err(e.to_string()))?;
    decode_with(path, &bytes, limits)
}

/// Decode the bytes of a .npz file (`path` only names it in errors) within the default
/// [`ReadLimits`].
pub fn decode(path: &Path, bytes: &[u8]) -> Result<Vec<(String, NpyArray)>, NpzError> {
    decode_with(path, bytes, &ReadLimits::default())
}

/// Decode the bytes of a .npz file (`path` only names it in errors) within `limits`:
/// every `NAME.npy` member (stored or deflated), in archive order. Each member's declared
/// size is charged to the budget before it is inflated, and a member that inflates past
/// its declared size is refused.
pub fn decode_with(
    path: &Path,
    bytes: &[u8],
    limits: &ReadLimits,
) -> Result<Vec<(String, NpyArray)>, NpzError> {
    let err = |reason: String| NpzError {
        path: path.to_path_buf(),
        reason: printable(&reason),
    };
    let mut budget = Budget::new(limits, bytes.len());
    let mut zip = zip::ZipArchive::new(std::io::Cursor::new(bytes))
        .map_err(|e| err(format!("not a .npz (zip) file: {e}")))?;
    let mut out = Vec::new();
    for i in 0..zip.len() {
        let mut member = zip.by_index(i).map_err(|e| err(e.to_string()))?;
        let name = member.name().map_err(|e| err(e.to_string()))?.to_string();
        let Some(stem) = name.strip_suffix(".npy") else {
            continue;
        };
        let in_err = |e: String| err(format!("{name}: {e}"));
        let declared = member.size();
        if member.compression() == zip::CompressionMethod::Stored {
            budget.take(declared)
        } else {
            budget.inflate(declared)
        }
        .map_err(in_err)?;
        let declared = usize::try_from(declared)
            .map_err(|_| in_err(format!("a declared size of {declared} bytes")))?;
        let mut data = Vec::new();
        read_exact_capped(&mut member, &mut data, declared).map_err(in_err)?;
        // Reading past the end checks the CRC, and catches a member longer than it said.
        let mut extra = [0u8; 1];
        match member.read(&mut extra) {
            Ok(0) => {}
            Ok(_) => return Err(in_err("the member is longer than its declared size".into())),
            Err(e) => return Err(in_err(e.to_string())),
        }
        let a = parse_npy_in(&data, &mut budget).map_err(in_err)?;
        out.push((stem.to_string(), a));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn npy_header_is_aligned_and_round_trips() {
        for a in [
            NpyArray::scalar(0.25),
            NpyArray::vector(&[1.0, -2.0, 1e-300]),
            NpyArray::from_rows(&[vec![1.0, 2.0], vec![3.0, 4.0], vec![5.0, 6.0]]),
        ] {
            let b = npy_bytes(&a);
            let hlen = u16::from_le_bytes([b[8], b[9]]) as usize;
            assert_eq!((10 + hlen) % 64, 0);
            assert_eq!(b[10 + hlen - 1], b'\n');
            assert_eq!(parse_npy(&b).unwrap(), a);
        }
    }

    #[test]
    fn npz_round_trips() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.npz");
        let arrays = vec![
            ("x".to_string(), NpyArray::vector(&[0.0, 0.5, 1.0])),
            (
                "y".to_string(),
                NpyArray::from_rows(&[vec![1.0, 2.0, 3.0], vec![4.0, 5.0, 6.0]]),
            ),
        ];
        write(&p, &arrays).unwrap();
        assert_eq!(read(&p).unwrap(), arrays);
    }

    /// A .npy file with `header` (the dict) and `data`, version 1.0.
    fn npy(header: &str, data: &[u8]) -> Vec<u8> {
        let mut b = b"\x93NUMPY\x01\x00".to_vec();
        b.extend_from_slice(&(header.len() as u16).to_le_bytes());
        b.extend_from_slice(header.as_bytes());
        b.extend_from_slice(data);
        b
    }

    #[test]
    fn orders_endianness_and_types() {
        // 2x3 Fortran-ordered big-endian int16: columns (1, 4), (2, 5), (3, 6).
        let data: Vec<u8> = [1i16, 4, 2, 5, 3, 6]
            .iter()
            .flat_map(|x| x.to_be_bytes())
            .collect();
        let a = parse_npy(&npy(
            "{'descr': '>i2', 'fortran_order': True, 'shape': (2, 3), }\n",
            &data,
        ))
        .unwrap();
        assert_eq!(a.shape, [2, 3]);
        assert_eq!(a.data, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        // Python 2's long ints, double quotes, no trailing comma.
        let a = parse_npy(&npy(
            "{\"descr\": \"|b1\", \"fortran_order\": False, \"shape\": (3L,)}",
            &[0, 1, 7],
        ))
        .unwrap();
        assert_eq!((a.shape, a.data), (vec![3], vec![0.0, 1.0, 1.0]));
        for (descr, why) in [
            ("<c16", "dtype \"<c16\" is not read"),
            ("<f2", "dtype \"<f2\" is not read"),
            ("|f8", "dtype \"|f8\" is not read"),
            ("<U3", "dtype \"<U3\" is not read"),
        ] {
            let h = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': (1,), }}");
            let e = parse_npy(&npy(&h, &[0; 16])).unwrap_err().reason;
            assert!(e.starts_with(why), "{e}");
        }
        let e = parse_npy(&npy(
            "{'descr': [('a', '<f8')], 'fortran_order': False, 'shape': (1,), }",
            &[0; 8],
        ))
        .unwrap_err()
        .reason;
        assert!(e.contains("structured dtypes are not read"), "{e}");
    }

    #[test]
    fn hostile_shapes_and_headers_are_refused() {
        let h =
            |shape: &str| format!("{{'descr': '<f8', 'fortran_order': False, 'shape': {shape}, }}");
        // The element count overflows; the byte size overflows; a size far beyond the data.
        let e = parse_npy(&npy(&h("(4611686018427387904, 8)"), &[]))
            .unwrap_err()
            .reason;
        assert!(e.contains("overflows"), "{e}");
        let e = parse_npy(&npy(&h("(2305843009213693952,)"), &[0; 8]))
            .unwrap_err()
            .reason;
        assert!(e.starts_with("8 data bytes for shape"), "{e}");
        let e = parse_npy(&npy(&h("(99999999999999999999,)"), &[]))
            .unwrap_err()
            .reason;
        assert!(e.contains("99999999999999999999"), "{e}");
        let e = parse_npy(&npy(&h("(1000, 1000)"), &[0; 8]))
            .unwrap_err()
            .reason;
        assert!(e.starts_with("8 data bytes for shape [1000, 1000]"), "{e}");
        // Nesting, junk, truncation.
        let deep = format!("{}{}", "(".repeat(10_000), ")".repeat(10_000));
        let e = parse_npy(&npy(&h(&deep), &[])).unwrap_err().reason;
        assert!(e.contains("nests too deep"), "{e}");
        assert!(parse_npy(b"\x93NUMPY\x01\x00\xff\xff{").is_err());
        assert!(parse_npy(b"\x93NUMPY\x02\x00\xff\xff").is_err());
        assert!(parse_npy(b"\x93NUMPY\x04\x00\x00\x00").is_err());
    }

    #[test]
    fn zip_bombs_are_refused() {
        // A member of 16 MiB of zeros deflates to about 16 KiB: a ratio near 1000.
        let big = NpyArray::vector(&vec![0.0; 2 << 20]);
        let bytes = encode(&[("z".to_string(), big.clone())]).unwrap();
        assert!(bytes.len() < 100_000, "{}", bytes.len());
        let e = decode(Path::new("bomb.npz"), &bytes)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("bomb.npz: z.npy: compressed data inflates to more than 128 times"));
        let loose = ReadLimits {
            max_ratio: 2000,
            ..ReadLimits::default()
        };
        let back = decode_with(Path::new("bomb.npz"), &bytes, &loose).unwrap();
        assert_eq!(back, vec![("z".to_string(), big)]);
        let tight = ReadLimits {
            max_bytes: 8 << 20,
            max_ratio: 2000,
            ..ReadLimits::default()
        };
        let e = decode_with(Path::new("bomb.npz"), &bytes, &tight)
            .unwrap_err()
            .to_string();
        assert!(e.contains("z.npy: holds more than 8 MiB"), "{e}");
    }
}
