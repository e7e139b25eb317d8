//! MATLAB v5 .mat files: a writer of our own and a reader on top of the `matrw` crate.
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
//! Reading goes through `matrw` (numeric, struct and cell arrays, `miCOMPRESSED`, small
//! elements), which we convert to [`MatValue`]: numeric arrays of any class become f64,
//! 1×1 structs become [`MatValue::Struct`], anything else is skipped. Only little-endian
//! files are read (MATLAB, Octave and SciPy write those on every current platform); a
//! big-endian file, a v7.3 (HDF5) file or a file that is not a .mat file is refused with a
//! message saying so.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use eyeshell::rundir::write_atomic;

/// `miINT8`.
const MI_INT8: u32 = 1;
/// `miINT32`.
const MI_INT32: u32 = 5;
/// `miUINT32`.
const MI_UINT32: u32 = 6;
/// `miDOUBLE`.
const MI_DOUBLE: u32 = 9;
/// `miMATRIX`.
const MI_MATRIX: u32 = 14;
/// `miCOMPRESSED`.
const MI_COMPRESSED: u32 = 15;
/// `mxSTRUCT_CLASS`.
const MX_STRUCT: u32 = 2;
/// `mxDOUBLE_CLASS`.
const MX_DOUBLE: u32 = 6;
/// Bytes per field name in a struct (31 characters and a NUL).
const FIELD_NAME_LEN: usize = 32;

/// One MATLAB value: a real double array or a 1×1 struct.
#[derive(Clone, Debug, PartialEq)]
pub enum MatValue {
    /// A real double array: its dimensions and its values in column-major order.
    Double { dims: Vec<usize>, data: Vec<f64> },
    /// A 1×1 struct: its fields in order.
    Struct(Vec<(String, MatValue)>),
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

    /// The values of a double array, column-major.
    pub fn data(&self) -> Option<&[f64]> {
        match self {
            MatValue::Double { data, .. } => Some(data),
            MatValue::Struct(_) => None,
        }
    }

    /// The dimensions of a double array.
    pub fn dims(&self) -> Option<&[usize]> {
        match self {
            MatValue::Double { dims, .. } => Some(dims),
            MatValue::Struct(_) => None,
        }
    }

    /// Row `i` of a 2-D double array.
    pub fn row_of(&self, i: usize) -> Option<Vec<f64>> {
        match self {
            MatValue::Double { dims, data } if dims.len() == 2 && i < dims[0] => {
                Some((0..dims[1]).map(|j| data[j * dims[0] + i]).collect())
            }
            _ => None,
        }
    }

    /// A field of a struct.
    pub fn field(&self, name: &str) -> Option<&MatValue> {
        match self {
            MatValue::Struct(fields) => fields.iter().find(|(n, _)| n == name).map(|(_, v)| v),
            MatValue::Double { .. } => None,
        }
    }
}

/// Why a .mat file could not be written or read. Display names the file.
#[derive(Debug, thiserror::Error)]
pub enum MatError {
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: not a readable MATLAB v5 .mat file: {reason}", path.display())]
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
    }
    let mut out = Vec::with_capacity(body.len() + 8);
    out.extend_from_slice(&MI_MATRIX.to_le_bytes());
    out.extend_from_slice(&(body.len() as u32).to_le_bytes());
    out.extend(body);
    Ok(out)
}

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

fn numeric_to_f64(v: &matrw::MatlabType) -> Option<Vec<f64>> {
    use matrw::MatlabType as T;
    Some(match v {
        T::U8(x) => x.iter().map(|&a| a as f64).collect(),
        T::I8(x) => x.iter().map(|&a| a as f64).collect(),
        T::U16(x) => x.iter().map(|&a| a as f64).collect(),
        T::I16(x) => x.iter().map(|&a| a as f64).collect(),
        T::U32(x) => x.iter().map(|&a| a as f64).collect(),
        T::I32(x) => x.iter().map(|&a| a as f64).collect(),
        T::U64(x) => x.iter().map(|&a| a as f64).collect(),
        T::I64(x) => x.iter().map(|&a| a as f64).collect(),
        T::F32(x) => x.iter().map(|&a| a as f64).collect(),
        T::F64(x) => x.clone(),
        T::BOOL(x) => x.iter().map(|&a| if a { 1.0 } else { 0.0 }).collect(),
        T::UTF8(_) | T::UTF16(_) => return None,
    })
}

