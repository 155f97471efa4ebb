//! The statistics of the Gaussian noise streams (src/noise/stream.rs, docs/noise.md "Noise
//! streams"): stream 2 (xoshiro256++ per row, the default) must give the same noise as
//! stream 1 (ChaCha8 per row, the stream before it), which these tests hold both to.
//!
//! Every bound is five standard errors of the statistic under the hypothesis (a false
//! failure about once in 1.7 million per bound), and every draw is seeded, so each test
//! gives the same answer on every run; the sample sizes are stated per test.

use day2night::noise::apply::{apply_noise_crop_stream, apply_noise_stream};
use day2night::noise::stream::{fill_normals_v2, row_rng_v1, stream_key};
use day2night::noise::{NoiseParams, NoiseStream};
use day2night::raw::crop::Crop;
use day2night::raw::meta::RawMeta;
use day2night::raw::{Bayer, RawImage};
use rand_distr::{Distribution, StandardNormal};

const STREAMS: [NoiseStream; 2] = [NoiseStream::V1, NoiseStream::V2];

/// `n` standard normals of `stream`: rows of `w` from row 0 of `seed`'s key.
fn normals(stream: NoiseStream, seed: u64, rows: usize, w: usize) -> Vec<Vec<f64>> {
    let key = stream_key(stream, false, seed, &[]);
    (0..rows)
        .map(|r| match stream {
            NoiseStream::V1 => {
                let mut rng = row_rng_v1(&key, r);
                (0..w).map(|_| StandardNormal.sample(&mut rng)).collect()
            }
            NoiseStream::V2 => {
                let mut v = vec![0.0; w];
                fill_normals_v2(&key, r, &mut v);
                v
            }
        })
        .collect()
}

/// The standard normal CDF, from `erfc` (W. J. Cody's rational approximations through
/// Numerical Recipes' `erfcc`: absolute error below 1.2e-7, far under the KS bound's 1e-3).
fn phi(x: f64) -> f64 {
    let z = x.abs() / std::f64::consts::SQRT_2;
    let t = 1.0 / (1.0 + 0.5 * z);
    let poly = -z * z - 1.265_512_23
        + t * (1.000_023_68
            + t * (0.374_091_96
                + t * (0.096_784_18
                    + t * (-0.186_288_06
                        + t * (0.278_868_07
                            + t * (-1.135_203_98
                                + t * (1.488_515_87 + t * (-0.822_152_23 + t * 0.170_872_77))))))));
    let erfc = t * poly.exp();
    if x >= 0.0 {
        1.0 - 0.5 * erfc
    } else {
        0.5 * erfc
    }
}

/// Pearson correlation of two equally long series.
fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        let (dx, dy) = (x - ma, y - mb);
        sab += dx * dy;
        saa += dx * dx;
        sbb += dy * dy;
    }
    sab / (saa * sbb).sqrt()
}

/// Normality of 2^21 normals per stream (512 rows of 4096): the Kolmogorov-Smirnov
/// statistic `sqrt(n) * D` under 1.95 (the 0.1 % critical value of the Kolmogorov
/// distribution, 1.949), mean, variance, skewness and excess kurtosis within five standard
/// errors (`1`, `sqrt(2)`, `sqrt(6)`, `sqrt(24)` over `sqrt(n)`), and the two tails
/// (`|z| > 3`: p = 2.6998e-3; `|z| > 4`: p = 6.3342e-5) within five binomial standard
/// errors of their expected counts.
#[test]
fn both_streams_draw_standard_normals() {
    for stream in STREAMS {
        let mut x: Vec<f64> = normals(stream, 11, 512, 4096).concat();
        let n = x.len() as f64;
        let mean = x.iter().sum::<f64>() / n;
        let m = |k: i32| x.iter().map(|v| (v - mean).powi(k)).sum::<f64>() / n;
        let (m2, m3, m4) = (m(2), m(3), m(4));
        let (skew, kurt) = (m3 / m2.powf(1.5), m4 / (m2 * m2) - 3.0);
        let se = |k: f64| 5.0 * (k / n).sqrt();
        assert!(mean.abs() < se(1.0), "{stream:?} mean {mean}");
        assert!((m2 - 1.0).abs() < se(2.0), "{stream:?} variance {m2}");
        assert!(skew.abs() < se(6.0), "{stream:?} skewness {skew}");
        assert!(kurt.abs() < se(24.0), "{stream:?} excess kurtosis {kurt}");
        for (z, p) in [(3.0, 2.6998e-3), (4.0, 6.3342e-5)] {
            let count = x.iter().filter(|v| v.abs() > z).count() as f64;
            let (want, sd) = (n * p, (n * p * (1.0 - p)).sqrt());
            assert!(
                (count - want).abs() < 5.0 * sd,
                "{stream:?}: {count} beyond {z} sigma, expected {want:.0}"
            );
        }
        x.sort_by(f64::total_cmp);
        let d = x
            .iter()
            .enumerate()
            .map(|(i, &v)| {
                let f = phi(v);
                (f - i as f64 / n).max((i + 1) as f64 / n - f)
            })
            .fold(0.0f64, f64::max);
        assert!(
            d * n.sqrt() < 1.95,
            "{stream:?}: KS sqrt(n) D = {}",
            d * n.sqrt()
        );
    }
}

