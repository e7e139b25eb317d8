//! The reader: level 5 files as MATLAB, Octave and SciPy write them, every size checked
//! before anything is allocated.

use std::fs;
use std::path::Path;

use super::{
    MatError, MatValue, FLAG_COMPLEX, HDF5_SIGNATURE, MI_COMPRESSED, MI_DOUBLE, MI_INT16, MI_INT32,
    MI_INT64, MI_INT8, MI_MATRIX, MI_SINGLE, MI_UINT16, MI_UINT32, MI_UINT64, MI_UINT8, MI_UTF16,
    MI_UTF32, MI_UTF8, MX_CELL, MX_CHAR, MX_DOUBLE, MX_FUNCTION, MX_OBJECT, MX_OPAQUE, MX_SPARSE,
    MX_STRUCT, MX_UINT64, NODE_COST,
};
use crate::interop::{printable, read_exact_capped, Budget, ReadLimits};

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
                crate::interop::human_bytes(limits.max_bytes)
            ),
        });
    }
    let bytes = fs::read(path).map_err(io)?;
    decode_with(path, &bytes, limits)
}
