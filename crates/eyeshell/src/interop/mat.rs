//! MATLAB v5 .mat files: a writer and a reader, both our own.
//!
//! What is written (MAT-File Format, level 5, little-endian):
//! - a 128-byte header: text `MATLAB 5.0 MAT-file, ...` padded with spaces to 116 bytes,
//!   8 zero bytes (no subsystem data), version 0x0100 and the endian indicator `IM`;
//! - one `miMATRIX` element per variable: array flags (`miUINT32`: the class, no complex or
//!   logical bit), dimensions (`miINT32`), the name (`miINT8`, in the 4-byte small-element
//!   form when it has 1 to 4 characters, like MATLAB), then
//!   - for `mxDOUBLE_CLASS` the real part (`miDOUBLE`, column-major);
//!   - for a 1×1 `mxSTRUCT_CLASS` the field-name length (32, a small `miINT32`), the field
//!     names (`miINT8`, 32 bytes each, NUL-padded) and one unnamed `miMATRIX` per field;
//! - every element padded to 8 bytes; with compression each variable's whole `miMATRIX`
//!   element is zlib-compressed into one `miCOMPRESSED` element (no padding after it, as
//!   MATLAB writes them).
//!
//! What is read: level 5 files as MATLAB (`save`, default `-v7`, and `-v6`), GNU Octave and
//! SciPy write them, in either byte order (`IM` or `MI`), any header text after `MATLAB`
//! (SciPy's has no comma), small and normal data elements, `miCOMPRESSED` variables. Into
//! [`MatValue`]:
//! - numeric arrays of every class (double, single, int8…uint64) and logical arrays, in
//!   whatever type the file stores them (MATLAB stores small integers in narrower types):
//!   [`MatValue::Double`], as f64;
//! - char arrays: [`MatValue::Char`] (UTF-8, UTF-16 or UTF-32 storage);
//! - structs: a 1×1 struct is [`MatValue::Struct`], any other size a
//!   [`MatValue::StructArray`] with every element; nested structs and cells to any depth up
//!   to [`ReadLimits::max_depth`];
//! - cell arrays: [`MatValue::Cell`];
//! - objects, function handles and MATLAB's opaque classes (`string`, `table`, …):
//!   [`MatValue::Unread`], naming what it is;
//! - sparse and complex arrays are refused, naming the variable.
//!
//! MATLAB v7.3 files (HDF5) and v4 files are refused with a line saying how to re-save them
//! as v7. Every size the file declares is checked (checked arithmetic, against the bytes
//! present and the [`ReadLimits`] budget) before anything is allocated; decompression stops
//! at the budget; every error is one line naming the file and the variable. Nothing in the
//! reader panics on any input (tests/cli/readers.rs fuzzes it).

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use crate::rundir::write_atomic;

use super::{printable, read_exact_capped, Budget, ReadLimits};

/// `miINT8`.
const MI_INT8: u32 = 1;
/// `miUINT8`.
const MI_UINT8: u32 = 2;
/// `miINT16`.
const MI_INT16: u32 = 3;
/// `miUINT16`.
const MI_UINT16: u32 = 4;
/// `miINT32`.
const MI_INT32: u32 = 5;
/// `miUINT32`.
const MI_UINT32: u32 = 6;
/// `miSINGLE`.
const MI_SINGLE: u32 = 7;
/// `miDOUBLE`.
const MI_DOUBLE: u32 = 9;
/// `miINT64`.
const MI_INT64: u32 = 12;
/// `miUINT64`.
const MI_UINT64: u32 = 13;
/// `miMATRIX`.
const MI_MATRIX: u32 = 14;
/// `miCOMPRESSED`.
const MI_COMPRESSED: u32 = 15;
/// `miUTF8`.
const MI_UTF8: u32 = 16;
/// `miUTF16`.
const MI_UTF16: u32 = 17;
/// `miUTF32`.
const MI_UTF32: u32 = 18;
/// `mxCELL_CLASS`.
const MX_CELL: u32 = 1;
/// `mxSTRUCT_CLASS`.
const MX_STRUCT: u32 = 2;
/// `mxOBJECT_CLASS`.
const MX_OBJECT: u32 = 3;
/// `mxCHAR_CLASS`.
const MX_CHAR: u32 = 4;
/// `mxSPARSE_CLASS`.
const MX_SPARSE: u32 = 5;
/// `mxDOUBLE_CLASS`.
const MX_DOUBLE: u32 = 6;
/// `mxUINT64_CLASS`, the last numeric class (`mxDOUBLE_CLASS` to here: double, single,
/// int8, uint8, int16, uint16, int32, uint32, int64, uint64).
const MX_UINT64: u32 = 15;
/// `mxFUNCTION_CLASS` (function handles).
const MX_FUNCTION: u32 = 16;
/// `mxOPAQUE_CLASS` (MATLAB's `string`, `table`, … objects).
const MX_OPAQUE: u32 = 17;
/// The complex bit of the array flags.
const FLAG_COMPLEX: u32 = 0x0800;
/// Bytes per field name in a struct (31 characters and a NUL).
const FIELD_NAME_LEN: usize = 32;
/// The HDF5 signature (v7.3 files carry it at byte 512).
const HDF5_SIGNATURE: &[u8] = b"\x89HDF\r\n\x1a\n";
/// Bytes charged to the budget for each value node decoded, on top of its data: the
/// bookkeeping of a [`MatValue`], so that millions of empty arrays cost what they take.
const NODE_COST: u64 = 64;

/// One MATLAB value.
#[derive(Clone, Debug, PartialEq)]
pub enum MatValue {
    /// A real numeric or logical array of any class (double, single, int8…uint64,
    /// logical), as f64: its dimensions and its values in column-major order.
    Double { dims: Vec<usize>, data: Vec<f64> },
    /// A 1×1 struct: its fields in order.
    Struct(Vec<(String, MatValue)>),
    /// A struct array of any other size (1×2, 0×0, …): its dimensions and every element's
    /// fields (each element as a 1×1 struct's), elements in column-major order.
    StructArray {
        dims: Vec<usize>,
        elements: Vec<Vec<(String, MatValue)>>,
    },
    /// A char array as text: a row (or any 1-row or N-D array) as its characters in order;
    /// the rows of an R×C array (R > 1) joined by `'\n'`.
    Char(String),
    /// A cell array: its dimensions and its cells in column-major order.
    Cell {
        dims: Vec<usize>,
        cells: Vec<MatValue>,
    },
    /// A value of a class that is not decoded (an object, a function handle, MATLAB's
    /// opaque `string`, `table`, …): what it is. Read only; never written.
    Unread(String),
}

impl MatValue {
    /// A 1×N row vector.
    pub fn row(values: &[f64]) -> MatValue {
        MatValue::Double {
            dims: vec![1, values.len()],
            data: values.to_vec(),
        }
    }

    /// A 1×1 scalar.
    pub fn scalar(x: f64) -> MatValue {
        MatValue::Double {
            dims: vec![1, 1],
            data: vec![x],
        }
    }

    /// An R×C matrix from its rows (each of length C).
    pub fn from_rows(rows: &[Vec<f64>]) -> MatValue {
        let r = rows.len();
        let c = rows.first().map_or(0, Vec::len);
        let mut data = Vec::with_capacity(r * c);
        for j in 0..c {
            for row in rows {
                data.push(row[j]);
            }
        }
        MatValue::Double {
            dims: vec![r, c],
            data,
        }
    }

