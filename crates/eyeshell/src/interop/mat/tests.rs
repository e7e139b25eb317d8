use std::io::Write;
use std::path::Path;

use super::write::pad8;
use super::*;
use super::{
    MatValue, FLAG_COMPLEX, HDF5_SIGNATURE, MI_COMPRESSED, MI_DOUBLE, MI_INT16, MI_INT32, MI_INT8,
    MI_MATRIX, MI_UINT16, MI_UINT32, MI_UINT8, MX_CELL, MX_CHAR, MX_DOUBLE, MX_FUNCTION, MX_SPARSE,
    MX_STRUCT,
};
use crate::interop::ReadLimits;

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
