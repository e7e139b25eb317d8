//! Fuzz of the foreign-file readers (a fuzz target for each foreign-file reader): .mat decode, .npy parse and .npz decode on random bytes and on mutations (bit
//! flips, overwritten bytes, length fields set to huge values, truncations, insertions and
//! deletions) of valid files: eyeshell's own writer's output and the SciPy/NumPy fixtures,
//! raw and, for compressed containers, inside the compression (the mutated variable or
//! member compressed again, so that the parser and not only zlib or the CRC sees it).
//!
//! Each call must return without panicking, within a time bound, and an error must be one
//! non-empty line naming the file. The runs are seeded (ChaCha) and their case counts fixed,
//! so CI runs the same cases every time; the whole set (26,000 cases) takes a few seconds in
//! release. For a longer hunt, `EYESHELL_FUZZ_SCALE=50 cargo test --release --test cli
//! fuzz_readers` multiplies every case count (the first cases stay the same).

use crate::support::repo;
use eyeshell::interop::mat::{self, MatValue};
use eyeshell::interop::npz::{self, NpyArray};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use std::io::{Read, Write};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;
use std::time::{Duration, Instant};

/// The bound on one call (a generous one: CI machines are shared; the calls take
/// microseconds to a few milliseconds).
pub(crate) const TIME_BOUND: Duration = Duration::from_secs(2);