    /// The values of a numeric array, column-major.
    pub fn data(&self) -> Option<&[f64]> {
        match self {
            MatValue::Double { data, .. } => Some(data),
            _ => None,
        }
    }

    /// The dimensions of a numeric array.
    pub fn dims(&self) -> Option<&[usize]> {
        match self {
            MatValue::Double { dims, .. } => Some(dims),
            _ => None,
        }
    }

    /// Row `i` of a 2-D numeric array.
    pub fn row_of(&self, i: usize) -> Option<Vec<f64>> {
        match self {
            MatValue::Double { dims, data }
                if dims.len() == 2 && i < dims[0] && data.len() == dims[0] * dims[1] =>
            {
                Some((0..dims[1]).map(|j| data[j * dims[0] + i]).collect())
            }
            _ => None,
        }
    }

    /// A field of a 1×1 struct.
    pub fn field(&self, name: &str) -> Option<&MatValue> {
        match self {
            MatValue::Struct(fields) => fields.iter().find(|(n, _)| n == name).map(|(_, v)| v),
            _ => None,
        }
    }

    /// The fields of element `k` (0-based, column-major) of a struct: `k = 0` of a 1×1
    /// struct, any element of a struct array.
    pub fn struct_element(&self, k: usize) -> Option<&[(String, MatValue)]> {
        match self {
            MatValue::Struct(fields) if k == 0 => Some(fields),
            MatValue::StructArray { elements, .. } => elements.get(k).map(Vec::as_slice),
            _ => None,
        }
    }

    /// The text of a char array.
    pub fn text(&self) -> Option<&str> {
        match self {
            MatValue::Char(s) => Some(s),
            _ => None,
        }
    }
}

/// Why a .mat file could not be written or read. Display names the file, on one line.
#[derive(Debug, thiserror::Error)]
pub enum MatError {
    #[error("{}: {source}", printable(&path.display().to_string()))]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: {reason}", printable(&path.display().to_string()))]
    Format { path: PathBuf, reason: String },
    #[error("cannot write variable {name:?}: {reason}")]
    Invalid { name: String, reason: String },
}

fn pad8(out: &mut Vec<u8>) {
    while !out.len().is_multiple_of(8) {
        out.push(0);
    }
}

/// A data element: the small form (4-byte tag, up to 4 bytes of data) when `small` allows
/// and the data fits, else the 8-byte tag, the data and padding to 8 bytes.
fn element(out: &mut Vec<u8>, ty: u32, bytes: &[u8], small: bool) {
    if small && !bytes.is_empty() && bytes.len() <= 4 {
        out.extend_from_slice(&(((bytes.len() as u32) << 16) | ty).to_le_bytes());
        out.extend_from_slice(bytes);
        out.resize(out.len() + 4 - bytes.len(), 0);
    } else {
        out.extend_from_slice(&ty.to_le_bytes());
        out.extend_from_slice(&(bytes.len() as u32).to_le_bytes());
        out.extend_from_slice(bytes);
        pad8(out);
    }
}

fn check_name(name: &str, max: usize) -> Result<(), MatError> {
    let ok = !name.is_empty()
        && name.len() <= max
        && name.chars().next().is_some_and(|c| c.is_ascii_alphabetic())
        && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
    if ok {
        Ok(())
    } else {
        Err(MatError::Invalid {
            name: name.to_string(),
            reason: format!(
                "a MATLAB name is a letter, then letters, digits or '_', at most {max} characters"
            ),
        })
    }
}

/// The whole `miMATRIX` element (tag included) of `value` named `name` ("" for a field).
fn matrix_element(name: &str, value: &MatValue) -> Result<Vec<u8>, MatError> {
    let mut body = Vec::new();
    let (class, dims): (u32, Vec<usize>) = match value {
        MatValue::Double { dims, data } => {
            if dims.len() < 2 || dims.iter().product::<usize>() != data.len() {
                return Err(MatError::Invalid {
                    name: name.to_string(),
                    reason: format!("dimensions {dims:?} do not hold {} values", data.len()),
                });
            }
            (MX_DOUBLE, dims.clone())
        }
        MatValue::Struct(_) => (MX_STRUCT, vec![1, 1]),
        MatValue::Char(text) => (MX_CHAR, vec![1, text.encode_utf16().count()]),
        _ => {
            return Err(MatError::Invalid {
                name: name.to_string(),
                reason: "only numeric arrays, char rows and 1×1 structs are written".into(),
            })
        }
    };
    let mut flags = Vec::with_capacity(8);
    flags.extend_from_slice(&class.to_le_bytes());
    flags.extend_from_slice(&0u32.to_le_bytes());
    element(&mut body, MI_UINT32, &flags, false);
    let mut d = Vec::with_capacity(4 * dims.len());
    for &n in &dims {
        let n = i32::try_from(n).map_err(|_| MatError::Invalid {
            name: name.to_string(),
            reason: format!("dimension {n} is too large"),
        })?;
        d.extend_from_slice(&n.to_le_bytes());
    }
    element(&mut body, MI_INT32, &d, false);
    element(&mut body, MI_INT8, name.as_bytes(), true);
    match value {
        MatValue::Double { data, .. } => {
            let mut bytes = Vec::with_capacity(8 * data.len());
            for x in data {
                bytes.extend_from_slice(&x.to_le_bytes());
            }
            element(&mut body, MI_DOUBLE, &bytes, false);
        }
        // As MATLAB saves a char row: UTF-16 code units.
        MatValue::Char(text) => {
            let bytes: Vec<u8> = text.encode_utf16().flat_map(u16::to_le_bytes).collect();
            element(&mut body, MI_UINT16, &bytes, false);
        }
        MatValue::Struct(fields) => {
            element(
                &mut body,
                MI_INT32,
                &(FIELD_NAME_LEN as i32).to_le_bytes(),
                true,
            );
            let mut names = vec![0u8; FIELD_NAME_LEN * fields.len()];
            for (k, (f, _)) in fields.iter().enumerate() {
                check_name(f, FIELD_NAME_LEN - 1)?;
                names[k * FIELD_NAME_LEN..k * FIELD_NAME_LEN + f.len()]
                    .copy_from_slice(f.as_bytes());
            }
            element(&mut body, MI_INT8, &names, false);
            for (_, v) in fields {
                body.extend(matrix_element("", v)?);
            }
        }
        // Refused above.
        _ => {}
    }
    let mut out = Vec::with_capacity(body.len() + 8);
    out.extend_from_slice(&MI_MATRIX.to_le_bytes());
    out.extend_from_slice(&(body.len() as u32).to_le_bytes());
    out.extend(body);
    Ok(out)
}

/// How every .mat file eyeshell writes begins (its header names eyeshell as the platform).
pub const SIGNATURE: &[u8] = b"MATLAB 5.0 MAT-file, Platform: eyeshell ";

/// The 128-byte header (deterministic: no date, so equal runs give equal files).
pub fn header() -> Vec<u8> {
    let text = format!(
        "MATLAB 5.0 MAT-file, Platform: eyeshell {}, Created by: eyeshell export",
        env!("CARGO_PKG_VERSION")
    );
    let mut h = text.into_bytes();
    h.resize(116, b' ');
    h.extend_from_slice(&[0u8; 8]);
    h.extend_from_slice(&0x0100u16.to_le_bytes());
    h.extend_from_slice(b"IM");
    h
}

