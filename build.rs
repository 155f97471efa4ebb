//! Build script: only tells the integration tests which requirements the developer has
//! declared absent, so that the tests needing them are reported as *ignored* (with the
//! reason) instead of passing without testing. The library and the CLI do not use it.
//!
//! `D2N_ALLOW_MISSING=validators,exiftool,chromium,time,shared-data` (or `all`) sets
//! `cfg(d2n_missing = "...")` for each name; a test that needs one carries
//! `#[cfg_attr(d2n_missing = "NAME", ignore = "...")]`. The real-camera files are also
//! declared missing when they are not found at build time, unless
//! `D2N_REQUIRE_SHARED_DATA=1`. Without the declaration, a test whose requirement is
//! absent fails, naming it (tests/README.md).

use std::path::PathBuf;

const NAMES: [&str; 5] = ["validators", "exiftool", "chromium", "time", "shared-data"];

fn main() {
    println!("cargo::rerun-if-changed=build.rs");
    for var in [
        "D2N_ALLOW_MISSING",
        "D2N_SHARED_DATA",
        "D2N_REQUIRE_SHARED_DATA",
    ] {
        println!("cargo::rerun-if-env-changed={var}");
    }
    let list: Vec<String> = NAMES.iter().map(|n| format!("\"{n}\"")).collect();
    println!(
        "cargo::rustc-check-cfg=cfg(d2n_missing, values({}))",
        list.join(", ")
    );
    let allow = std::env::var("D2N_ALLOW_MISSING").unwrap_or_default();
    let allowed: Vec<&str> = allow.split(',').map(str::trim).collect();
    for a in &allowed {
        if !a.is_empty() && *a != "all" && !NAMES.contains(a) {
            println!(
                "cargo::warning=D2N_ALLOW_MISSING: unknown name {a:?} (known: all, {NAMES:?})"
            );
        }
    }
    for name in NAMES {
        let declared = allowed.contains(&name) || allowed.contains(&"all");
        if declared || (name == "shared-data" && shared_data_absent()) {
            println!("cargo::rustc-cfg=d2n_missing=\"{name}\"");
        }
    }
}

/// The real-camera files (`$D2N_SHARED_DATA`, else `../shared/data` beside the checkout)
/// are absent and not required.
fn shared_data_absent() -> bool {
    if std::env::var("D2N_REQUIRE_SHARED_DATA").as_deref() == Ok("1") {
        return false;
    }
    let dir = std::env::var_os("D2N_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            let root = std::env::var_os("CARGO_MANIFEST_DIR").unwrap_or_default();
            PathBuf::from(root).join("../shared/data")
        });
    !dir.is_dir()
}
