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
//!   to [`ReadLimits::max_depth`](super::ReadLimits::max_depth);
//! - cell arrays: [`MatValue::Cell`];
//! - objects, function handles and MATLAB's opaque classes (`string`, `table`, …):
//!   [`MatValue::Unread`], naming what it is;
//! - sparse and complex arrays are refused, naming the variable.
//!
//! MATLAB v7.3 files (HDF5) and v4 files are refused with a line saying how to re-save them
//! as v7. Every size the file declares is checked (checked arithmetic, against the bytes
//! present and the [`ReadLimits`](super::ReadLimits) budget) before anything is allocated; decompression stops
//! at the budget; every error is one line naming the file and the variable. Nothing in the
//! reader panics on any input (tests/cli/readers.rs fuzzes it).

mod read;
#[cfg(test)]
mod tests;
mod write;

use std::path::PathBuf;

use super::printable;
pub(crate) use read::values;
pub use read::{decode, decode_with, read, read_with};
pub use write::{encode, header, write, SIGNATURE};

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
