//! Architecture invariants read from the source tree (after rust-analyzer's `tidy`): the
//! layer order of docs/layers.txt holds (no file uses an item of a higher layer or of
//! another module of its own layer) and no files use each other in a cycle. A failure names
//! the file, the line and the path used. A file's use of the module files that contain it
//! (its `mod.rs` ancestors: the facade of its module, e.g. a helper in `isp/demosaic/mod.rs`
//! that every demosaicer uses) is not counted as a dependency. Test code (`#[cfg(test)]` items and the files of
//! test modules) is not checked: a unit test may read a fixture through a higher layer.
mod model;

use crate::common;
use model::{parse_file, FileModel};
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// The files of one crate, by module path, as its `mod` declarations reach them.
struct Crate {
    files: Vec<FileModel>,
    by_module: BTreeMap<Vec<String>, usize>,
}

/// Source texts by repository-relative path (so a test can check an altered tree).
type Sources = BTreeMap<String, String>;

fn read_sources(dir: &str) -> Sources {
    fn walk(root: &Path, d: &Path, out: &mut Sources) {
        for e in std::fs::read_dir(d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(root, &p, out);
            } else if p.extension().and_then(|x| x.to_str()) == Some("rs") {
                let rel = p
                    .strip_prefix(root)
                    .unwrap()
                    .to_string_lossy()
                    .replace('\\', "/");
                out.insert(rel, std::fs::read_to_string(&p).unwrap());
            }
        }
    }
    let root = common::root();
    let mut out = Sources::new();
    walk(&root, &root.join(dir), &mut out);
    out
}

/// The crate rooted at `root_file` (e.g. `src/lib.rs`), following `mod` declarations.
fn load_crate(src: &Sources, root_file: &str) -> Crate {
    let mut files = Vec::new();
    let mut by_module = BTreeMap::new();
    // (file, module path, directory its child modules live in)
    let dir_of = |f: &str| {
        f.rsplit_once('/')
            .map(|(d, _)| d.to_string())
            .unwrap_or_default()
    };
    let mut todo = vec![(
        root_file.to_string(),
        Vec::<String>::new(),
        dir_of(root_file),
    )];
    while let Some((path, module, dir)) = todo.pop() {
        let text = src
            .get(&path)
            .unwrap_or_else(|| panic!("{path}: declared module file not found"));
        let mut test_children = BTreeSet::new();
        let fm = parse_file(&path, module.clone(), text, &mut test_children)
            .unwrap_or_else(|e| panic!("{e}"));
        for child in &fm.children {
            let flat = format!("{dir}/{child}.rs");
            let nested = format!("{dir}/{child}/mod.rs");
            let (file, child_dir) = if src.contains_key(&flat) {
                (flat, format!("{dir}/{child}"))
            } else {
                (nested, format!("{dir}/{child}"))
            };
            let mut m = module.clone();
            m.push(child.clone());
            todo.push((file, m, child_dir));
        }
        by_module.insert(module, files.len());
        files.push(fm);
    }
    Crate { files, by_module }
}

impl Crate {
    /// The file that defines what `path` (absolute) names: the module's file for a module,
    /// the defining file for an item, through `pub use` re-exports and globs.
    fn resolve(&self, path: &[String], depth: usize) -> Option<usize> {
        if depth > 16 {
            return None;
        }
        let mut cur: Vec<String> = Vec::new();
        for (i, seg) in path.iter().enumerate() {
            let fi = *self.by_module.get(&cur)?;
            let f = &self.files[fi];
            if f.children.contains(seg) {
                cur.push(seg.clone());
                continue;
            }
            if f.defines.contains(seg) {
                return Some(fi);
            }
            if let Some(target) = f.reexports.get(seg) {
                let mut p = target.clone();
                p.extend_from_slice(&path[i + 1..]);
                return self.resolve(&p, depth + 1).or(Some(fi));
            }
            for g in &f.globs {
                let mut p = g.clone();
                p.extend_from_slice(&path[i..]);
                if let Some(t) = self.resolve(&p, depth + 1) {
                    if self.files[t].defines.contains(seg) || t != *self.by_module.get(g)? {
                        return Some(t);
                    }
                }
            }
            // an unknown name (a variant, an associated item...) is the module's
            return Some(fi);
        }
        self.by_module.get(&cur).copied()
    }
}