/// The bytes of a .mat file holding `vars` in order, each variable `miCOMPRESSED` if
/// `compress`.
pub fn encode(vars: &[(String, MatValue)], compress: bool) -> Result<Vec<u8>, MatError> {
    let mut out = header();
    for (name, value) in vars {
        check_name(name, 63)?;
        let el = matrix_element(name, value)?;
        if compress {
            let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
            z.write_all(&el)
                .and_then(|_| z.finish())
                .map(|zipped| {
                    out.extend_from_slice(&MI_COMPRESSED.to_le_bytes());
                    out.extend_from_slice(&(zipped.len() as u32).to_le_bytes());
                    out.extend(zipped);
                })
                .map_err(|e| MatError::Invalid {
                    name: name.clone(),
                    reason: e.to_string(),
                })?;
        } else {
            out.extend(el);
        }
    }
    Ok(out)
}

/// Write `vars` to the .mat file `path` (atomically).
pub fn write(path: &Path, vars: &[(String, MatValue)], compress: bool) -> Result<(), MatError> {
    let bytes = encode(vars, compress)?;
    write_atomic(path, &bytes).map_err(|source| MatError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// The name of a data type, for messages.
fn type_name(ty: u32) -> String {
    let name = match ty {
        MI_INT8 => "miINT8",
        MI_UINT8 => "miUINT8",
        MI_INT16 => "miINT16",
        MI_UINT16 => "miUINT16",
        MI_INT32 => "miINT32",
        MI_UINT32 => "miUINT32",
        MI_SINGLE => "miSINGLE",
        MI_DOUBLE => "miDOUBLE",
        MI_INT64 => "miINT64",
        MI_UINT64 => "miUINT64",
        MI_MATRIX => "miMATRIX",
        MI_COMPRESSED => "miCOMPRESSED",
        MI_UTF8 => "miUTF8",
        MI_UTF16 => "miUTF16",
        MI_UTF32 => "miUTF32",
        _ => return format!("type {ty}"),
    };
    name.to_string()
}

/// The u32 of the 4 bytes at the start of `b` (all callers hold 4 or more) in the file's
/// byte order.
fn u32_of(b: &[u8], big: bool) -> u32 {
    let mut a = [0u8; 4];
    for (x, y) in a.iter_mut().zip(b) {
        *x = *y;
    }
    if big {
        u32::from_be_bytes(a)
    } else {
        u32::from_le_bytes(a)
    }
}

/// Values of `n`-byte chunks (`n` = the size of `$t`) as f64, in the file's byte order.
macro_rules! values {
    ($data:expr, $t:ty, $big:expr) => {
        $data
            .chunks_exact(std::mem::size_of::<$t>())
            .map(|b| {
                let a = b.try_into().unwrap_or_default();
                (if $big {
                    <$t>::from_be_bytes(a)
                } else {
                    <$t>::from_le_bytes(a)
                }) as f64
            })
            .collect()
    };
}
pub(crate) use values;

/// One data element: its type and its bytes (borrowed from the file or the decompressed
/// variable), and where its tag starts.
struct Element<'a> {
    ty: u32,
    data: &'a [u8],
    offset: usize,
}

/// The data elements of a byte range, one after another.
struct Elements<'a> {
    bytes: &'a [u8],
    pos: usize,
    big: bool,
}

impl<'a> Elements<'a> {
    fn new(bytes: &'a [u8], big: bool) -> Self {
        Elements { bytes, pos: 0, big }
    }

    fn rest(&self) -> &'a [u8] {
        self.bytes.get(self.pos..).unwrap_or(&[])
    }

    /// The next element, in the small form (tag and up to 4 bytes of data in 8 bytes) or the
    /// normal one (8-byte tag, data, and padding to 8 bytes skipped when `pad`; padding cut
    /// off by the end of the range is forgiven).
    fn next(&mut self, pad: bool) -> Result<Element<'a>, String> {
        let rest = self.rest();
        let Some(tag) = rest.get(..8) else {
            return Err(if rest.is_empty() {
                "a data element is missing (the data ends)".into()
            } else {
                format!(
                    "a data element's tag is cut short ({} of 8 bytes)",
                    rest.len()
                )
            });
        };
        let first = u32_of(tag, self.big);
        let (ty, data, used) = if first >> 16 != 0 {
            let n = (first >> 16) as usize;
            let Some(data) = tag.get(4..4 + n).filter(|_| n <= 4) else {
                return Err(format!("a small data element claims {n} bytes (at most 4)"));
            };
            (first & 0xffff, data, 8)
        } else {
            let n = u32_of(&tag[4..], self.big) as usize;
            let avail = rest.len() - 8;
            let Some(data) = rest[8..].get(..n) else {
                return Err(format!(
                    "a {} element claims {n} bytes where {avail} remain",
                    type_name(first)
                ));
            };
            // 8 + n <= rest.len() here, so neither sum overflows.
            let used = if pad {
                ((8 + n).div_ceil(8) * 8).min(rest.len())
            } else {
                8 + n
            };
            (first, data, used)
        };
        let offset = self.pos;
        self.pos += used;
        Ok(Element { ty, data, offset })
    }
}

/// Where a value sits in the file, for messages (built only when one is needed).
#[derive(Clone, Copy)]
enum Loc<'a> {
    /// A top-level variable whose name is not read yet.
    At { offset: usize, compressed: bool },
    /// A top-level variable.
    Var(&'a str),
    /// A field of element `index` (0-based; `None` for a 1×1 struct) of a struct.
    Field {
        parent: &'a Loc<'a>,
        index: Option<usize>,
        name: &'a str,
    },
    /// Cell `index` (0-based) of a cell array.
    Cell { parent: &'a Loc<'a>, index: usize },
}

impl Loc<'_> {
    /// The MATLAB expression of the value (`sol(2).stats.x`, `c{3}`), 1-based.
    fn path(&self) -> String {
        match self {
            Loc::At { .. } => "?".into(),
            Loc::Var(name) => printable(name),
            Loc::Field {
                parent,
                index,
                name,
            } => match index {
                Some(k) => format!("{}({}).{}", parent.path(), k + 1, printable(name)),
                None => format!("{}.{}", parent.path(), printable(name)),
            },
            Loc::Cell { parent, index } => format!("{}{{{}}}", parent.path(), index + 1),
        }
    }
}

impl std::fmt::Display for Loc<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Loc::At {
                offset,
                compressed: false,
            } => write!(f, "the variable at byte {offset}"),
            Loc::At {
                offset,
                compressed: true,
            } => write!(f, "the compressed variable at byte {offset}"),
            _ => write!(f, "variable {}", self.path()),
        }
    }
}

/// What one decode carries along.
struct Ctx<'b> {
    big: bool,
    budget: &'b mut Budget,
    max_depth: usize,
}

/// The number of values of an array of dimensions `dims`, if it fits in a usize.
fn count(dims: &[usize]) -> Result<usize, String> {
    dims.iter()
        .try_fold(1usize, |n, &d| n.checked_mul(d))
        .ok_or_else(|| format!("dimensions {dims:?} overflow"))
}

