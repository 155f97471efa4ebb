//! `rust-version` in Cargo.toml is what the dependency tree requires: the highest
//! `rust-version` among the packages a build of the crate compiles (normal and build
//! dependencies, transitively; dev-dependencies are for our tests only), as `cargo
//! metadata` reports them. Same check for the Python package's crate (python/Cargo.toml).

use serde_json::Value;
use std::collections::{BTreeSet, HashMap};
use std::process::Command;

fn version_key(v: &str) -> (u64, u64, u64) {
    let mut it = v.split('.').map(|p| p.parse::<u64>().unwrap_or(0));
    (
        it.next().unwrap_or(0),
        it.next().unwrap_or(0),
        it.next().unwrap_or(0),
    )
}

/// (declared rust-version, required rust-version, the packages requiring it) of `name`.
fn msrv_of(meta: &Value, name: &str) -> (String, String, Vec<String>) {
    let packages: HashMap<&str, &Value> = meta["packages"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| (p["id"].as_str().unwrap(), p))
        .collect();
    let root = packages
        .values()
        .find(|p| p["name"] == name && p["source"].is_null())
        .unwrap_or_else(|| panic!("{name} not in cargo metadata"));
    let nodes: HashMap<&str, &Value> = meta["resolve"]["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| (n["id"].as_str().unwrap(), n))
        .collect();
    let mut seen = BTreeSet::new();
    let mut stack = vec![root["id"].as_str().unwrap()];
    while let Some(id) = stack.pop() {
        if !seen.insert(id) {
            continue;
        }
        for dep in nodes[id]["deps"].as_array().unwrap() {
            let kinds = dep["dep_kinds"].as_array().unwrap();
            if kinds
                .iter()
                .any(|k| k["kind"].is_null() || k["kind"] == "build")
            {
                stack.push(dep["pkg"].as_str().unwrap());
            }
        }
    }
    seen.remove(root["id"].as_str().unwrap());
    let mut best = "0".to_string();
    let mut who = Vec::new();
    for id in seen {
        let p = packages[id];
        if let Some(rv) = p["rust_version"].as_str() {
            let name = format!(
                "{} {}",
                p["name"].as_str().unwrap(),
                p["version"].as_str().unwrap()
            );
            match version_key(rv).cmp(&version_key(&best)) {
                std::cmp::Ordering::Greater => {
                    best = rv.to_string();
                    who = vec![name];
                }
                std::cmp::Ordering::Equal => who.push(name),
                std::cmp::Ordering::Less => {}
            }
        }
    }
    let declared = root["rust_version"].as_str().unwrap_or("none").to_string();
    (declared, best, who)
}

#[test]
fn rust_version_is_what_the_dependencies_require() {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .args(["metadata", "--format-version", "1"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("cargo metadata runs");
    assert!(
        out.status.success(),
        "cargo metadata failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let meta: Value = serde_json::from_slice(&out.stdout).unwrap();
    for name in ["day2night", "day2night-python"] {
        let (declared, required, who) = msrv_of(&meta, name);
        assert_eq!(
            version_key(&declared),
            version_key(&required),
            "{name}: Cargo.toml says rust-version = {declared:?}, the dependencies need {required} ({})",
            who.join(", ")
        );
    }
}