pub(crate) fn runner(cases: u32, seed: u8) -> TestRunner {
    let scale: u32 = std::env::var("EYESHELL_FUZZ_SCALE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1);
    let config = Config {
        cases: cases.saturating_mul(scale),
        failure_persistence: None,
        rng_algorithm: RngAlgorithm::ChaCha,
        ..Config::default()
    };
    TestRunner::new_with_rng(
        config,
        TestRng::from_seed(RngAlgorithm::ChaCha, &[seed; 32]),
    )
}

/// Run one reader on `bytes`: no panic, bounded time, a one-line error naming `name`.
fn check<T>(
    name: &str,
    bytes: &[u8],
    read: impl FnOnce(&[u8]) -> Result<T, String>,
) -> Result<(), TestCaseError> {
    let start = Instant::now();
    let r = catch_unwind(AssertUnwindSafe(|| read(bytes)));
    let took = start.elapsed();
    let head = &bytes[..bytes.len().min(160)];
    let r = r.map_err(|_| {
        TestCaseError::fail(format!(
            "{name}: the reader panicked on {} bytes starting {head:02x?}",
            bytes.len()
        ))
    })?;
    prop_assert!(
        took < TIME_BOUND,
        "{name}: {took:?} on {} bytes starting {head:02x?}",
        bytes.len()
    );
    if let Err(e) = r {
        prop_assert!(
            e.starts_with(&format!("{name}: ")) || name.ends_with(".npy"),
            "{e:?}"
        );
        prop_assert!(!e.trim().is_empty(), "an empty message");
        prop_assert!(
            !e.contains(['\n', '\r', '\x1b']),
            "not one clean line: {e:?}"
        );
    }
    Ok(())
}

fn decode_mat(bytes: &[u8]) -> Result<Vec<(String, MatValue)>, String> {
    mat::decode(Path::new("fuzz.mat"), bytes).map_err(|e| e.to_string())
}

fn decode_npz(bytes: &[u8]) -> Result<Vec<(String, NpyArray)>, String> {
    npz::decode(Path::new("fuzz.npz"), bytes).map_err(|e| e.to_string())
}

fn parse_npy(bytes: &[u8]) -> Result<NpyArray, String> {
    npz::parse_npy(bytes).map_err(|e| e.to_string())
}

fn fixtures(ext: &str) -> Vec<Vec<u8>> {
    let mut files: Vec<_> = std::fs::read_dir(repo().join("tests/fixtures"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == ext))
        .collect();
    files.sort();
    assert!(!files.is_empty(), "no .{ext} fixtures");
    files.iter().map(|p| std::fs::read(p).unwrap()).collect()
}

/// Variables as eyeshell exports them, with awkward values.
fn our_vars() -> Vec<(String, MatValue)> {
    vec![
        (
            "sol".into(),
            MatValue::Struct(vec![
                ("x".into(), MatValue::row(&[0.0, 0.5, 1.0])),
                (
                    "y".into(),
                    MatValue::from_rows(&[vec![1.0, 2.0, 3.0], vec![f64::NAN, -0.0, 1e300]]),
                ),
                (
                    "stats".into(),
                    MatValue::Struct(vec![("n".into(), MatValue::scalar(3.0))]),
                ),
            ]),
        ),
        ("time".into(), MatValue::scalar(0.25)),
        ("empty".into(), MatValue::row(&[])),
    ]
}

fn mat_seeds() -> Vec<Vec<u8>> {
    let mut seeds = fixtures("mat");
    seeds.push(mat::encode(&our_vars(), false).unwrap());
    seeds.push(mat::encode(&our_vars(), true).unwrap());
    seeds
}

fn our_arrays() -> Vec<(String, NpyArray)> {
    vec![
        ("x".into(), NpyArray::vector(&[0.0, 0.5, 1.0])),
        (
            "y".into(),
            NpyArray::from_rows(&[vec![1.0, 2.0, 3.0], vec![4.0, 5.0, 6.0]]),
        ),
        ("time".into(), NpyArray::scalar(0.25)),
    ]
}

/// The .npy members of a .npz file.
fn members(npz_bytes: &[u8]) -> Vec<Vec<u8>> {
    let mut z = zip::ZipArchive::new(std::io::Cursor::new(npz_bytes)).unwrap();
    (0..z.len())
        .map(|i| {
            let mut v = Vec::new();
            z.by_index(i).unwrap().read_to_end(&mut v).unwrap();
            v
        })
        .collect()
}

fn npy_seeds() -> Vec<Vec<u8>> {
    let mut seeds = fixtures("npy");
    for f in fixtures("npz") {
        seeds.extend(members(&f));
    }
    seeds.extend(our_arrays().iter().map(|(_, a)| npz::npy_bytes(a)));
    seeds
}

fn npz_seeds() -> Vec<Vec<u8>> {
    let mut seeds = fixtures("npz");
    seeds.push(npz::encode(&our_arrays()).unwrap());
    seeds
}

/// Length-like values written over a field.
const HUGE: [u32; 10] = [
    0xffff_ffff,
    0xffff_fff8,
    0x8000_0000,
    0x7fff_ffff,
    0x4000_0000,
    0x0100_0000,
    0x0001_0000,
    0,
    1,
    8,
];

#[derive(Clone, Debug)]
pub(crate) enum Mutation {
    Flip(usize, u8),
    Set(usize, u8),
    /// A 32-bit length-like value (little- or big-endian), at a 4-aligned offset or not.
    Huge(usize, usize, bool, bool),
    Truncate(usize),
    Insert(usize, Vec<u8>),
    Remove(usize, usize),
}

pub(crate) fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        3 => (any::<usize>(), 0u8..8).prop_map(|(p, b)| Mutation::Flip(p, b)),
        2 => (any::<usize>(), any::<u8>()).prop_map(|(p, v)| Mutation::Set(p, v)),
        4 => (any::<usize>(), 0..HUGE.len(), any::<bool>(), any::<bool>())
            .prop_map(|(p, k, big, aligned)| Mutation::Huge(p, k, big, aligned)),
        1 => any::<usize>().prop_map(Mutation::Truncate),
        1 => (any::<usize>(), proptest::collection::vec(any::<u8>(), 1..16))
            .prop_map(|(p, v)| Mutation::Insert(p, v)),
        1 => (any::<usize>(), 1usize..64).prop_map(|(p, n)| Mutation::Remove(p, n)),
    ]
}