/// Independence: the correlation of every pair below within five standard errors of 0
/// (`5 / sqrt(n)`): neighbouring samples of a row (lag 1 and 2, 2^21 pairs), the same
/// column of neighbouring rows (2^21 pairs), the first sample of neighbouring rows (the
/// seeding: 2^17 rows), the same sites under neighbouring seeds (variants and ISOs draw
/// their own seeds; 2^21 pairs) and a crop's stream against the whole image's.
#[test]
fn rows_seeds_and_crops_draw_independent_normals() {
    let bound = |n: usize| 5.0 / (n as f64).sqrt();
    for stream in STREAMS {
        let a = normals(stream, 21, 512, 4096);
        let b = normals(stream, 22, 512, 4096);
        for lag in [1, 2] {
            let (x, y): (Vec<f64>, Vec<f64>) = a
                .iter()
                .flat_map(|r| r.iter().zip(&r[lag..]).map(|(&p, &q)| (p, q)))
                .unzip();
            let c = correlation(&x, &y);
            assert!(c.abs() < bound(x.len()), "{stream:?} lag {lag}: {c}");
        }
        let rows_x = a[..511].concat();
        let rows_y = a[1..].concat();
        let c = correlation(&rows_x, &rows_y);
        assert!(c.abs() < bound(rows_x.len()), "{stream:?} rows: {c}");
        let c = correlation(&a.concat(), &b.concat());
        assert!(c.abs() < bound(512 * 4096), "{stream:?} seeds 21/22: {c}");
        let first: Vec<f64> = normals(stream, 23, 1 << 17, 1)
            .into_iter()
            .map(|r| r[0])
            .collect();
        let c = correlation(&first[1..], &first[..first.len() - 1]);
        assert!(
            c.abs() < bound(first.len()),
            "{stream:?} first samples: {c}"
        );
        let key = stream_key(stream, true, 21, &[0, 0, 512, 4096]);
        assert_ne!(key, stream_key(stream, false, 21, &[]));
    }
    // the two streams are not the same numbers
    let c = correlation(
        &normals(NoiseStream::V1, 21, 64, 4096).concat(),
        &normals(NoiseStream::V2, 21, 64, 4096).concat(),
    );
    assert!(c.abs() < bound(64 * 4096), "v1 against v2: {c}");
}

/// A flat 10-bit RGGB frame (black 64, white 1023), `value` everywhere, `w x h`.
fn flat(w: usize, h: usize, value: u16) -> RawImage {
    RawImage {
        width: w,
        height: h,
        data: vec![value; w * h],
        meta: RawMeta::new_bayer(Bayer::RGGB, 10, 64.0, 1023.0),
    }
}