/// A name (variable, field or class) from its bytes: up to the first NUL, as UTF-8
/// (invalid bytes replaced).
fn name_from(bytes: &[u8]) -> String {
    let end = bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len());
    String::from_utf8_lossy(&bytes[..end]).into_owned()
}

/// The name element of an array.
fn name_element(els: &mut Elements) -> Result<String, String> {
    let el = els.next(true)?;
    match el.ty {
        MI_INT8 | MI_UINT8 | MI_UTF8 => Ok(name_from(el.data)),
        t => Err(format!("the array name is stored as {}", type_name(t))),
    }
}

/// The values of a numeric data element, `n` of them, as f64.
fn numbers(ctx: &mut Ctx, el: &Element, n: usize) -> Result<Vec<f64>, String> {
    let size = match el.ty {
        MI_INT8 | MI_UINT8 => 1,
        MI_INT16 | MI_UINT16 => 2,
        MI_INT32 | MI_UINT32 | MI_SINGLE => 4,
        MI_DOUBLE | MI_INT64 | MI_UINT64 => 8,
        t => return Err(format!("values stored as {}", type_name(t))),
    };
    if n.checked_mul(size) != Some(el.data.len()) {
        return Err(format!(
            "{} bytes of {} for {n} values",
            el.data.len(),
            type_name(el.ty)
        ));
    }
    ctx.budget.take(8 * n as u64)?;
    let d = el.data;
    let big = ctx.big;
    Ok(match el.ty {
        MI_INT8 => d.iter().map(|&b| b as i8 as f64).collect(),
        MI_UINT8 => d.iter().map(|&b| b as f64).collect(),
        MI_INT16 => values!(d, i16, big),
        MI_UINT16 => values!(d, u16, big),
        MI_INT32 => values!(d, i32, big),
        MI_UINT32 => values!(d, u32, big),
        MI_SINGLE => values!(d, f32, big),
        MI_INT64 => values!(d, i64, big),
        MI_UINT64 => values!(d, u64, big),
        _ => values!(d, f64, big),
    })
}

/// The text of a char array of dimensions `dims` from its data element.
fn chars(ctx: &mut Ctx, el: &Element, dims: &[usize]) -> Result<String, String> {
    // At most one char (4 bytes) per stored byte.
    ctx.budget.take(4 * el.data.len() as u64)?;
    let big = ctx.big;
    let cs: Vec<char> = match el.ty {
        MI_UTF8 | MI_INT8 | MI_UINT8 => String::from_utf8_lossy(el.data).chars().collect(),
        MI_UTF16 | MI_UINT16 | MI_INT16 if el.data.len().is_multiple_of(2) => {
            let units = el.data.chunks_exact(2).map(|b| {
                let a = [b[0], b[1]];
                if big {
                    u16::from_be_bytes(a)
                } else {
                    u16::from_le_bytes(a)
                }
            });
            char::decode_utf16(units)
                .map(|c| c.unwrap_or(char::REPLACEMENT_CHARACTER))
                .collect()
        }
        MI_UTF32 | MI_UINT32 | MI_INT32 if el.data.len().is_multiple_of(4) => el
            .data
            .chunks_exact(4)
            .map(|b| char::from_u32(u32_of(b, big)).unwrap_or(char::REPLACEMENT_CHARACTER))
            .collect(),
        t => {
            return Err(format!(
                "char data of {} bytes stored as {}",
                el.data.len(),
                type_name(t)
            ))
        }
    };
    // Column-major: the rows of an R×C array, when the characters fill it.
    match dims {
        [r, c] if *r > 1 && r.checked_mul(*c) == Some(cs.len()) => Ok((0..*r)
            .map(|i| (0..*c).map(|j| cs[j * r + i]).collect::<String>())
            .collect::<Vec<_>>()
            .join("\n")),
        _ => Ok(cs.into_iter().collect()),
    }
}

/// The struct part of an array (after its name): field names, then each element's fields.
fn struct_value(
    ctx: &mut Ctx,
    els: &mut Elements,
    dims: Vec<usize>,
    depth: usize,
    here: &Loc,
) -> Result<MatValue, String> {
    let fail = |e: String| format!("{here}: {e}");
    let len_el = els.next(true).map_err(fail)?;
    let width = match (len_el.ty, len_el.data.len()) {
        (MI_INT32 | MI_UINT32, 4) => u32_of(len_el.data, ctx.big) as usize,
        (t, n) => {
            return Err(fail(format!(
                "the field-name length is {n} bytes of {}",
                type_name(t)
            )))
        }
    };
    let names_el = els.next(true).map_err(fail)?;
    if !matches!(names_el.ty, MI_INT8 | MI_UINT8 | MI_UTF8) {
        return Err(fail(format!(
            "the field names are stored as {}",
            type_name(names_el.ty)
        )));
    }
    let nfields = match names_el.data.len() {
        0 => 0,
        n if width > 0 && n.is_multiple_of(width) => n / width,
        n => {
            return Err(fail(format!(
                "{n} bytes of field names are not a whole number of {width}-byte names"
            )))
        }
    };
    let names: Vec<String> = names_el
        .data
        .chunks(width.max(1))
        .take(nfields)
        .map(name_from)
        .collect();
    let n = count(&dims).map_err(fail)?;
    // Each field of each element is a miMATRIX of 8 bytes at least: check that they can be
    // there before making room for them.
    let slots = n
        .checked_mul(nfields)
        .ok_or_else(|| fail(format!("{n} elements of {nfields} fields overflow")))?;
    let remaining = els.rest().len();
    if slots.checked_mul(8).is_none_or(|b| b > remaining) {
        return Err(fail(format!(
            "{n} struct elements of {nfields} fields cannot fit in the {remaining} bytes left"
        )));
    }
    ctx.budget
        .take(
            (n as u64)
                .saturating_mul(32)
                .saturating_add((slots as u64).saturating_mul(NODE_COST)),
        )
        .map_err(fail)?;
    let one = dims == [1, 1];
    let mut elements = Vec::with_capacity(n);
    for k in 0..n {
        let mut fields = Vec::with_capacity(nfields);
        for name in &names {
            let loc = Loc::Field {
                parent: here,
                index: (!one).then_some(k),
                name,
            };
            let el = els.next(true).map_err(|e| format!("{loc}: {e}"))?;
            if el.ty != MI_MATRIX {
                return Err(format!(
                    "{loc}: a {} element where a field (miMATRIX) belongs",
                    type_name(el.ty)
                ));
            }
            let (_, v) = matrix(ctx, el.data, depth + 1, &loc)?;
            fields.push((name.clone(), v));
        }
        elements.push(fields);
    }
    Ok(match elements.pop() {
        Some(fields) if one => MatValue::Struct(fields),
        last => {
            elements.extend(last);
            MatValue::StructArray { dims, elements }
        }
    })
}

