//! Tile a DNG's CFA plane N x N into a larger DNG (issue 20 point 2: the ~109 MP input is the
//! 12 MP benchmark image of `make_bench_input` tiled 3 x 3, 12096 x 9072).
//!
//! ```text
//! cargo run --release --example make_bench_input -- day.dng
//! cargo run --release --example make_tiled_input -- day.dng day109.dng [N]
//! ```
//! Width and height must be even (the CFA phase is kept); the default crop keeps the
//! source's margins around the whole mosaic. Inputs with an active area or opcodes are
//! refused (their geometry would not tile).

use day2night::dng::read::read_dng;
use day2night::dng::write::{encode_dng, WriteOptions};
use day2night::raw::RawImage;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let usage = "usage: make_tiled_input IN.dng OUT.dng [N]";
    let input = args.next().ok_or(usage)?;
    let out = args.next().ok_or(usage)?;
    let n: usize = args.next().map(|s| s.parse()).transpose()?.unwrap_or(3);
    if n == 0 {
        return Err("N must be at least 1".into());
    }
    let src = read_dng(std::path::Path::new(&input))?;
    let (w, h) = (src.width, src.height);
    if w % 2 != 0 || h % 2 != 0 {
        return Err(format!("{input}: {w}x{h} is not even: tiling would shift the CFA").into());
    }
    if src.meta.active_area.is_some() || src.meta.opcode_lists.iter().any(Option::is_some) {
        return Err(format!("{input}: active area or opcodes present: not tiled").into());
    }
    let (tw, th) = (w * n, h * n);
    let mut data = Vec::with_capacity(tw * th);
    for y in 0..th {
        let row = &src.data[(y % h) * w..(y % h + 1) * w];
        for _ in 0..n {
            data.extend_from_slice(row);
        }
    }
    let mut meta = src.meta;
    if let (Some(o), Some(_)) = (meta.default_crop_origin, meta.default_crop_size) {
        meta.default_crop_size = Some([tw as f64 - 2.0 * o[0], th as f64 - 2.0 * o[1]]);
    }
    let img = RawImage {
        width: tw,
        height: th,
        data,
        meta,
    };
    img.validate()?;
    std::fs::write(&out, encode_dng(&img, &WriteOptions::default())?)?;
    Ok(())
}