/// One dependency: `from` uses `path` (defined in `to`) at `line`.
#[derive(Debug, Clone)]
struct Edge {
    to: String,
    line: usize,
    path: String,
}

/// File dependency graph of several crates: file -> (file it uses -> first use).
type Graph = BTreeMap<String, BTreeMap<String, Edge>>;

fn graph(crates: &[Crate]) -> Graph {
    let mut g = Graph::new();
    for c in crates {
        for f in &c.files {
            let out = g.entry(f.path.clone()).or_default();
            for (p, line) in &f.uses {
                let Some(t) = c.resolve(p, 0) else { continue };
                let to = &c.files[t].path;
                // The module files that contain a file (its `mod.rs` ancestors, the crate
                // root) are its facade: `super::` items are not a dependency between files.
                let ancestor = c.files[t].module.len() < f.module.len()
                    && f.module.starts_with(&c.files[t].module);
                if *to != f.path && !ancestor {
                    out.entry(to.clone()).or_insert_with(|| Edge {
                        to: to.clone(),
                        line: *line,
                        path: format!("crate::{}", p.join("::")),
                    });
                }
            }
        }
    }
    g
}

/// Layers of docs/layers.txt: top-level module name -> layer index (0 = lowest).
fn layers(text: &str) -> BTreeMap<String, usize> {
    let mut out = BTreeMap::new();
    let lines = text
        .lines()
        .map(|l| l.split('#').next().unwrap_or("").trim())
        .filter(|l| !l.is_empty());
    for (i, line) in lines.enumerate() {
        for m in line.split_whitespace() {
            assert!(
                out.insert(m.to_string(), i).is_none(),
                "docs/layers.txt: {m} twice"
            );
        }
    }
    out
}

/// The layer name of a file of src/: its top-level module (`crate` for lib.rs, `cli` for
/// the binary's files).
fn top_module(path: &str) -> String {
    let rest = path.trim_start_matches("src/");
    match rest {
        "lib.rs" => "crate".into(),
        "main.rs" => "cli".into(),
        _ => rest
            .split('/')
            .next()
            .unwrap_or("")
            .trim_end_matches(".rs")
            .to_string(),
    }
}

/// Every layering violation of `g` (files of src/ only), as messages.
fn layer_violations(g: &Graph, order: &BTreeMap<String, usize>) -> Vec<String> {
    let mut out = Vec::new();
    for (from, edges) in g {
        if !from.starts_with("src/") {
            continue;
        }
        let fm = top_module(from);
        let Some(&fl) = order.get(&fm) else {
            out.push(format!("{from}: module `{fm}` is not in docs/layers.txt"));
            continue;
        };
        for e in edges.values() {
            let tm = top_module(&e.to);
            let Some(&tl) = order.get(&tm) else { continue };
            if tm != fm && tl >= fl {
                let why = if tl == fl {
                    "same layer"
                } else {
                    "higher layer"
                };
                out.push(format!(
                    "{from}:{}: `{fm}` uses {} of `{tm}` ({why}: {})",
                    e.line, e.path, e.to
                ));
            }
        }
    }
    out
}

/// Every cycle between files (one per strongly connected component), as messages naming
/// each step's line.
fn cycles(g: &Graph) -> Vec<String> {
    // Tarjan's strongly connected components.
    struct T<'a> {
        g: &'a Graph,
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        on: BTreeSet<&'a str>,
        next: usize,
        sccs: Vec<Vec<&'a str>>,
    }
    fn visit<'a>(t: &mut T<'a>, v: &'a str) {
        t.index.insert(v, t.next);
        t.low.insert(v, t.next);
        t.next += 1;
        t.stack.push(v);
        t.on.insert(v);
        if let Some(es) = t.g.get(v) {
            for w in es.keys() {
                let w = w.as_str();
                if !t.index.contains_key(w) {
                    visit(t, w);
                    let lw = t.low[w];
                    let lv = t.low[v];
                    t.low.insert(v, lv.min(lw));
                } else if t.on.contains(w) {
                    let iw = t.index[w];
                    let lv = t.low[v];
                    t.low.insert(v, lv.min(iw));
                }
            }
        }
        if t.low[v] == t.index[v] {
            let mut comp = Vec::new();
            while let Some(w) = t.stack.pop() {
                t.on.remove(w);
                comp.push(w);
                if w == v {
                    break;
                }
            }
            if comp.len() > 1 {
                t.sccs.push(comp);
            }
        }
    }
    let mut t = T {
        g,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on: BTreeSet::new(),
        next: 0,
        sccs: Vec::new(),
    };
    for v in g.keys() {
        if !t.index.contains_key(v.as_str()) {
            visit(&mut t, v);
        }
    }
    t.sccs
        .iter()
        .map(|comp| {
            let set: BTreeSet<&str> = comp.iter().copied().collect();
            let steps: Vec<String> = comp
                .iter()
                .flat_map(|a| {
                    g[*a]
                        .values()
                        .filter(|e| set.contains(e.to.as_str()))
                        .map(move |e| format!("{a}:{} uses {} ({})", e.line, e.path, e.to))
                })
                .collect();
            format!(
                "cycle between {}:\n    {}",
                comp.join(", "),
                steps.join("\n    ")
            )
        })
        .collect()
}

