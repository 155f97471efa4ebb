//! The import graph's rules (issue 43 item 4): the graph is visible and has no cycle.
//!
//! - `py-import`: no import inside a Python function of python/pysrc (imports go at the top of
//!   each module), and torch is imported only by python/pysrc/day2night/train/_torch.py
//!   ([`TORCH_HOME`]), the one optional dependency;
//! - `py-cycle`: no cycle among the modules of python/pysrc (every `import`/`from ... import`
//!   statement an edge, relative imports resolved, `day2night._native` the extension);
//! - `pyo3-by-name`: python/src reads the parameters it binds itself by name: no `p[0]` on
//!   what `bind_params`/`bind` returned and no `PARAMS[1..]`-style slice of a parameter list,
//!   so that reordering a list cannot rebind a value silently.
//!
//! Cycles among the Rust modules (files) of src/ and python/src are refused by
//! tests/it/layers (`layers_hold_and_no_file_cycles`), with the layers of docs/layers.txt.

use super::{python_blocks, python_code_only, tokens, v, Violation};
use std::collections::{BTreeMap, BTreeSet};

/// The module that imports torch, the package's one optional dependency.
pub(super) const TORCH_HOME: &str = "python/pysrc/day2night/train/_torch.py";

/// The compiled extension: a module of the package without a `.py` file.
const EXTENSION: &str = "day2night._native";

/// The import statements of Python source: (line, statement joined onto one line), strings
/// and comments blanked; a parenthesized or backslash-continued statement is one.
fn import_statements(text: &str) -> Vec<(usize, String)> {
    let code = python_code_only(text);
    let lines: Vec<&str> = code.lines().collect();
    let mut out = Vec::new();
    let mut k = 0;
    while k < lines.len() {
        let t = lines[k].trim_start();
        if !(t.starts_with("import ") || t.starts_with("from ")) {
            k += 1;
            continue;
        }
        let start = k;
        let mut stmt = String::new();
        let mut depth = 0i32;
        loop {
            let l = lines[k];
            depth += l.matches('(').count() as i32 - l.matches(')').count() as i32;
            stmt.push_str(l.trim().trim_end_matches('\\'));
            stmt.push(' ');
            k += 1;
            let more = depth > 0 || l.trim_end().ends_with('\\');
            if !more || k >= lines.len() {
                break;
            }
        }
        let stmt = stmt.trim().to_string();
        // `raise E(...) \` continued by `from None` is no import
        if stmt.starts_with("import ") || stmt.contains(" import ") {
            out.push((start + 1, stmt));
        }
    }
    out
}

/// Rule `py-import` on one file of python/pysrc.
pub(super) fn function_imports(rel: &str, text: &str) -> Vec<Violation> {
    let defs: Vec<(usize, usize)> = python_blocks(text)
        .into_iter()
        .filter(|b| b.kind == "def")
        .map(|b| (b.start, b.end))
        .collect();
    let mut out = Vec::new();
    for (line, stmt) in import_statements(text) {
        if let Some((start, _)) = defs.iter().find(|(s, e)| *s < line && line <= *e) {
            out.push(v(
                rel,
                line,
                "py-import",
                format!(
                    "`{stmt}` inside the function of line {start}: import at the top of the module"
                ),
            ));
        }
        let torch = imported_names(&stmt)
            .iter()
            .any(|m| m == "torch" || m.starts_with("torch."));
        if torch && rel != TORCH_HOME {
            out.push(v(
                rel,
                line,
                "py-import",
                format!("`{stmt}`: import torch from {TORCH_HOME} (`from ._torch import torch`)"),
            ));
        }
    }
    out
}

