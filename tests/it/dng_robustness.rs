//! Deterministic mutation test (runs in plain `cargo test`, no nightly needed): valid small
//! DNGs of every layout, with bytes flipped, overwritten with extreme values and truncated,
//! thousands of times. The reader must return Ok or an error, never panic or hang.
use crate::dngbuild;

use day2night::dng::read::{inspect_bytes, read_dng_bytes};
use day2night::tiff::value::Value;
use dngbuild::{Builder, Pixels};

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

fn seeds() -> Vec<Vec<u8>> {
    let mut v = Vec::new();
    let base = Builder::new(24, 16, 12)
        .set(50829, Value::Long(vec![0, 0, 16, 24]))
        .set(51041, Value::Double(vec![1e-4, 1e-6]))
        .set(50712, Value::Short((0..64).collect()));
    v.push(base.build());
    let mut b = base.clone();
    b.big_endian = true;
    b.bits = 14;
    b.layout = Pixels::Tiles { w: 16, h: 16 };
    b.pixels.iter_mut().for_each(|p| *p &= 0x3FFF);
    v.push(b.build());
    let mut b = Builder::new(32, 16, 14);
    b.layout = Pixels::LjpegTiles {
        w: 16,
        h: 16,
        two_components: true,
    };
    b.raw_in_sub = true;
    v.push(b.build());
    let mut b = Builder::new(24, 8, 16);
    b.layout = Pixels::LjpegStrips { rows: 4 };
    b.exif = vec![(34855, Value::Short(vec![100]))];
    v.push(b.build());
    v
}

#[test]
fn mutated_dngs_never_panic() {
    let mut rng = Rng(0x9E3779B97F4A7C15);
    let iterations = std::env::var("D2N_MUTATIONS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(4000usize);
    let seeds = seeds();
    for s in &seeds {
        read_dng_bytes(s).expect("seed files are valid");
    }
    let mut errors = 0usize;
    for it in 0..iterations {
        for seed in &seeds {
            let mut m = seed.clone();
            match it % 4 {
                0 => {
                    for _ in 0..1 + rng.below(4) {
                        let i = rng.below(m.len());
                        m[i] ^= 1 << rng.below(8);
                    }
                }
                1 => {
                    // Extreme values in likely-numeric places.
                    let i = rng.below(m.len().saturating_sub(4));
                    let v: [u8; 4] = match rng.below(4) {
                        0 => [0xFF; 4],
                        1 => [0; 4],
                        2 => [0x7F, 0xFF, 0xFF, 0xFF],
                        _ => [0, 0, 0, 0x80],
                    };
                    m[i..i + 4].copy_from_slice(&v);
                }
                2 => m.truncate(rng.below(m.len())),
                _ => {
                    // Mutate the IFD region (the builder writes IFDs after the pixels).
                    let start = m.len() * 2 / 3;
                    for _ in 0..1 + rng.below(6) {
                        let i = start + rng.below(m.len() - start);
                        m[i] = rng.next() as u8;
                    }
                }
            }
            if read_dng_bytes(&m).is_err() {
                errors += 1;
            }
            let _ = inspect_bytes(&m);
        }
    }
    eprintln!(
        "{} mutants, {errors} refused with an error, the rest read",
        iterations * seeds.len()
    );
    assert!(errors > 0);
}

/// `D2N_WRITE_SEEDS=DIR cargo test --test it dng_robustness::write_seeds -- --ignored` writes
/// the valid seed DNGs into DIR (a starting corpus for `cargo fuzz run read_dng`). A tool, not
/// a check: ignored by default.
#[test]
#[ignore = "tool: writes the fuzz seed corpus into $D2N_WRITE_SEEDS"]
fn write_seeds() {
    let dir = std::env::var_os("D2N_WRITE_SEEDS")
        .expect("D2N_WRITE_SEEDS=DIR names the folder for the seed corpus");
    let dir = std::path::Path::new(&dir);
    for (i, s) in seeds().iter().enumerate() {
        std::fs::write(dir.join(format!("seed{i}.dng")), s).unwrap();
    }
    // Bare lossless JPEG streams (for the `ljpeg` target).
    for (i, (nc, p)) in [(1usize, 12u8), (2, 14), (3, 16), (4, 8)]
        .into_iter()
        .enumerate()
    {
        let px: Vec<u16> = (0..16 * 8 * nc)
            .map(|k| (k * 37 % (1 << p)) as u16)
            .collect();
        std::fs::write(
            dir.join(format!("seed{i}.ljpeg")),
            dngbuild::lj92(16, 8, nc, p, &px),
        )
        .unwrap();
    }
}