/// The cells of a cell array (after its name).
fn cell_value(
    ctx: &mut Ctx,
    els: &mut Elements,
    dims: Vec<usize>,
    depth: usize,
    here: &Loc,
) -> Result<MatValue, String> {
    let fail = |e: String| format!("{here}: {e}");
    let n = count(&dims).map_err(fail)?;
    let remaining = els.rest().len();
    if n.checked_mul(8).is_none_or(|b| b > remaining) {
        return Err(fail(format!(
            "{n} cells cannot fit in the {remaining} bytes left"
        )));
    }
    ctx.budget
        .take((n as u64).saturating_mul(NODE_COST))
        .map_err(fail)?;
    let mut cells = Vec::with_capacity(n);
    for index in 0..n {
        let loc = Loc::Cell {
            parent: here,
            index,
        };
        let el = els.next(true).map_err(|e| format!("{loc}: {e}"))?;
        if el.ty != MI_MATRIX {
            return Err(format!(
                "{loc}: a {} element where a cell (miMATRIX) belongs",
                type_name(el.ty)
            ));
        }
        cells.push(matrix(ctx, el.data, depth + 1, &loc)?.1);
    }
    Ok(MatValue::Cell { dims, cells })
}

/// The array in the body of a `miMATRIX` element (`data`, its tag stripped) at nesting
/// `depth` (1 for a variable): its name and value. Errors name `loc`.
fn matrix(
    ctx: &mut Ctx,
    data: &[u8],
    depth: usize,
    loc: &Loc,
) -> Result<(String, MatValue), String> {
    if depth > ctx.max_depth {
        return Err(format!(
            "{loc}: structs or cells nested more than {} deep",
            ctx.max_depth
        ));
    }
    ctx.budget
        .take(NODE_COST)
        .map_err(|e| format!("{loc}: {e}"))?;
    // MATLAB writes an empty field as a miMATRIX element with no body.
    if data.is_empty() {
        return Ok((
            String::new(),
            MatValue::Double {
                dims: vec![0, 0],
                data: vec![],
            },
        ));
    }
    let mut els = Elements::new(data, ctx.big);
    let head = |els: &mut Elements| -> Result<(u32, u32), String> {
        let flags = els.next(true)?;
        if flags.ty != MI_UINT32 || flags.data.len() < 4 {
            return Err(format!(
                "the array flags are {} bytes of {}",
                flags.data.len(),
                type_name(flags.ty)
            ));
        }
        let f = u32_of(flags.data, els.big);
        Ok((f & 0xff, f))
    };
    let (class, flags) = head(&mut els).map_err(|e| format!("{loc}: {e}"))?;
    if class == MX_OPAQUE {
        // Flags, name, then a layout of its own (no dimensions): not ours to decode.
        let name = name_element(&mut els).map_err(|e| format!("{loc}: {e}"))?;
        return Ok((
            name,
            MatValue::Unread("a MATLAB opaque object (string, table, datetime, …)".into()),
        ));
    }
    let dims = (|| {
        let el = els.next(true)?;
        if !matches!(el.ty, MI_INT32 | MI_UINT32) || !el.data.len().is_multiple_of(4) {
            return Err(format!(
                "the dimensions are {} bytes of {}",
                el.data.len(),
                type_name(el.ty)
            ));
        }
        let mut dims = Vec::with_capacity(el.data.len() / 4);
        for b in el.data.chunks_exact(4) {
            let d = u32_of(b, ctx.big);
            if el.ty == MI_INT32 && d > i32::MAX as u32 {
                return Err(format!("a negative dimension {}", d as i32));
            }
            dims.push(d as usize);
        }
        match dims.len() {
            0 => return Err("no dimensions".into()),
            1 => dims.push(1),
            _ => {}
        }
        Ok(dims)
    })()
    .map_err(|e| format!("{loc}: {e}"))?;
    ctx.budget
        .take(8 * dims.len() as u64)
        .map_err(|e| format!("{loc}: {e}"))?;
    let name = name_element(&mut els).map_err(|e| format!("{loc}: {e}"))?;
    let here = match loc {
        Loc::At { .. } => Loc::Var(&name),
        other => *other,
    };
    let fail = |e: String| format!("{here}: {e}");
    let value = match class {
        MX_DOUBLE..=MX_UINT64 => {
            if flags & FLAG_COMPLEX != 0 {
                return Err(fail("complex arrays are not read".into()));
            }
            let n = count(&dims).map_err(fail)?;
            let data = if els.rest().is_empty() && n == 0 {
                vec![]
            } else {
                let el = els.next(true).map_err(fail)?;
                numbers(ctx, &el, n).map_err(fail)?
            };
            MatValue::Double { dims, data }
        }
        MX_CHAR => {
            let text = if els.rest().is_empty() {
                String::new()
            } else {
                let el = els.next(true).map_err(fail)?;
                chars(ctx, &el, &dims).map_err(fail)?
            };
            MatValue::Char(text)
        }
        MX_STRUCT => struct_value(ctx, &mut els, dims, depth, &here)?,
        MX_CELL => cell_value(ctx, &mut els, dims, depth, &here)?,
        MX_SPARSE => {
            return Err(fail(
                "sparse matrices are not read (save it as a full matrix: full(...))".into(),
            ))
        }
        MX_OBJECT => {
            let class = name_element(&mut els).map_err(fail)?;
            MatValue::Unread(format!("an object of class {}", printable(&class)))
        }
        MX_FUNCTION => MatValue::Unread("a function handle".into()),
        other => return Err(fail(format!("unknown array class {other}"))),
    };
    Ok((name, value))
}

/// Inflate one `miCOMPRESSED` element: the `miMATRIX` element inside, tag included, its
/// declared size charged to the budget before it is inflated (and no further byte read).
fn inflate(ctx: &mut Ctx, zipped: &[u8]) -> Result<Vec<u8>, String> {
    let mut z = flate2::read::ZlibDecoder::new(zipped);
    let mut out = Vec::new();
    ctx.budget.inflate(8)?;
    let corrupt = |e: String| format!("corrupt compressed data ({e})");
    read_exact_capped(&mut z, &mut out, 8).map_err(corrupt)?;
    let ty = u32_of(&out, ctx.big);
    if ty != MI_MATRIX {
        return Err(format!(
            "the compressed data holds a {} element, not a variable (miMATRIX)",
            type_name(ty)
        ));
    }
    let n = u32_of(&out[4..], ctx.big);
    ctx.budget.inflate(n as u64)?;
    read_exact_capped(&mut z, &mut out, n as usize).map_err(corrupt)?;
    Ok(out)
}

/// Why a file that is no MAT v5 file is refused, when it is a v7.3 or a v4 file.
fn other_mat_version(bytes: &[u8]) -> Option<String> {
    let v73 = "a MATLAB v7.3 (HDF5) file, which is not read: load it in MATLAB and save it as \
               v7, e.g. save('ref_v7.mat', 'sol', '-v7')";
    if bytes.starts_with(b"MATLAB 7.3")
        || bytes.get(512..520) == Some(HDF5_SIGNATURE)
        || (bytes.starts_with(b"MATLAB")
            && matches!(bytes.get(124..126), Some([0x00, 0x02] | [0x02, 0x00])))
    {
        return Some(v73.into());
    }
    if bytes.starts_with(HDF5_SIGNATURE) {
        return Some("an HDF5 file, not a MATLAB v5 .mat file".into());
    }
    // A v4 file starts with five 32-bit integers: type MOPT (M: 0-4, O: 0, P: 0-5, T:
    // 0-2), rows, columns, imaginary flag (0 or 1), name length (> 0).
    let h = bytes.get(..20)?;
    let v4 = [false, true].iter().any(|&big| {
        let w: Vec<u32> = h.chunks_exact(4).map(|b| u32_of(b, big)).collect();
        let t = w[0];
        t < 5000
            && (t / 100).is_multiple_of(10)
            && (t / 10) % 10 <= 5
            && t % 10 <= 2
            && w[1] <= i32::MAX as u32
            && w[2] <= i32::MAX as u32
            && w[3] <= 1
            && (1..=4096).contains(&w[4])
    });
    v4.then(|| {
        "a MAT v4 file, which is not read: load it in MATLAB or Octave and save it as v7, \
         e.g. save('ref_v7.mat', 'sol', '-v7')"
            .into()
    })
}