fn convert(v: &matrw::MatVariable) -> Option<MatValue> {
    use matrw::MatVariable as V;
    match v {
        V::Compressed(c) => convert(&c.value),
        V::NumericArray(n) => {
            let data = numeric_to_f64(&n.value)?;
            let mut dims = n.dim.clone();
            if dims.len() < 2 {
                dims.resize(2, 1);
            }
            if dims.iter().product::<usize>() != data.len() {
                return None;
            }
            Some(MatValue::Double { dims, data })
        }
        V::Structure(s) => Some(MatValue::Struct(
            s.value
                .iter()
                .filter_map(|(k, v)| convert(v).map(|c| (k.clone(), c)))
                .collect(),
        )),
        V::StructureArray(a) if a.value.len() == 1 => convert(&a.value[0]),
        _ => None,
    }
}

/// Decode the bytes of a .mat file (`path` only names it in errors).
pub fn decode(path: &Path, bytes: &[u8]) -> Result<Vec<(String, MatValue)>, MatError> {
    let bad = |reason: String| MatError::Format {
        path: path.to_path_buf(),
        reason,
    };
    if bytes.len() < 128 || !bytes.starts_with(b"MATLAB") {
        return Err(bad(
            "no MATLAB header (the file does not start with 'MATLAB' and 128 header bytes)".into(),
        ));
    }
    match &bytes[126..128] {
        b"IM" => {}
        b"MI" => return Err(bad("big-endian files are not supported".into())),
        other => {
            return Err(bad(format!(
                "endian indicator {other:?} is neither 'IM' nor 'MI'"
            )))
        }
    }
    let version = u16::from_le_bytes([bytes[124], bytes[125]]);
    if version == 0x0200 {
        return Err(bad("a v7.3 (HDF5) file: save it with -v7 or -v6".into()));
    }
    if version != 0x0100 {
        return Err(bad(format!("version 0x{version:04x} (expected 0x0100)")));
    }
    // Subsystem data (MATLAB objects) after the variables is not ours: stop before it.
    let sub = &bytes[116..124];
    let mut end = bytes.len();
    if sub.iter().any(|&b| b != 0 && b != b' ') {
        let off = u64::from_le_bytes(sub.try_into().expect("8 bytes")) as usize;
        if off >= 128 && off < end {
            end = off;
        }
    }
    // matrw insists on the text starting "MATLAB 5.0 MAT-file, " (SciPy writes no comma):
    // the header is checked above, so hand it ours.
    let mut owned = header();
    owned.extend_from_slice(&bytes[128..end]);
    let bytes = &owned[..];
    // matrw may panic on malformed input: turn that into an error too.
    let parsed = std::panic::catch_unwind(|| matrw::load_matfile_from_u8(bytes));
    let file = match parsed {
        Ok(Ok(f)) => f,
        Ok(Err(e)) => return Err(bad(e.to_string().replace('\n', " "))),
        Err(_) => return Err(bad("malformed data elements".into())),
    };
    Ok(file
        .iter()
        .filter_map(|(k, v)| convert(v).map(|c| (k.clone(), c)))
        .collect())
}

/// Read the variables of the .mat file `path` that are numeric arrays or 1×1 structs.
pub fn read(path: &Path) -> Result<Vec<(String, MatValue)>, MatError> {
    let bytes = fs::read(path).map_err(|source| MatError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    decode(path, &bytes)
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
        let mut b = encode(&sample(), false).unwrap();
        b[126] = b'M';
        b[127] = b'I';
        assert!(decode(p, &b)
            .unwrap_err()
            .to_string()
            .contains("big-endian"));
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
}
