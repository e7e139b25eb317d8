//! The writer: variables as level 5 `miMATRIX` elements, optionally compressed.

use std::io::Write;
use std::path::Path;

use super::{
    MatError, MatValue, FIELD_NAME_LEN, MI_COMPRESSED, MI_DOUBLE, MI_INT32, MI_INT8, MI_MATRIX,
    MI_UINT16, MI_UINT32, MX_CHAR, MX_DOUBLE, MX_STRUCT,
};
use crate::rundir::write_atomic;

pub(super) fn pad8(out: &mut Vec<u8>) {
    while !out.len().is_multiple_of(8) {
        out.push(0);
    }
}

/// A data element: the small form (4-byte tag, up to 4 bytes of data) when `small` allows
/// and the data fits, else the 8-byte tag, the data and padding to 8 bytes.
pub(super) fn element(out: &mut Vec<u8>, ty: u32, bytes: &[u8], small: bool) {
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