/// Check a source tree: layering of src/ and cycles in every crate.
fn check(src: &Sources, py: &Sources, order: &BTreeMap<String, usize>) -> Vec<String> {
    let crates = [
        load_crate(src, "src/lib.rs"),
        load_crate(src, "src/main.rs"),
        load_crate(py, "python/src/lib.rs"),
    ];
    let g = graph(&crates);
    let mut problems = layer_violations(&g, order);
    problems.extend(cycles(&g));
    problems
}

fn layer_text() -> String {
    std::fs::read_to_string(common::root().join("docs/layers.txt")).unwrap()
}

#[test]
fn layers_hold_and_no_file_cycles() {
    let order = layers(&layer_text());
    let problems = check(&read_sources("src"), &read_sources("python/src"), &order);
    assert!(
        problems.is_empty(),
        "{} layering problem(s) (docs/layers.txt):\n{}",
        problems.len(),
        problems.join("\n")
    );
}

#[test]
fn an_upward_use_and_a_cycle_are_caught_and_named() {
    let order = layers(&layer_text());
    let mut src = read_sources("src");
    let py = read_sources("python/src");
    // The tiff layer using the synthesis (a higher layer), on a known line.
    let tiff = src.get_mut("src/tiff/mod.rs").unwrap();
    let line = tiff.lines().count() + 1;
    tiff.push_str("use crate::synth::Plan;\n");
    let problems = check(&src, &py, &order);
    let hit = format!("src/tiff/mod.rs:{line}: `tiff` uses crate::synth::Plan of `synth`");
    assert!(
        problems.iter().any(|p| p.starts_with(&hit)),
        "expected {hit:?} in {problems:#?}"
    );
    // A cycle: job.rs uses sidecar.rs today; make sidecar.rs use job.rs too.
    let mut src = read_sources("src");
    src.get_mut("src/synth/sidecar.rs")
        .unwrap()
        .push_str("\nfn _cycle_probe(_: &crate::synth::job::SynthJob) {}\n");
    let problems = check(&src, &py, &order);
    assert!(
        problems
            .iter()
            .any(|p| p.starts_with("cycle between") && p.contains("src/synth/sidecar.rs:")),
        "expected a cycle through sidecar.rs in {problems:#?}"
    );
}

#[test]
fn layer_data_covers_src_and_matches_the_architecture_doc() {
    let text = layer_text();
    let order = layers(&text);
    let src = read_sources("src");
    let tops: BTreeSet<String> = src.keys().map(|p| top_module(p)).collect();
    for t in &tops {
        assert!(order.contains_key(t), "src/{t}: not in docs/layers.txt");
    }
    for m in order.keys() {
        assert!(
            tops.contains(m),
            "docs/layers.txt names `{m}`, which src/ does not have"
        );
    }
    // docs/architecture.md shows the same order: each layer's modules as `a`, `b`, in order
    let doc = std::fs::read_to_string(common::root().join("docs/architecture.md")).unwrap();
    let rendered: Vec<String> = text
        .lines()
        .map(|l| l.split('#').next().unwrap_or("").trim())
        .filter(|l| !l.is_empty())
        .map(|l| {
            l.split_whitespace()
                .map(|m| format!("`{m}`"))
                .collect::<Vec<_>>()
                .join(", ")
        })
        .collect();
    let line = rendered.join(" → ");
    assert!(
        doc.replace('\n', " ").contains(&line),
        "docs/architecture.md must show the layer order of docs/layers.txt as:\n{line}"
    );
}