pub(crate) fn mutate(mut b: Vec<u8>, ms: &[Mutation]) -> Vec<u8> {
    for m in ms {
        let len = b.len();
        if len == 0 {
            break;
        }
        match m {
            Mutation::Flip(p, bit) => b[p % len] ^= 1 << bit,
            Mutation::Set(p, v) => b[p % len] = *v,
            Mutation::Huge(p, k, big, aligned) => {
                let mut at = p % len;
                if *aligned {
                    at -= at % 4;
                }
                let v = if *big {
                    HUGE[*k].to_be_bytes()
                } else {
                    HUGE[*k].to_le_bytes()
                };
                for (i, x) in v.iter().enumerate() {
                    if let Some(y) = b.get_mut(at + i) {
                        *y = *x;
                    }
                }
            }
            Mutation::Truncate(p) => b.truncate(p % len),
            Mutation::Insert(p, v) => {
                let at = p % (len + 1);
                b.splice(at..at, v.iter().copied());
            }
            Mutation::Remove(p, n) => {
                let at = p % len;
                b.drain(at..(at + n).min(len));
            }
        }
    }
    b
}

fn zlib(bytes: &[u8]) -> Vec<u8> {
    let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::fast());
    z.write_all(bytes).unwrap();
    z.finish().unwrap()
}

/// A little-endian .mat file with every miCOMPRESSED variable's inflated bytes mutated and
/// compressed again (the tags outside stay consistent).
fn mutate_inside_mat(file: &[u8], ms: &[Mutation]) -> Vec<u8> {
    let mut out = file[..128].to_vec();
    let mut pos = 128;
    while pos + 8 <= file.len() {
        let ty = u32::from_le_bytes(file[pos..pos + 4].try_into().unwrap());
        let n = u32::from_le_bytes(file[pos + 4..pos + 8].try_into().unwrap()) as usize;
        let body = &file[pos + 8..pos + 8 + n];
        if ty == 15 {
            let mut inner = Vec::new();
            flate2::read::ZlibDecoder::new(body)
                .read_to_end(&mut inner)
                .unwrap();
            let z = zlib(&mutate(inner, ms));
            out.extend_from_slice(&15u32.to_le_bytes());
            out.extend_from_slice(&(z.len() as u32).to_le_bytes());
            out.extend(z);
        } else {
            out.extend_from_slice(&file[pos..pos + 8 + n]);
        }
        pos += 8 + n;
    }
    out
}

/// A .npz of the given .npy members, stored or deflated.
fn zip_of(members: &[Vec<u8>], deflate: bool) -> Vec<u8> {
    let mut z = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let method = if deflate {
        zip::CompressionMethod::Deflated
    } else {
        zip::CompressionMethod::Stored
    };
    let options = zip::write::SimpleFileOptions::default().compression_method(method);
    for (k, m) in members.iter().enumerate() {
        z.start_file(format!("a{k}.npy"), options).unwrap();
        z.write_all(m).unwrap();
    }
    z.finish().unwrap().into_inner()
}

pub(crate) fn mutations() -> impl Strategy<Value = Vec<Mutation>> {
    proptest::collection::vec(mutation(), 1..6)
}

#[test]
fn mat_random_bytes() {
    let header = mat::header();
    let strategy = (
        any::<bool>(),
        any::<bool>(),
        proptest::collection::vec(any::<u8>(), 0..600),
    );
    runner(3000, 1)
        .run(&strategy, |(with_header, big, tail)| {
            let mut b = Vec::new();
            if with_header {
                let mut header = header.clone();
                header[126..128].copy_from_slice(if big { b"MI" } else { b"IM" });
                header[124..126].copy_from_slice(if big { &[1, 0] } else { &[0, 1] });
                b.extend_from_slice(&header);
            }
            b.extend(tail);
            check("fuzz.mat", &b, decode_mat)
        })
        .unwrap();
}

#[test]
fn mat_mutated_files() {
    let seeds = mat_seeds();
    let strategy = (0..seeds.len(), mutations());
    runner(4000, 2)
        .run(&strategy, |(k, ms)| {
            check("fuzz.mat", &mutate(seeds[k].clone(), &ms), decode_mat)
        })
        .unwrap();
    // Inside the compression: the compressed seeds only.
    let zipped: Vec<Vec<u8>> = seeds
        .into_iter()
        .filter(|s| s.get(128..132) == Some(&15u32.to_le_bytes()[..]))
        .collect();
    assert!(zipped.len() >= 4, "{} compressed seeds", zipped.len());
    let strategy = (0..zipped.len(), mutations());
    runner(3000, 3)
        .run(&strategy, |(k, ms)| {
            check("fuzz.mat", &mutate_inside_mat(&zipped[k], &ms), decode_mat)
        })
        .unwrap();
}