/// The absolute module names a statement names (before resolving relative ones: `.x` stays
/// `.x`): `import a.b, c as d` gives a.b and c; `from X import a, b` gives X.a and X.b.
fn imported_names(stmt: &str) -> Vec<String> {
    let clean = |s: &str| {
        s.split(" as ")
            .next()
            .unwrap_or("")
            .trim()
            .trim_matches(|c| c == '(' || c == ')')
            .trim()
            .to_string()
    };
    if let Some(rest) = stmt.strip_prefix("import ") {
        return rest
            .split(',')
            .map(clean)
            .filter(|s| !s.is_empty())
            .collect();
    }
    let Some(rest) = stmt.strip_prefix("from ") else {
        return vec![];
    };
    let Some((from, names)) = rest.split_once(" import ") else {
        return vec![];
    };
    let from = from.trim();
    let sep = if from.ends_with('.') { "" } else { "." };
    names
        .split(',')
        .map(clean)
        .filter(|s| !s.is_empty())
        .map(|n| format!("{from}{sep}{n}"))
        .collect()
}

/// The module name of a file under python/pysrc (`day2night/x/__init__.py` is `day2night.x`).
fn module_name(rel: &str) -> String {
    let p = rel.strip_prefix("python/pysrc/").unwrap_or(rel);
    let p = p.strip_suffix(".py").unwrap_or(p);
    let p = p.strip_suffix("/__init__").unwrap_or(p);
    p.replace('/', ".")
}

/// `name` (`..x.y` relative to the module `module`, a package when `package`) made absolute.
fn absolute(name: &str, module: &str, package: bool) -> String {
    let dots = name.chars().take_while(|&c| c == '.').count();
    if dots == 0 {
        return name.to_string();
    }
    let mut base: Vec<&str> = module.split('.').collect();
    let up = if package { dots - 1 } else { dots };
    base.truncate(base.len().saturating_sub(up));
    let rest = &name[dots..];
    if rest.is_empty() {
        base.join(".")
    } else {
        format!("{}.{rest}", base.join("."))
    }
}

/// The import graph of Python files ((path, text) under python/pysrc): module -> (module
/// it imports -> the line of the first such import). `from X import n` is an edge to X.n
/// when that is a module, else to X; `import a.b` to the longest known prefix of a.b.
pub(super) fn python_graph(
    files: &[(String, String)],
) -> BTreeMap<String, BTreeMap<String, usize>> {
    let mut known: BTreeSet<String> = files.iter().map(|(r, _)| module_name(r)).collect();
    known.insert(EXTENSION.to_string());
    let mut g: BTreeMap<String, BTreeMap<String, usize>> = BTreeMap::new();
    for (rel, text) in files {
        let m = module_name(rel);
        let package = rel.ends_with("/__init__.py");
        let edges = g.entry(m.clone()).or_default();
        for (line, stmt) in import_statements(text) {
            for name in imported_names(&stmt) {
                let full = absolute(&name, &m, package);
                // the longest known prefix: X.n when n is a module, else X
                let mut target = full.as_str();
                while !known.contains(target) {
                    match target.rsplit_once('.') {
                        Some((head, _)) => target = head,
                        None => break,
                    }
                }
                if known.contains(target) && target != m {
                    edges.entry(target.to_string()).or_insert(line);
                }
            }
        }
    }
    g
}

/// Every cycle of a graph (one per strongly connected component of two or more nodes), as
/// its nodes in order.
pub(super) fn cycles(g: &BTreeMap<String, BTreeMap<String, usize>>) -> Vec<Vec<String>> {
    // Tarjan's algorithm
    struct T<'a> {
        g: &'a BTreeMap<String, BTreeMap<String, usize>>,
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        on: BTreeSet<&'a str>,
        out: Vec<Vec<String>>,
    }
    fn visit<'a>(t: &mut T<'a>, v: &'a str) {
        let n = t.index.len();
        t.index.insert(v, n);
        t.low.insert(v, n);
        t.stack.push(v);
        t.on.insert(v);
        let g = t.g;
        for w in g.get(v).into_iter().flat_map(|e| e.keys()) {
            let w = w.as_str();
            if !t.index.contains_key(w) {
                visit(t, w);
                let lw = t.low[w];
                let lv = t.low.get_mut(v).expect("visited");
                *lv = (*lv).min(lw);
            } else if t.on.contains(w) {
                let iw = t.index[w];
                let lv = t.low.get_mut(v).expect("visited");
                *lv = (*lv).min(iw);
            }
        }
        if t.low[v] == t.index[v] {
            let mut comp = Vec::new();
            while let Some(w) = t.stack.pop() {
                t.on.remove(w);
                comp.push(w.to_string());
                if w == v {
                    break;
                }
            }
            if comp.len() > 1 {
                comp.sort();
                t.out.push(comp);
            }
        }
    }
    let mut t = T {
        g,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on: BTreeSet::new(),
        out: Vec::new(),
    };
    for v in g.keys() {
        if !t.index.contains_key(v.as_str()) {
            visit(&mut t, v);
        }
    }
    t.out
}

