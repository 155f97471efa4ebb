//! Fresh-synthesis training items (issue 31, `day2night.train.FreshPatches`) on one thread:
//! per item, the plan of a new variant and the 64 network-input and target patches of a
//! 512 x 512 crop (`synth::patches::crop_pair` + `cut_patches`, what
//! `day2night._native.fresh_pair` runs). Then the same items stage by stage (clean pass
//! over the crop and the demosaicer's margin, one ISO's noise, the target render, the
//! release input, the 8-bit encoding, the cutting). Prints the median time of each over
//! the items, so a profiler (`perf record`) or the printed split says where the time goes.
//!
//! Run: `D2N_FRESH_DNG=day.dng cargo bench --bench fresh` (a 12 MP input: `cargo run
//! --release --example make_bench_input -- day.dng`; `D2N_FRESH_ITEMS`, default 200).
//! Python-side numbers (patches/s next to the trainer): benches/train_bench.py.
use day2night::encode::png::encode_u8;
use day2night::isp::release_input::{
    release_codes, release_table, CfaPlane, FrameFacts, RELEASE_GAMMA,
};
use day2night::isp::render::{render_crop, CropSamples, RenderOptions};
use day2night::isp::render_crop::CROP_MARGIN;
use day2night::isp::tone::DisplayTone;
use day2night::noise::apply::apply_noise_crop_with;
use day2night::raw::crop::Crop;
use day2night::synth::config::JobConfig;
use day2night::synth::day_input::DayInput;
use day2night::synth::job::Target;
use day2night::synth::patches::{crop_pair, cut_patches, PairInput};
use day2night::synth::relight::run_clean_crop;
use std::path::PathBuf;
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let Some(path) = std::env::var_os("D2N_FRESH_DNG").map(PathBuf::from) else {
        eprintln!("fresh bench: set D2N_FRESH_DNG to a day DNG (make_bench_input makes one)");
        return;
    };
    let items: usize = std::env::var("D2N_FRESH_ITEMS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(200);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a one-thread pool");
    let day = DayInput::read(&path).expect("the day DNG");
    let name = path
        .file_name()
        .map_or("day.dng".into(), |n| n.to_string_lossy().into_owned());
    let isos = [1600u32, 3200];
    let jobs: Vec<_> = isos
        .iter()
        .map(|&iso| {
            let mut cfg = JobConfig::default();
            cfg.options.isos = vec![iso];
            cfg.target = Target::Exr;
            cfg.build().expect("the job")
        })
        .collect();
    let a = day.raw.active_area();
    let (aw, ah) = (a.width(), a.height());
    let side = 512usize;
    let names = [
        "plan",
        "crop_pair + cut (the item)",
        "  clean pass (crop + margin)",
        "  noise (one ISO)",
        "  target render",
        "  release input codes",
        "  8-bit target",
        "  cut + code table",
    ];
    let mut t: Vec<Vec<f64>> = vec![Vec::new(); names.len()];
    let table = release_table(Some(RELEASE_GAMMA));
    pool.install(|| {
        // the image's noise estimate, made once per input (as the Python `Raw` keeps it)
        let _ = jobs[0].plan(&day, &name, 0, 0).expect("a plan");
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = |n: usize| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 33) as usize) % n
        };
        let bayer = day.raw.bayer().expect("a CFA input");
        for k in 0..items {
            let (job, iso) = (&jobs[k % isos.len()], isos[k % isos.len()]);
            let crop = Crop {
                top: 2 * next((ah - side) / 2),
                left: 2 * next((aw - side) / 2),
                height: side,
                width: side,
            };
            let mut clock = Instant::now();
            let mut lap = |i: usize, t: &mut Vec<Vec<f64>>| {
                let now = Instant::now();
                t[i].push((now - clock).as_secs_f64() * 1e3);
                clock = now;
            };
            let plan = job.plan(&day, &name, 0, k as u32).expect("a plan").plan;
            // the whole-frame mean of the dimming, from the input's memo (as the Python
            // `Raw` keeps it)
            let plan = day.with_frame_mean(plan).expect("the frame mean");
            lap(0, &mut t);
            let pair = crop_pair(
                &day.raw,
                &plan,
                crop,
                PairInput::Noisy(iso),
                DisplayTone::Srgb,
            )
            .expect("the pair");
            let look = |c: u16| table[c as usize];
            let x = cut_patches(&pair.codes, side, side, 64, look).expect("input patches");
            let unit: Vec<f32> = (0..=255u8).map(|v| v as f32 / 255.0).collect();
            let y = cut_patches(&pair.target, side, side, 64, |v| unit[v as usize])
                .expect("target patches");
            std::hint::black_box((x, y));
            lap(1, &mut t);
            // the same item, stage by stage
            let outer = crop.grown(CROP_MARGIN, aw, ah);
            let (plane, _) = run_clean_crop(&day.raw, &plan, outer).expect("clean");
            lap(2, &mut t);
            let mut noisy = crop.cut_from(&outer, &plane);
            let np = &plan.noise[0];
            apply_noise_crop_with(&day.raw, &crop, &mut noisy, &np.params, np.seed, false)
                .expect("noise");
            lap(3, &mut t);
            let opts = RenderOptions {
                neutral: Some(plan.night_neutral),
                opcodes: plan.opcodes,
                crop: false,
                orient: false,
                ..RenderOptions::default()
            };
            let samples = CropSamples::Stored {
                outer: &outer,
                plane: &plane,
            };
            let rgb = render_crop(&day.raw, &opts, &crop, samples).expect("target");
            lap(4, &mut t);
            let codes = release_codes(
                &CfaPlane {
                    data: &noisy,
                    width: side,
                    height: side,
                    top: crop.top,
                    left: crop.left,
                },
                &FrameFacts {
                    levels: &day.raw.meta.levels,
                    bayer,
                    neutral: plan.night_neutral,
                    linearization: None,
                },
            )
            .expect("codes");
            lap(5, &mut t);
            let y8 = encode_u8(&rgb, DisplayTone::Srgb);
            lap(6, &mut t);
            let x = cut_patches(&codes, side, side, 64, look).expect("input patches");
            let y = cut_patches(&y8, side, side, 64, |v| unit[v as usize]).expect("patches");
            lap(7, &mut t);
            std::hint::black_box((x, y));
        }
    });
    println!("fresh items: {items} crops of {side}x{side}, 1 thread, medians per item");
    let med: Vec<f64> = t.into_iter().map(median).collect();
    for (n, m) in names.iter().zip(&med) {
        println!("  {n:<30} {m:8.3} ms");
    }
    let item = med[0] + med[1];
    println!(
        "  plan + item                    {item:8.3} ms = {:.0} patches of 64x64 per second",
        64.0 * 1e3 / item
    );
}