/// Header dicts as NumPy writes them, with hostile values.
fn npy_header() -> impl Strategy<Value = Vec<u8>> {
    let descr = prop_oneof![
        Just("<f8".to_string()),
        Just(">f8".to_string()),
        Just("<f4".to_string()),
        Just("|u1".to_string()),
        Just("|b1".to_string()),
        Just(">i8".to_string()),
        Just("<c16".to_string()),
        "[<>|=]?[a-zA-Z?]{0,2}[0-9]{0,3}",
    ];
    let dim = prop_oneof![
        3 => 0u64..20,
        1 => any::<u64>(),
        1 => Just(u64::MAX),
        1 => Just(1u64 << 61),
    ];
    (
        descr,
        any::<bool>(),
        proptest::collection::vec(dim, 0..5),
        1u8..4,
        0usize..600,
        any::<u8>(),
    )
        .prop_map(|(descr, fortran, shape, version, data_len, fill)| {
            let shape: Vec<String> = shape.iter().map(u64::to_string).collect();
            let shape = match shape.len() {
                1 => format!("({},)", shape[0]),
                _ => format!("({})", shape.join(", ")),
            };
            let fortran = if fortran { "True" } else { "False" };
            let header =
                format!("{{'descr': '{descr}', 'fortran_order': {fortran}, 'shape': {shape}, }}\n");
            let mut b = b"\x93NUMPY".to_vec();
            b.extend_from_slice(&[version, 0]);
            if version == 1 {
                b.extend_from_slice(&(header.len() as u16).to_le_bytes());
            } else {
                b.extend_from_slice(&(header.len() as u32).to_le_bytes());
            }
            b.extend_from_slice(header.as_bytes());
            b.resize(b.len() + data_len, fill);
            b
        })
}

#[test]
fn npy_random_and_mutated() {
    runner(3000, 4)
        .run(&npy_header(), |b| check("fuzz.npy", &b, parse_npy))
        .unwrap();
    let strategy = (
        any::<bool>(),
        proptest::collection::vec(any::<u8>(), 0..300),
    );
    runner(1000, 5)
        .run(&strategy, |(magic, tail)| {
            let mut b = if magic { b"\x93NUMPY".to_vec() } else { vec![] };
            b.extend(tail);
            check("fuzz.npy", &b, parse_npy)
        })
        .unwrap();
    let seeds = npy_seeds();
    let strategy = (0..seeds.len(), mutations());
    runner(4000, 6)
        .run(&strategy, |(k, ms)| {
            check("fuzz.npy", &mutate(seeds[k].clone(), &ms), parse_npy)
        })
        .unwrap();
}

#[test]
fn npz_random_and_mutated() {
    let strategy = (
        any::<bool>(),
        proptest::collection::vec(any::<u8>(), 0..400),
    );
    runner(1000, 7)
        .run(&strategy, |(magic, tail)| {
            let mut b = if magic {
                b"PK\x03\x04".to_vec()
            } else {
                vec![]
            };
            b.extend(tail);
            check("fuzz.npz", &b, decode_npz)
        })
        .unwrap();
    // The archive itself mutated: headers, sizes, offsets, the central directory.
    let seeds = npz_seeds();
    let strategy = (0..seeds.len(), mutations());
    runner(4000, 8)
        .run(&strategy, |(k, ms)| {
            check("fuzz.npz", &mutate(seeds[k].clone(), &ms), decode_npz)
        })
        .unwrap();
    // Mutated members in a well-formed archive (stored and deflated).
    let members = npy_seeds();
    let strategy = (
        proptest::collection::vec((0..members.len(), mutations()), 1..4),
        any::<bool>(),
    );
    runner(2000, 9)
        .run(&strategy, |(picks, deflate)| {
            let ms: Vec<Vec<u8>> = picks
                .iter()
                .map(|(k, m)| mutate(members[*k].clone(), m))
                .collect();
            check("fuzz.npz", &zip_of(&ms, deflate), decode_npz)
        })
        .unwrap();
}