/// Rule `py-cycle`: one violation per cycle, at the first import of its first module that
/// stays inside the cycle.
pub(super) fn python_cycles(files: &[(String, String)]) -> Vec<Violation> {
    let g = python_graph(files);
    let path_of: BTreeMap<String, &str> = files
        .iter()
        .map(|(r, _)| (module_name(r), r.as_str()))
        .collect();
    let mut out = Vec::new();
    for comp in cycles(&g) {
        let first = &comp[0];
        let line = g[first]
            .iter()
            .filter(|(to, _)| comp.contains(to))
            .map(|(_, l)| *l)
            .min()
            .unwrap_or(1);
        let edges: Vec<String> = comp
            .iter()
            .flat_map(|a| {
                g[a].iter()
                    .filter(|(b, _)| comp.contains(b))
                    .map(move |(b, l)| format!("{a} -> {b} (line {l})"))
            })
            .collect();
        out.push(v(
            path_of.get(first).copied().unwrap_or(first),
            line,
            "py-cycle",
            format!(
                "the modules {} import each other: {}; move what they share into one of them \
                 or a third module",
                comp.join(", "),
                edges.join(", ")
            ),
        ));
    }
    out
}

/// Rule `pyo3-by-name` on one file of python/src.
pub(super) fn positional_params(rel: &str, text: &str) -> Vec<Violation> {
    let toks = tokens(rel, text);
    // the names a `let` binds from bind_params(...) or bind(...)
    let mut bound: BTreeSet<String> = BTreeSet::new();
    let mut i = 0;
    while i < toks.len() {
        if toks[i].0 == "let" {
            let end = (i..toks.len())
                .find(|&j| toks[j].0 == ";")
                .unwrap_or(toks.len());
            let eq = (i..end).find(|&j| toks[j].0 == "=").unwrap_or(end);
            let binds = toks[eq..end]
                .windows(2)
                .any(|w| (w[0].0 == "bind_params" || w[0].0 == "bind") && w[1].0 == "(");
            if binds {
                for t in &toks[i + 1..eq] {
                    let ident = t.0.chars().all(|c| c.is_alphanumeric() || c == '_');
                    if ident && !t.2 && t.0 != "mut" && t.0 != "_" {
                        bound.insert(t.0.clone());
                    }
                }
            }
            i = end;
        }
        i += 1;
    }
    let mut out = Vec::new();
    for w in toks.windows(3) {
        let (name, open, first) = (&w[0], &w[1], &w[2]);
        let literal = first.2 && first.0.chars().all(|c| c.is_ascii_digit());
        let slice = first.0 == "." && name.0.ends_with("PARAMS");
        if open.0 == "["
            && (literal || slice)
            && (bound.contains(&name.0) || name.0.ends_with("PARAMS"))
        {
            out.push(v(
                rel,
                name.1,
                "pyo3-by-name",
                format!(
                    "`{}[{}...]`: read a bound parameter by its name (`p.get(\"seed\")`, \
                     `p.extract::<T>(\"seed\")`), not by its position",
                    name.0, first.0
                ),
            ));
        }
    }
    out
}
