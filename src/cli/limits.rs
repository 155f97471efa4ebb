//! The CLI's resource limits: `--max-pixels`, else `D2N_MAX_PIXELS`, for the pixel limit;
//! `D2N_OPCODE_BUDGET` for the opcode work budget (docs/limits.md). The environment is read
//! here, never by the library, and the result is installed for the whole run.

use day2night::limits::{Limits, MAX_PIXELS_ENV, OPCODE_BUDGET_ENV};

/// The limits of this run, or the message of a bad variable (a usage error).
pub fn from_args_and_env(max_pixels: Option<u64>) -> Result<Limits, String> {
    let var = |name: &str| std::env::var(name).ok();
    let mut limits = match (max_pixels, var(MAX_PIXELS_ENV)) {
        (Some(n), _) => Limits::with_max_pixels(n).map_err(|e| e.to_string())?,
        (None, Some(v)) => Limits::parse_pixels(&v)
            .and_then(Limits::with_max_pixels)
            .map_err(|e| format!("{MAX_PIXELS_ENV}: {e}"))?,
        (None, None) => Limits::default(),
    };
    if let Some(v) = var(OPCODE_BUDGET_ENV) {
        limits = Limits::parse_opcode_budget(&v)
            .and_then(|b| limits.with_opcode_budget(b))
            .map_err(|e| format!("{OPCODE_BUDGET_ENV}: {e}"))?;
    }
    Ok(limits)
}
