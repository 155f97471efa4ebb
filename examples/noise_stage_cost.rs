//! Issue 20: the noise stage alone, for profiling (`perf stat`, callgrind): adds one ISO of
//! noise to a clean raw `REPS` times with the Gaussian model (the embedded phone table) or
//! a physics model file, and prints the median wall time.
//!
//! Run: `cargo run --release --example noise_stage_cost -- CLEAN.dng gauss|MODEL.json ISO REPS`
//! (CLEAN.dng: e.g. the `*_clean.dng` that `synth` writes).
use day2night::dng::read_dng;
use day2night::noise::{apply_noise, apply_physics_noise_image, NoiseModel};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let a: Vec<String> = std::env::args().collect();
    if a.len() != 5 {
        return Err("usage: noise_stage_cost CLEAN.dng gauss|MODEL.json ISO REPS".into());
    }
    let clean = read_dng(std::path::Path::new(&a[1]))?;
    let iso: u32 = a[3].parse()?;
    let reps: usize = a[4].parse()?;
    let mut times = vec![];
    if a[2] == "gauss" {
        let m = day2night::synth::dictionaries::embedded::noise_model();
        let p = m.at(iso)?.params;
        for _ in 0..reps {
            let t = Instant::now();
            std::hint::black_box(apply_noise(&clean, &p, 1)?);
            times.push(t.elapsed().as_secs_f64());
        }
    } else {
        let m = NoiseModel::from_file(std::path::Path::new(&a[2]))?;
        let p = m.physics.ok_or("not a physics model")?.at(iso)?.params;
        for _ in 0..reps {
            let t = Instant::now();
            std::hint::black_box(apply_physics_noise_image(&clean, &p, 1)?);
            times.push(t.elapsed().as_secs_f64());
        }
    }
    times.sort_by(f64::total_cmp);
    println!("median {:.4} s of {reps}", times[reps / 2]);
    Ok(())
}