/// Decode the bytes of a .mat file (`path` only names it in errors) within the default
/// [`ReadLimits`].
pub fn decode(path: &Path, bytes: &[u8]) -> Result<Vec<(String, MatValue)>, MatError> {
    decode_with(path, bytes, &ReadLimits::default())
}

/// Decode the bytes of a .mat file within `limits`: every variable in file order.
pub fn decode_with(
    path: &Path,
    bytes: &[u8],
    limits: &ReadLimits,
) -> Result<Vec<(String, MatValue)>, MatError> {
    let bad = |reason: String| MatError::Format {
        path: path.to_path_buf(),
        reason,
    };
    if let Some(reason) = other_mat_version(bytes) {
        return Err(bad(reason));
    }
    if !bytes.starts_with(b"MATLAB") {
        return Err(bad(
            "not a MATLAB .mat file (it does not start with a 'MATLAB' header)".into(),
        ));
    }
    let Some(header) = bytes.get(..128) else {
        return Err(bad(format!(
            "the 128-byte header is cut short ({} bytes)",
            bytes.len()
        )));
    };
    let big = match &header[126..128] {
        b"IM" => false,
        b"MI" => true,
        other => {
            return Err(bad(format!(
                "the endian indicator is {:?}, neither 'IM' nor 'MI'",
                String::from_utf8_lossy(other)
            )))
        }
    };
    let v = [header[124], header[125]];
    let version = if big {
        u16::from_be_bytes(v)
    } else {
        u16::from_le_bytes(v)
    };
    if version != 0x0100 {
        return Err(bad(format!(
            "MAT-file version 0x{version:04x} (level 5 files are 0x0100)"
        )));
    }
    // Subsystem data (MATLAB objects' contents) after the variables is not ours: stop
    // before it. Spaces or zeros mean there is none.
    let sub = &header[116..124];
    let mut end = bytes.len();
    if sub.iter().any(|&b| b != 0 && b != b' ') {
        let mut a = [0u8; 8];
        a.copy_from_slice(sub);
        let off = if big {
            u64::from_be_bytes(a)
        } else {
            u64::from_le_bytes(a)
        };
        if let Ok(off) = usize::try_from(off) {
            if off >= 128 && off < end {
                end = off;
            }
        }
    }
    let mut budget = Budget::new(limits, bytes.len());
    let mut ctx = Ctx {
        big,
        budget: &mut budget,
        max_depth: limits.max_depth,
    };
    let mut els = Elements {
        bytes: &bytes[..end],
        pos: 128,
        big,
    };
    let mut vars = Vec::new();
    while !els.rest().is_empty() {
        // Zero padding at the end of a file is no variable.
        if els.rest().iter().all(|&b| b == 0) {
            break;
        }
        let at = els.pos;
        let el = els
            .next(false)
            .map_err(|e| bad(format!("the variable at byte {at}: {e}")))?;
        match el.ty {
            MI_MATRIX => {
                let loc = Loc::At {
                    offset: el.offset,
                    compressed: false,
                };
                vars.push(matrix(&mut ctx, el.data, 1, &loc).map_err(bad)?);
            }
            MI_COMPRESSED => {
                let loc = Loc::At {
                    offset: el.offset,
                    compressed: true,
                };
                let inner = inflate(&mut ctx, el.data).map_err(|e| bad(format!("{loc}: {e}")))?;
                // `inflate` checked the tag: the body follows it.
                vars.push(matrix(&mut ctx, &inner[8..], 1, &loc).map_err(bad)?);
            }
            t => {
                return Err(bad(format!(
                    "a {} element at byte {} where a variable (miMATRIX or miCOMPRESSED) \
                     belongs",
                    type_name(t),
                    el.offset
                )))
            }
        }
    }
    Ok(vars)
}

/// Read every variable of the .mat file `path` within the default [`ReadLimits`].
pub fn read(path: &Path) -> Result<Vec<(String, MatValue)>, MatError> {
    read_with(path, &ReadLimits::default())
}