/// The noise model's variance per 2x2 position and ISO, against the noisy samples: the
/// embedded table (the paper phone's, docs/noise.md) at ISO 800, 1600 and 3200 on flat
/// 10-bit frames at three levels (y = 0.05, 0.25, 0.6 of the range), 512 x 512, so 65,536
/// samples per channel. Per channel, the mean of `noisy - clean` within five standard errors
/// of 0 (`5 sigma / sqrt(n)`), and the variance within five standard errors of the model's
/// plus the rounding's 1/12 DN^2 (Sheppard's correction; `se = sqrt(2 / n)` relative, plus
/// the error of the correction itself, under 2 % of 1/12 at sigma > 2 DN); both streams.
/// No sample is clipped at these levels (5 sigma stays inside [0, white]).
#[test]
fn noisy_samples_follow_the_model_per_iso_and_channel() {
    let model = day2night::synth::dictionaries::embedded::noise_model();
    let (w, h) = (512usize, 512usize);
    let scale: f64 = 1023.0 - 64.0;
    for iso in [800u32, 1600, 3200] {
        let params = model.at(iso).unwrap().params;
        for y in [0.05, 0.25, 0.6] {
            let value = (64.0 + y * scale).round() as u16;
            let clean = flat(w, h, value);
            let yq = (value as f64 - 64.0) / scale;
            for stream in STREAMS {
                let out = apply_noise_stream(&clean, &params, 5, false, stream).unwrap();
                for pos in 0..4 {
                    let d: Vec<f64> = (0..h)
                        .filter(|r| (r & 1) == (pos >> 1))
                        .flat_map(|r| {
                            (0..w)
                                .filter(move |c| (c & 1) == (pos & 1))
                                .map(move |c| (r, c))
                        })
                        .map(|(r, c)| out.data[r * w + c] as f64 - value as f64)
                        .collect();
                    let n = d.len() as f64;
                    let var_model = params.var_norm(pos, yq) * scale * scale;
                    let sigma = var_model.sqrt();
                    assert!(
                        sigma > 2.0 && value as f64 - 5.0 * sigma > 0.0,
                        "the test's levels: sigma {sigma}"
                    );
                    assert!(
                        value as f64 + 5.0 * sigma < 1023.0,
                        "the test's levels: sigma {sigma}"
                    );
                    let mean = d.iter().sum::<f64>() / n;
                    let var = d.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
                    let want = var_model + 1.0 / 12.0;
                    let what = format!("{stream:?} ISO {iso} y {y} position {pos}");
                    assert!(mean.abs() < 5.0 * sigma / n.sqrt(), "{what}: mean {mean}");
                    let tol = 5.0 * (2.0 / n).sqrt() * want + 0.02 / 12.0;
                    assert!(
                        (var - want).abs() < tol,
                        "{what}: variance {var}, model {want}"
                    );
                }
            }
        }
    }
}

/// The same model on a crop (the training patches' and burst frames' path): the noise of
/// a 256 x 256 crop at ISO 3200, per channel (16,384 samples), within the same bounds as
/// the whole image's, both streams.
#[test]
fn crop_noise_follows_the_model() {
    let model = day2night::synth::dictionaries::embedded::noise_model();
    let params: NoiseParams = model.at(3200).unwrap().params;
    let frame = flat(600, 400, 300);
    let crop = Crop {
        top: 10,
        left: 20,
        height: 256,
        width: 256,
    };
    let scale: f64 = 1023.0 - 64.0;
    for stream in STREAMS {
        let mut plane = vec![300u16; 256 * 256];
        apply_noise_crop_stream(&frame, &crop, &mut plane, &params, (9, false), stream).unwrap();
        for pos in 0..4 {
            let d: Vec<f64> = plane
                .iter()
                .enumerate()
                .filter(|(i, _)| {
                    ((i / 256 + 10) & 1) == pos >> 1 && ((i % 256 + 20) & 1) == pos & 1
                })
                .map(|(_, &v)| v as f64 - 300.0)
                .collect();
            let n = d.len() as f64;
            let want = params.var_norm(pos, (300.0 - 64.0) / scale) * scale * scale + 1.0 / 12.0;
            let mean = d.iter().sum::<f64>() / n;
            let var = d.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
            assert!(
                mean.abs() < 5.0 * want.sqrt() / n.sqrt(),
                "{stream:?} {pos}: mean {mean}"
            );
            let tol = 5.0 * (2.0 / n).sqrt() * want + 0.02 / 12.0;
            assert!(
                (var - want).abs() < tol,
                "{stream:?} {pos}: {var} vs {want}"
            );
        }
    }
}
