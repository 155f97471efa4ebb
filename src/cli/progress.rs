//! The dataset run's progress on stderr: an indicatif bar with ETA when stderr is a
//! terminal, one plain line per input otherwise, nothing with `--quiet` (warnings still
//! print). The library calls it through [`day2night::dataset::Progress`].

use day2night::dataset::{InputDone, Progress, ProgressSink};
use std::io::IsTerminal;
use std::path::Path;

/// Bar or lines on stderr.
struct Stderr {
    bar: Option<indicatif::ProgressBar>,
    plain: bool,
}

/// The progress receiver of `day2night dataset` (`quiet`: no per-input output).
pub fn dataset_progress(quiet: bool) -> ProgressSink {
    let terminal = std::io::stderr().is_terminal();
    let bar = (!quiet && terminal).then(|| {
        let b = indicatif::ProgressBar::hidden();
        if let Ok(style) = indicatif::ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} images, ETA {eta} {msg}",
        ) {
            b.set_style(style);
        }
        b
    });
    ProgressSink::new(Stderr {
        bar,
        plain: !quiet && !terminal,
    })
}

impl Stderr {
    fn line(&self, text: &str) {
        match &self.bar {
            Some(b) => b.println(text),
            None => eprintln!("{text}"),
        }
    }
}

impl Progress for Stderr {
    fn start(&self, total: usize) {
        if let Some(b) = &self.bar {
            b.set_length(total as u64);
            b.set_draw_target(indicatif::ProgressDrawTarget::stderr());
        }
    }

    fn warning(&self, path: &Path, warning: &day2night::Warning) {
        self.line(&warning.line(&path.display().to_string()));
    }

    fn input_done(&self, e: &InputDone<'_>) {
        if let Some(b) = &self.bar {
            b.inc(1);
            if e.failed > 0 {
                b.println(format!("dataset: {} failed", e.input));
            }
        } else if self.plain {
            let state = if e.failed > 0 {
                format!("{} done, {} FAILED", e.done, e.failed)
            } else if e.done == 0 {
                format!("up to date ({} skipped)", e.skipped)
            } else {
                format!("{} done, {} skipped", e.done, e.skipped)
            };
            eprintln!(
                "dataset: [{}/{}] {} {}: {state} ({:.1} s)",
                e.index, e.total, e.split, e.input, e.secs
            );
        }
    }

    fn finish(&self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
    }
}
