//! The own zlib encoder (`day2night::deflate`) against the reference C zlib: varied inputs
//! (empty, tiny, long runs across blocks, all byte values, random data taking the stored
//! fallback, skewed data needing the 15-bit limit, EXR-like predicted bytes, mixtures) are
//! compressed and inflated by Python's zlib (tests/validators/deflate_zlib.py), which checks
//! the framing and Adler-32 and must reproduce every input exactly.
use crate::common;

use day2night::deflate::{compress_zlib_rle_to_vec, Encoder};

fn noise(n: usize, seed: u64) -> Vec<u8> {
    let mut s = seed | 1;
    (0..n)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 24) as u8
        })
        .collect()
}

/// Bytes around 128 with runs: like the EXR predictor's output.
fn exr_like(n: usize, seed: u64) -> Vec<u8> {
    let r = noise(n, seed);
    let mut v = Vec::with_capacity(n);
    let mut i = 0;
    while v.len() < n {
        let x = r[i % n];
        if x < 12 {
            // a run of 128 (flat high bytes)
            let len = 3 + usize::from(r[(i * 7 + 3) % n]) % 40;
            v.extend(std::iter::repeat_n(128u8, len));
        } else {
            v.push(128u8.wrapping_add((x % 16).wrapping_sub(8)));
        }
        i += 1;
    }
    v.truncate(n);
    v
}

fn cases() -> Vec<(String, Vec<u8>, Option<usize>)> {
    let mut c: Vec<(String, Vec<u8>, Option<usize>)> = vec![
        ("empty".into(), vec![], None),
        ("one".into(), vec![42], None),
        ("two".into(), vec![0, 255], None),
        ("run_258".into(), vec![9; 258], None),
        ("run_259".into(), vec![9; 259], None),
        ("run_long".into(), vec![128; 300_001], None),
        ("all_bytes".into(), (0..=255u8).collect(), None),
        (
            "all_bytes_x1000".into(),
            (0..256_000).map(|i| i as u8).collect(),
            None,
        ),
        ("random_200k".into(), noise(200_000, 7), None),
        ("exr_like_381k".into(), exr_like(381_000, 3), None),
        (
            "exr_like_small_chunks".into(),
            exr_like(100_000, 4),
            Some(1024),
        ),
    ];
    // skewed: Fibonacci-distributed symbols, shuffled
    let mut fib = vec![1usize, 1];
    while fib.len() < 24 {
        fib.push(fib[fib.len() - 1] + fib[fib.len() - 2]);
    }
    let mut v: Vec<u8> = fib
        .iter()
        .enumerate()
        .flat_map(|(s, &f)| std::iter::repeat_n(s as u8 * 3, f))
        .collect();
    let r = noise(v.len(), 11);
    let mut idx: Vec<usize> = (0..v.len()).collect();
    idx.sort_by_key(|&i| (r[i], i));
    v = idx.iter().map(|&i| v[i]).collect();
    c.push(("fibonacci".into(), v, Some(1 << 20)));
    // mixture: compressible, incompressible (stored mid-stream), runs, across small chunks
    let mut m = exr_like(5000, 5);
    m.extend(noise(3000, 6));
    m.extend(vec![77u8; 2000]);
    m.extend(exr_like(4000, 8));
    c.push(("mixed_small_chunks".into(), m.clone(), Some(1024)));
    c.push(("mixed".into(), m, None));
    for n in [1023usize, 1024, 1025, 2049] {
        c.push((format!("boundary_{n}"), exr_like(n, n as u64), Some(1024)));
    }
    c
}

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn reference_zlib_inflates_every_stream() {
    let py = common::python();
    let dir = tempfile::tempdir().unwrap();
    for (name, raw, chunk) in cases() {
        let z = match chunk {
            Some(ch) => {
                let mut out = Vec::new();
                Encoder::with_chunk(ch).compress_zlib(&raw, &mut out);
                out
            }
            None => compress_zlib_rle_to_vec(&raw),
        };
        std::fs::write(dir.path().join(format!("{name}.raw")), &raw).unwrap();
        std::fs::write(dir.path().join(format!("{name}.z")), &z).unwrap();
    }
    let out = common::run_validator(&py, "deflate_zlib.py", &[dir.path().as_os_str()]);
    let text = String::from_utf8_lossy(&out.stdout);
    let err = String::from_utf8_lossy(&out.stderr);
    eprintln!("{text}{err}");
    assert!(out.status.success(), "zlib rejected streams:\n{err}");
    assert!(text.contains("streams inflate with zlib"));
}