/// Read every variable of the .mat file `path` within `limits` (a file larger than
/// `limits.max_bytes` is refused before it is read).
pub fn read_with(path: &Path, limits: &ReadLimits) -> Result<Vec<(String, MatValue)>, MatError> {
    let io = |source| MatError::Io {
        path: path.to_path_buf(),
        source,
    };
    let size = fs::metadata(path).map_err(io)?.len();
    if size > limits.max_bytes {
        return Err(MatError::Format {
            path: path.to_path_buf(),
            reason: format!(
                "{} bytes, larger than the readers' limit of {}",
                size,
                super::human_bytes(limits.max_bytes)
            ),
        });
    }
    let bytes = fs::read(path).map_err(io)?;
    decode_with(path, &bytes, limits)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Vec<(String, MatValue)> {
        vec![
            ("h".into(), MatValue::row(&[0.65, 0.6, 1e-300, -2.5e17])),
            ("time".into(), MatValue::scalar(0.1)),
            (
                "sol".into(),
                MatValue::Struct(vec![
                    ("solver".into(), MatValue::Char("bvp4c".into())),
                    ("unicode".into(), MatValue::Char("Σ κ α_s €𝄞".into())),
                    (
                        "stats".into(),
                        MatValue::Struct(vec![("nmeshpoints".into(), MatValue::scalar(3.0))]),
                    ),
                    ("x".into(), MatValue::row(&[1e-3, 0.5, 1.0])),
                    (
                        "y".into(),
                        MatValue::from_rows(&[
                            vec![1.0, 2.0, 3.0],
                            vec![4.0, 5.0, 6.0],
                            vec![7.0, 8.0, 9.0],
                            vec![10.0, 11.0, 12.0],
                            vec![13.0, 14.0, f64::MIN_POSITIVE],
                        ]),
                    ),
                    ("alpha_phi".into(), MatValue::row(&[1.25, 1.5, 1.75])),
                ]),
            ),
            ("z_retina".into(), MatValue::row(&[])),
        ]
    }

    #[test]
    fn layout_of_a_row_vector() {
        let bytes = encode(&[("h".into(), MatValue::row(&[1.0, 2.0]))], false).unwrap();
        assert_eq!(bytes.len(), 128 + 8 + 16 + 16 + 8 + 8 + 16);
        assert_eq!(&bytes[124..128], &[0x00, 0x01, b'I', b'M']);
        // miMATRIX, 64 bytes of body.
        assert_eq!(&bytes[128..136], &[14, 0, 0, 0, 64, 0, 0, 0]);
        // The name "h" as a small element.
        assert_eq!(&bytes[168..176], &[1, 0, 1, 0, b'h', 0, 0, 0]);
    }

    #[test]
    fn round_trip_plain_and_compressed() {
        let vars = sample();
        for compress in [false, true] {
            let bytes = encode(&vars, compress).unwrap();
            if !compress {
                // Uncompressed elements are padded to 8 bytes; compressed ones need not be.
                assert!(bytes.len().is_multiple_of(8), "{} bytes", bytes.len());
            }
            let back = decode(Path::new("mem.mat"), &bytes).unwrap();
            assert_eq!(back, vars, "compress = {compress}");
        }
        let y = vars[2].1.field("y").unwrap();
        assert_eq!(y.row_of(4).unwrap(), vec![13.0, 14.0, f64::MIN_POSITIVE]);
    }

    #[test]
    fn bad_files_and_names_are_refused() {
        let p = Path::new("x.mat");
        assert!(decode(p, b"hello")
            .unwrap_err()
            .to_string()
            .contains("x.mat"));
        // A little-endian file marked big-endian: every tag reads wrong, and is refused.
        let mut b = encode(&sample(), false).unwrap();
        b[126] = b'M';
        b[127] = b'I';
        let e = decode(p, &b).unwrap_err().to_string();
        assert!(e.starts_with("x.mat: "), "{e}");
        let b = encode(&sample(), false).unwrap();
        assert!(decode(p, &b[..b.len() - 20]).is_err());
        assert!(encode(&[("1x".into(), MatValue::scalar(1.0))], false).is_err());
        // SciPy's header text has no comma after "MAT-file"; it reads all the same.
        let mut b = encode(&sample(), true).unwrap();
        let text = b"MATLAB 5.0 MAT-file Platform: posix, Created on: Mon Jan  1 00:00:00 2024";
        b[..116].fill(b' ');
        b[..text.len()].copy_from_slice(text);
        assert_eq!(decode(p, &b).unwrap(), sample());
    }

    /// A MAT v5 file built by hand, in either byte order.
    struct Builder {
        big: bool,
    }

    impl Builder {
        fn u32s(&self, xs: &[u32]) -> Vec<u8> {
            xs.iter()
                .flat_map(|x| {
                    if self.big {
                        x.to_be_bytes()
                    } else {
                        x.to_le_bytes()
                    }
                })
                .collect()
        }

        /// A normal element, padded to 8 bytes.
        fn el(&self, ty: u32, data: &[u8]) -> Vec<u8> {
            let mut out = self.u32s(&[ty, data.len() as u32]);
            out.extend_from_slice(data);
            pad8(&mut out);
            out
        }

        /// A small element (1 to 4 bytes).
        fn small(&self, ty: u32, data: &[u8]) -> Vec<u8> {
            let mut out = self.u32s(&[((data.len() as u32) << 16) | ty]);
            out.extend_from_slice(data);
            out.resize(8, 0);
            out
        }

        /// A miMATRIX element: flags, dims, name, then `rest`.
        fn matrix(&self, flags: u32, dims: &[u32], name: &str, rest: &[Vec<u8>]) -> Vec<u8> {
            let mut body = self.el(MI_UINT32, &self.u32s(&[flags, 0]));
            body.extend(self.el(MI_INT32, &self.u32s(dims)));
            body.extend(self.el(MI_INT8, name.as_bytes()));
            for r in rest {
                body.extend_from_slice(r);
            }
            self.el(MI_MATRIX, &body)
        }

        fn file(&self, vars: &[Vec<u8>]) -> Vec<u8> {
            let mut out = b"MATLAB 5.0 MAT-file, Platform: test".to_vec();
            out.resize(116, b' ');
            out.extend_from_slice(&[0; 8]);
            out.extend_from_slice(if self.big {
                b"\x01\x00MI"
            } else {
                b"\x00\x01IM"
            });
            for v in vars {
                out.extend_from_slice(v);
            }
            out
        }

        /// A 1×1 struct named `name` with the given fields (each a miMATRIX element).
        fn structure(&self, name: &str, fields: &[(&str, Vec<u8>)]) -> Vec<u8> {
            let mut names = vec![0u8; 8 * fields.len()];
            for (k, (f, _)) in fields.iter().enumerate() {
                names[8 * k..8 * k + f.len()].copy_from_slice(f.as_bytes());
            }
            let mut rest = vec![
                self.small(MI_INT32, &self.u32s(&[8])),
                self.el(MI_INT8, &names),
            ];
            rest.extend(fields.iter().map(|(_, v)| v.clone()));
            self.matrix(MX_STRUCT, &[1, 1], name, &rest)
        }
    }

    #[test]
    fn both_byte_orders_and_every_class() {
        for big in [false, true] {
            let b = Builder { big };
            let f64s: Vec<u8> = [1.5f64, -2.0, 1e-300, 4.0, 5.0, 6.0]
                .iter()
                .flat_map(|x| {
                    if big {
                        x.to_be_bytes()
                    } else {
                        x.to_le_bytes()
                    }
                })
                .collect();
            let i16s: Vec<u8> = [-3i16, 7]
                .iter()
                .flat_map(|x| {
                    if big {
                        x.to_be_bytes()
                    } else {
                        x.to_le_bytes()
                    }
                })
                .collect();
            let utf16: Vec<u8> = "bvp4c"
                .encode_utf16()
                .flat_map(|x| {
                    if big {
                        x.to_be_bytes()
                    } else {
                        x.to_le_bytes()
                    }
                })
                .collect();
            let file = b.file(&[
                b.matrix(MX_DOUBLE, &[2, 3], "M", &[b.el(MI_DOUBLE, &f64s)]),
                // A double array stored as miINT16 (MATLAB narrows integer values).
                b.matrix(MX_DOUBLE, &[1, 2], "n", &[b.small(MI_INT16, &i16s)]),
                // Logical (uint8 class, logical flag), stored as miUINT8.
                b.matrix(0x0200 | 9, &[1, 3], "ok", &[b.small(MI_UINT8, &[1, 0, 1])]),
                b.matrix(MX_CHAR, &[1, 5], "solver", &[b.el(MI_UINT16, &utf16)]),
                b.structure(
                    "sol",
                    &[
                        (
                            "x",
                            b.matrix(MX_DOUBLE, &[1, 2], "", &[b.small(MI_INT16, &i16s)]),
                        ),
                        (
                            "stats",
                            b.structure("", &[("maxres", b.matrix(MX_DOUBLE, &[0, 0], "", &[]))]),
                        ),
                    ],
                ),
                b.matrix(MX_FUNCTION, &[1, 1], "f", &[]),
            ]);
            let vars = decode(Path::new("be.mat"), &file).unwrap();
            let names: Vec<&str> = vars.iter().map(|(n, _)| n.as_str()).collect();
            assert_eq!(names, ["M", "n", "ok", "solver", "sol", "f"], "big = {big}");
            assert_eq!(vars[0].1.row_of(1).unwrap(), vec![-2.0, 4.0, 6.0]);
            assert_eq!(vars[1].1.data().unwrap(), &[-3.0, 7.0]);
            assert_eq!(vars[2].1.data().unwrap(), &[1.0, 0.0, 1.0]);
            assert_eq!(vars[3].1.text(), Some("bvp4c"));
            let sol = &vars[4].1;
            assert_eq!(sol.field("x").unwrap().data().unwrap(), &[-3.0, 7.0]);
            assert_eq!(
                sol.field("stats").unwrap().field("maxres").unwrap().dims(),
                Some(&[0usize, 0][..])
            );
            assert_eq!(vars[5].1, MatValue::Unread("a function handle".into()));
        }
    }

    #[test]
    fn refusals_name_the_file_and_the_variable() {
        let b = Builder { big: false };
        let p = Path::new("r.mat");
        let err = |bytes: &[u8]| decode(p, bytes).unwrap_err().to_string();
        // Sparse and complex.
        let e = err(&b.file(&[b.matrix(MX_SPARSE, &[3, 3], "J", &[])]));
        assert_eq!(
            e,
            "r.mat: variable J: sparse matrices are not read (save it as a full matrix: full(...))"
        );
        let e = err(&b.file(&[b.structure(
            "sol",
            &[("z", b.matrix(MX_DOUBLE | FLAG_COMPLEX, &[1, 1], "", &[]))],
        )]));
        assert_eq!(e, "r.mat: variable sol.z: complex arrays are not read");
        // v7.3: MATLAB's text header and an HDF5 superblock at 512.
        let mut v73 = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon".to_vec();
        v73.resize(512, b' ');
        v73.extend_from_slice(HDF5_SIGNATURE);
        v73.resize(2048, 0);
        let e = err(&v73);
        assert!(e.contains("v7.3") && e.contains("'-v7'"), "{e}");
        assert_eq!(e.lines().count(), 1);
        // v4: a 3x1 double named "x" (type 0000: little-endian doubles).
        let mut v4 = Vec::new();
        for w in [0u32, 3, 1, 0, 2] {
            v4.extend_from_slice(&w.to_le_bytes());
        }
        v4.extend_from_slice(b"x\0");
        v4.extend_from_slice(&[0; 24]);
        assert!(err(&v4).contains("MAT v4 file"), "{}", err(&v4));
        assert!(err(b"").contains("not a MATLAB .mat file"));
        assert!(err(b"MATLAB 5.0").contains("cut short"));
        // Dimensions whose product overflows, and data that is not there.
        let e = err(&b.file(&[b.matrix(
            MX_DOUBLE,
            &[0x7fff_ffff, 0x7fff_ffff, 0x7fff_ffff],
            "big",
            &[],
        )]));
        assert!(e.contains("variable big") && e.contains("overflow"), "{e}");
        let e = err(&b.file(&[b.matrix(
            MX_DOUBLE,
            &[1000, 1000],
            "big",
            &[b.el(MI_DOUBLE, &[0; 16])],
        )]));
        assert!(e.contains("16 bytes of miDOUBLE for 1000000 values"), "{e}");
        let e = err(&b.file(&[b.matrix(MX_CELL, &[100000, 100000], "c", &[])]));
        assert!(
            e.contains("variable c: 10000000000 cells cannot fit"),
            "{e}"
        );
        // A struct array of a billion elements with no fields: refused by the budget.
        let mut rest = vec![b.small(MI_INT32, &b.u32s(&[1])), b.el(MI_INT8, &[])];
        rest.truncate(2);
        let e = err(&b.file(&[b.matrix(MX_STRUCT, &[100000, 100000], "s", &rest)]));
        assert!(e.contains("variable s: holds more than 1 GiB"), "{e}");
        // A name with a terminal escape is printed escaped.
        let e = err(&b.file(&[b.matrix(MX_SPARSE, &[1, 1], "a\x1b[2Jb", &[])]));
        assert!(e.contains("variable a\\u{1b}[2Jb:"), "{e}");
    }

    #[test]
    fn nesting_is_bounded() {
        let b = Builder { big: false };
        // sol.a.a.a… `depth` levels of struct, then a scalar.
        let nested = |depth: usize| {
            let f64s = 2.5f64.to_le_bytes();
            let mut v = b.matrix(MX_DOUBLE, &[1, 1], "", &[b.el(MI_DOUBLE, &f64s)]);
            for level in (0..depth).rev() {
                v = b.structure(if level == 0 { "sol" } else { "" }, &[("a", v)]);
            }
            b.file(&[v])
        };
        let vars = decode(Path::new("n.mat"), &nested(31)).unwrap();
        let mut v = &vars[0].1;
        while let Some(inner) = v.field("a") {
            v = inner;
        }
        assert_eq!(v.data(), Some(&[2.5][..]));
        let e = decode(Path::new("n.mat"), &nested(32))
            .unwrap_err()
            .to_string();
        assert!(e.contains("nested more than 32 deep"), "{e}");
        assert!(e.contains("variable sol.a.a."), "{e}");
        // Thousands deep: refused the same, no stack overflow.
        let e = decode(Path::new("n.mat"), &nested(5000))
            .unwrap_err()
            .to_string();
        assert!(e.contains("nested more than 32 deep"), "{e}");
        let tight = ReadLimits {
            max_depth: 3,
            ..ReadLimits::default()
        };
        assert!(decode_with(Path::new("n.mat"), &nested(3), &tight).is_err());
        assert!(decode_with(Path::new("n.mat"), &nested(2), &tight).is_ok());
    }

    #[test]
    fn decompression_is_capped() {
        // 16 MiB of zeros in one compressed double array: about 16 KiB on disk, a ratio
        // near 1000.
        let n = 2 << 20;
        let bomb = vec![("z".to_string(), MatValue::row(&vec![0.0; n]))];
        let bytes = encode(&bomb, true).unwrap();
        assert!(bytes.len() < 200_000, "{}", bytes.len());
        let e = decode(Path::new("bomb.mat"), &bytes)
            .unwrap_err()
            .to_string();
        assert!(e.contains("128 times the file's size"), "{e}");
        // Allowed by a generous ratio, refused by a small total.
        let loose = ReadLimits {
            max_ratio: 2000,
            ..ReadLimits::default()
        };
        assert_eq!(
            decode_with(Path::new("bomb.mat"), &bytes, &loose).unwrap(),
            bomb
        );
        let small = ReadLimits {
            max_bytes: 8 << 20,
            max_ratio: 2000,
            ..ReadLimits::default()
        };
        let e = decode_with(Path::new("bomb.mat"), &bytes, &small)
            .unwrap_err()
            .to_string();
        assert!(e.contains("holds more than 8 MiB"), "{e}");
        // A tag claiming 4 GiB inside the compressed stream is refused before inflating.
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
        z.write_all(&[14, 0, 0, 0, 0xf8, 0xff, 0xff, 0xff]).unwrap();
        let zipped = z.finish().unwrap();
        let mut f = header();
        f.extend_from_slice(&MI_COMPRESSED.to_le_bytes());
        f.extend_from_slice(&(zipped.len() as u32).to_le_bytes());
        f.extend(zipped);
        let e = decode(Path::new("lie.mat"), &f).unwrap_err().to_string();
        assert!(e.contains("compressed variable at byte 128"), "{e}");
        assert!(e.contains("128 times"), "{e}");
        let no_ratio = ReadLimits {
            max_ratio: u64::MAX,
            ..ReadLimits::default()
        };
        let e = decode_with(Path::new("lie.mat"), &f, &no_ratio)
            .unwrap_err()
            .to_string();
        assert!(e.contains("holds more than 1 GiB"), "{e}");
    }
}
