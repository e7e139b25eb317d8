//! NumPy .npz files: a zip archive of .npy arrays (`NAME.npy`), as `numpy.savez` writes.
//!
//! Every array is written as NPY format version 1.0: the magic `\x93NUMPY`, version 1.0, a
//! little-endian u16 header length, the header dict
//! `{'descr': '<f8', 'fortran_order': False, 'shape': (...), }` padded with spaces and a
//! newline so that the data starts at a multiple of 64 bytes, then the little-endian f64
//! values in C (row-major) order. Members are deflate-compressed (`numpy.load` reads both).

use std::io::{Read, Write};
use std::path::Path;

use eyeshell::rundir::write_atomic;

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
#[error("{}: {reason}", path.display())]
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

/// Parse one .npy file of little-endian f64 in C order.
pub fn parse_npy(bytes: &[u8]) -> Result<NpyArray, String> {
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        return Err("not an .npy array (no \\x93NUMPY magic)".into());
    }
    let (hlen, start) = match bytes[6] {
        1 => (u16::from_le_bytes([bytes[8], bytes[9]]) as usize, 10),
        2 | 3 if bytes.len() >= 12 => (
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
            12,
        ),
        v => return Err(format!("unsupported .npy version {v}")),
    };
    let header = bytes
        .get(start..start + hlen)
        .and_then(|h| std::str::from_utf8(h).ok())
        .ok_or("truncated .npy header")?;
    if !header.contains("'descr': '<f8'") {
        return Err(format!(
            "only little-endian float64 arrays are read: {}",
            header.trim()
        ));
    }
    if header.contains("'fortran_order': True") {
        return Err("Fortran-order arrays are not read".into());
    }
    let shape_text = header
        .split("'shape':")
        .nth(1)
        .and_then(|s| s.split(')').next())
        .map(|s| s.trim().trim_start_matches('('))
        .ok_or("no shape in the .npy header")?;
    let shape = shape_text
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| {
            s.parse::<usize>()
                .map_err(|_| format!("bad shape {shape_text:?}"))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let n: usize = shape.iter().product();
    let body = &bytes[start + hlen..];
    if body.len() != 8 * n {
        return Err(format!("{} data bytes for shape {shape:?}", body.len()));
    }
    let data = body
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
        .collect();
    Ok(NpyArray { shape, data })
}

/// The bytes of a .npz archive of `arrays` (member `NAME.npy` each).
pub fn encode(arrays: &[(String, NpyArray)]) -> Result<Vec<u8>, String> {
    let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
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
    let bytes = encode(arrays).map_err(err)?;
    write_atomic(path, &bytes).map_err(|e| err(e.to_string()))
}

/// Read every `NAME.npy` member of the .npz file `path`, in archive order.
pub fn read(path: &Path) -> Result<Vec<(String, NpyArray)>, NpzError> {
    let err = |reason: String| NpzError {
        path: path.to_path_buf(),
        reason,
    };
    let file = std::fs::File::open(path).map_err(|e| err(e.to_string()))?;
    let mut zip =
        zip::ZipArchive::new(file).map_err(|e| err(format!("not a .npz (zip) file: {e}")))?;
    let mut out = Vec::new();
    for i in 0..zip.len() {
        let mut member = zip.by_index(i).map_err(|e| err(e.to_string()))?;
        let name = member.name().map_err(|e| err(e.to_string()))?.to_string();
        let Some(stem) = name.strip_suffix(".npy") else {
            continue;
        };
        let mut bytes = Vec::new();
        member
            .read_to_end(&mut bytes)
            .map_err(|e| err(format!("{name}: {e}")))?;
        let a = parse_npy(&bytes).map_err(|e| err(format!("{name}: {e}")))?;
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
}
