//! The house rules that a reader of the source can check, read from the repository's files
//! (after rust-analyzer's `tidy`): its own small test binary, pure text and token scanning
//! (`syn` for Rust, a line scanner for Python), run by the default `cargo test`. A failure
//! names `file:line`, the rule and what to do. The rules:
//!
//! - `env`: no `env::var` (any form) in the library: the environment is read by the command
//!   line (src/cli, src/main.rs) and handed down as options;
//! - `print`: no `print!`/`println!`/`eprint!`/`eprintln!`/`dbg!` in the library or the
//!   Python extension, except in test code (`#[cfg(test)]`, `#[test]`, test module files);
//! - `fn-length`, `file-length`: no function over [`FN_MAX`] lines, no file over
//!   [`FILE_MAX`] lines in src/, python/src and python/pysrc (Python functions too);
//!   python/pysrc's stricter limits ([`PY_STRICT_FN_MAX`], [`PY_CLASS_MAX`]) are checked
//!   when [`PY_STRICT`] is on, and listed otherwise;
//! - `colour`: no sRGB or XYZ constant (the matrices between linear sRGB and XYZ, the D65
//!   white in XYZ, Bradford's matrix, the sRGB transfer curve's constants) outside src/color
//!   in the code (src/, python/src, python/pysrc, examples/, benches/, scripts/). Tests
//!   (tests/, python/tests, with the validators of tests/validators) are oracles: they stay
//!   independent of src/color, so they are not scanned;
//! - `doc-path`: every repository path named in a doc (README.md, docs/*.md, docs/*.txt,
//!   python/README.md, tests/README.md) or a Rust doc comment exists, and so does every
//!   relative Markdown link target.
//!
//! - `py-import`, `py-cycle`, `pyo3-by-name`: the import graph (tests/tidy/imports.rs): no
//!   import inside a Python function and torch imported in one module, no cycle among the
//!   Python modules, parameters read by name in python/src.
//!
//! [`ALLOW`] lists the exceptions still standing, each with its reason; it is meant to be
//! empty. `cargo test --test tidy -- --nocapture` also prints what [`PY_STRICT`] would find.

use proc_macro2::{Delimiter, TokenStream, TokenTree};
use std::collections::BTreeSet;
use std::fmt;
use std::path::{Path, PathBuf};
use syn::spanned::Spanned;
use syn::visit::Visit;

#[path = "tidy/imports.rs"]
mod imports;

/// Longest function, in lines (Rust and Python).
const FN_MAX: usize = 150;
/// Longest source file, in lines (Rust and Python).
const FILE_MAX: usize = 900;
/// python/pysrc's own limits (house rules): on once python/pysrc meets them.
const PY_STRICT: bool = true;
/// Longest Python function in python/pysrc under [`PY_STRICT`].
const PY_STRICT_FN_MAX: usize = 60;
/// Longest Python class in python/pysrc under [`PY_STRICT`].
const PY_CLASS_MAX: usize = 150;

/// Exceptions: (rule, file, reason). Every entry is a debt to pay back, not a rule.
const ALLOW: &[(&str, &str, &str)] = &[];

/// One broken rule.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
struct Violation {
    file: String,
    line: usize,
    rule: &'static str,
    msg: String,
}

impl fmt::Display for Violation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}:{}: [{}] {}",
            self.file, self.line, self.rule, self.msg
        )
    }
}

fn v(file: &str, line: usize, rule: &'static str, msg: String) -> Violation {
    Violation {
        file: file.to_string(),
        line,
        rule,
        msg,
    }
}

// ---------------------------------------------------------------------------------------
// The tree

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Repository-relative paths (with `/`) of the files under `dir` whose names end with `ext`.
fn files(dir: &str, ext: &str) -> Vec<String> {
    fn walk(root: &Path, d: &Path, ext: &str, out: &mut Vec<String>) {
        let Ok(rd) = std::fs::read_dir(d) else { return };
        for e in rd.flatten() {
            let p = e.path();
            let name = e.file_name().to_string_lossy().into_owned();
            if p.is_dir() {
                if !matches!(
                    name.as_str(),
                    "target" | ".venv" | "node_modules" | "__pycache__"
                ) && !name.starts_with('.')
                {
                    walk(root, &p, ext, out);
                }
            } else if name.ends_with(ext) {
                let rel = p.strip_prefix(root).unwrap_or(&p);
                out.push(rel.to_string_lossy().replace('\\', "/"));
            }
        }
    }
    let mut out = Vec::new();
    walk(&root(), &root().join(dir), ext, &mut out);
    out.sort();
    out
}

fn read(rel: &str) -> String {
    std::fs::read_to_string(root().join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

fn allowed(x: &Violation) -> bool {
    ALLOW.iter().any(|(r, f, _)| *r == x.rule && *f == x.file)
}

fn assert_clean(what: &str, found: Vec<Violation>) {
    let left: Vec<String> = found
        .iter()
        .filter(|x| !allowed(x))
        .map(|x| x.to_string())
        .collect();
    assert!(
        left.is_empty(),
        "{} {what} violation(s) (tests/tidy.rs):\n{}",
        left.len(),
        left.join("\n")
    );
}

// ---------------------------------------------------------------------------------------
// Rust: test code, tokens

fn is_cfg_test(attrs: &[syn::Attribute]) -> bool {
    attrs.iter().any(|a| {
        if a.path().is_ident("test") {
            return true;
        }
        if !a.path().is_ident("cfg") {
            return false;
        }
        let t = match &a.meta {
            syn::Meta::List(l) => l.tokens.to_string(),
            _ => String::new(),
        };
        // #[cfg(test)], #[cfg(all(test, unix))]; not #[cfg(not(test))]
        t.split(|c: char| !c.is_alphanumeric() && c != '_')
            .any(|w| w == "test")
            && !t.contains("not")
    })
}

/// Line ranges (1-based, inclusive) of test code in a parsed file, and the names of the
/// child modules declared as test modules (`#[cfg(test)] mod tests;`).
#[derive(Default)]
struct TestCode {
    ranges: Vec<(usize, usize)>,
    child_mods: Vec<String>,
}

impl<'a> Visit<'a> for TestCode {
    fn visit_item(&mut self, i: &'a syn::Item) {
        let attrs: &[syn::Attribute] = match i {
            syn::Item::Fn(x) => &x.attrs,
            syn::Item::Mod(x) => &x.attrs,
            syn::Item::Impl(x) => &x.attrs,
            syn::Item::Const(x) => &x.attrs,
            syn::Item::Static(x) => &x.attrs,
            syn::Item::Struct(x) => &x.attrs,
            syn::Item::Enum(x) => &x.attrs,
            syn::Item::Use(x) => &x.attrs,
            syn::Item::Macro(x) => &x.attrs,
            _ => &[],
        };
        if is_cfg_test(attrs) {
            let s = i.span();
            self.ranges.push((s.start().line, s.end().line));
            if let syn::Item::Mod(m) = i {
                if m.content.is_none() {
                    self.child_mods.push(m.ident.to_string());
                }
            }
            return;
        }
        syn::visit::visit_item(self, i);
    }
    fn visit_impl_item_fn(&mut self, i: &'a syn::ImplItemFn) {
        if is_cfg_test(&i.attrs) {
            let s = i.span();
            self.ranges.push((s.start().line, s.end().line));
            return;
        }
        syn::visit::visit_impl_item_fn(self, i);
    }
}

fn parse(rel: &str, text: &str) -> syn::File {
    syn::parse_file(text).unwrap_or_else(|e| panic!("{rel}: cannot parse: {e}"))
}

/// The files of `rels` that are test modules (declared `#[cfg(test)] mod x;` by a parent).
fn test_module_files(rels: &[String], texts: &[String]) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for (rel, text) in rels.iter().zip(texts) {
        let mut t = TestCode::default();
        t.visit_file(&parse(rel, text));
        let (dir, stem) = rel.rsplit_once('/').unwrap_or(("", rel));
        let stem = stem.trim_end_matches(".rs");
        let base = if matches!(stem, "mod" | "lib" | "main") {
            dir.to_string()
        } else {
            format!("{dir}/{stem}")
        };
        for m in t.child_mods {
            out.insert(format!("{base}/{m}.rs"));
            out.insert(format!("{base}/{m}/mod.rs"));
        }
    }
    // the descendants of a test module are test code too
    let mut grew = true;
    while grew {
        grew = false;
        for rel in rels {
            let dir = rel.rsplit_once('/').map(|(d, _)| d).unwrap_or("");
            let parent_mod = format!("{dir}/mod.rs");
            let parent_file = format!("{dir}.rs");
            if !out.contains(rel) && (out.contains(&parent_mod) || out.contains(&parent_file)) {
                grew |= out.insert(rel.clone());
            }
        }
    }
    out
}

/// Every token of `ts`, flattened (groups' delimiters as `(`, `)` punctuation-like markers
/// are dropped: only what is inside them is kept), with its line.
fn flat_tokens(ts: TokenStream, out: &mut Vec<(String, usize, bool)>) {
    // (text, line, is_literal)
    for tt in ts {
        match tt {
            TokenTree::Group(g) => {
                let (open, close) = match g.delimiter() {
                    Delimiter::Parenthesis => ("(", ")"),
                    Delimiter::Brace => ("{", "}"),
                    Delimiter::Bracket => ("[", "]"),
                    Delimiter::None => ("", ""),
                };
                let line = g.span().start().line;
                if !open.is_empty() {
                    out.push((open.into(), line, false));
                }
                flat_tokens(g.stream(), out);
                if !close.is_empty() {
                    out.push((close.into(), g.span().end().line, false));
                }
            }
            TokenTree::Ident(i) => out.push((i.to_string(), i.span().start().line, false)),
            TokenTree::Punct(p) => {
                out.push((p.as_char().to_string(), p.span().start().line, false))
            }
            TokenTree::Literal(l) => out.push((l.to_string(), l.span().start().line, true)),
        }
    }
}

fn tokens(rel: &str, text: &str) -> Vec<(String, usize, bool)> {
    let ts: TokenStream = text
        .parse()
        .unwrap_or_else(|e| panic!("{rel}: cannot tokenize: {e:?}"));
    let mut out = Vec::new();
    flat_tokens(ts, &mut out);
    // doc comments arrive as `#[doc = "..."]`: their literal is never code, drop the
    // attribute's tokens as a whole
    let mut kept = Vec::with_capacity(out.len());
    let mut i = 0;
    while i < out.len() {
        if out[i].0 == "#"
            && out.get(i + 1).is_some_and(|t| t.0 == "[" || t.0 == "!")
            && out.iter().skip(i + 1).take(3).any(|t| t.0 == "doc")
        {
            // skip to the attribute's closing bracket
            let mut depth = 0;
            let mut j = i + 1;
            while j < out.len() {
                match out[j].0.as_str() {
                    "[" => depth += 1,
                    "]" => {
                        depth -= 1;
                        if depth == 0 {
                            break;
                        }
                    }
                    _ => {}
                }
                j += 1;
            }
            i = j + 1;
            continue;
        }
        kept.push(out[i].clone());
        i += 1;
    }
    kept
}

// ---------------------------------------------------------------------------------------
// Rules: env and print

const PRINTS: [&str; 5] = ["print", "println", "eprint", "eprintln", "dbg"];

/// `env::var*` and the print macros in `text` outside its test code. `test_file`: the
/// whole file is test code (a test module's file); then only `env` is checked.
fn env_and_print(rel: &str, text: &str, test_file: bool) -> Vec<Violation> {
    let mut test = TestCode::default();
    test.visit_file(&parse(rel, text));
    let in_test =
        |line: usize| test_file || test.ranges.iter().any(|&(a, b)| a <= line && line <= b);
    let t = tokens(rel, text);
    let mut out = Vec::new();
    for (i, (tok, line, lit)) in t.iter().enumerate() {
        if *lit {
            continue;
        }
        let next = |k: usize| t.get(i + k).map(|x| x.0.as_str()).unwrap_or("");
        if tok == "env" && next(1) == ":" && next(2) == ":" {
            let named = if next(3) == "{" {
                // use std::env::{self, var}: look inside the braces
                t[i + 4..]
                    .iter()
                    .take_while(|x| x.0 != "}")
                    .any(|x| x.0.starts_with("var"))
            } else {
                next(3).starts_with("var")
            };
            if named {
                out.push(v(
                    rel,
                    *line,
                    "env",
                    "environment read in the library: read it in src/cli (or src/main.rs) and pass it down as an option".into(),
                ));
            }
        }
        if PRINTS.contains(&tok.as_str()) && next(1) == "!" && !in_test(*line) {
            // not a macro definition's own name (macro_rules! print) nor a path segment
            let prev = if i > 0 { t[i - 1].0.as_str() } else { "" };
            if prev != "." {
                out.push(v(
                    rel,
                    *line,
                    "print",
                    format!("`{tok}!` in the library: return the text (or a warning) and let the command line print it"),
                ));
            }
        }
    }
    out
}

// ---------------------------------------------------------------------------------------
// Rules: lengths

/// Functions of a Rust file over [`FN_MAX`] lines (signature to closing brace), and the
/// file itself over [`FILE_MAX`].
fn rust_lengths(rel: &str, text: &str) -> Vec<Violation> {
    struct Fns<'r> {
        rel: &'r str,
        out: Vec<Violation>,
    }
    impl Fns<'_> {
        fn check(&mut self, name: &syn::Ident, start: usize, end: usize) {
            let n = end + 1 - start;
            if n > FN_MAX {
                self.out.push(v(
                    self.rel,
                    start,
                    "fn-length",
                    format!("fn {name} is {n} lines (at most {FN_MAX}): split it"),
                ));
            }
        }
    }
    impl<'a> Visit<'a> for Fns<'_> {
        fn visit_item_fn(&mut self, i: &'a syn::ItemFn) {
            let start = i.sig.span().start().line;
            self.check(
                &i.sig.ident,
                start,
                i.block.brace_token.span.close().end().line,
            );
            syn::visit::visit_item_fn(self, i);
        }
        fn visit_impl_item_fn(&mut self, i: &'a syn::ImplItemFn) {
            let start = i.sig.span().start().line;
            self.check(
                &i.sig.ident,
                start,
                i.block.brace_token.span.close().end().line,
            );
            syn::visit::visit_impl_item_fn(self, i);
        }
        fn visit_trait_item_fn(&mut self, i: &'a syn::TraitItemFn) {
            if let Some(b) = &i.default {
                let start = i.sig.span().start().line;
                self.check(&i.sig.ident, start, b.brace_token.span.close().end().line);
            }
            syn::visit::visit_trait_item_fn(self, i);
        }
    }
    let mut f = Fns {
        rel,
        out: Vec::new(),
    };
    f.visit_file(&parse(rel, text));
    let mut out = f.out;
    out.extend(file_length(rel, text));
    out
}

fn file_length(rel: &str, text: &str) -> Option<Violation> {
    let n = text.lines().count();
    (n > FILE_MAX).then(|| {
        v(
            rel,
            n,
            "file-length",
            format!("{n} lines (at most {FILE_MAX}): split the file"),
        )
    })
}

/// A Python block (`def` or `class`) with its first and last line.
#[derive(Debug, PartialEq)]
struct PyBlock {
    kind: &'static str,
    name: String,
    start: usize,
    end: usize,
}

/// The `def`/`class` blocks of Python source, measured from their `def`/`class` line to
/// their last non-blank line. Logical lines are found by tracking brackets, strings
/// (triple-quoted ones across lines) and comments, so a continuation or a docstring line
/// never ends a block.
fn python_blocks(text: &str) -> Vec<PyBlock> {
    // (line, indent, first words) of each logical line start, and the last code line of each
    let mut starts: Vec<(usize, usize, String)> = Vec::new();
    let mut last_code = vec![0usize; 0];
    let mut depth = 0i32;
    let mut in_str: Option<&str> = None; // the closing quote of an open triple string
    for (k, line) in text.lines().enumerate() {
        let n = k + 1;
        let trimmed = line.trim_start();
        let logical_start = depth == 0 && in_str.is_none();
        let mut has_code = in_str.is_some() || depth > 0;
        if logical_start && !trimmed.is_empty() && !trimmed.starts_with('#') {
            starts.push((n, line.len() - trimmed.len(), trimmed.to_string()));
            has_code = true;
        }
        let b = line.as_bytes();
        let mut i = 0;
        while i < b.len() {
            if let Some(q) = in_str {
                if b[i..].starts_with(q.as_bytes()) {
                    in_str = None;
                    i += q.len();
                } else {
                    i += if b[i] == b'\\' { 2 } else { 1 };
                }
                continue;
            }
            match b[i] {
                b'#' => break,
                b'(' | b'[' | b'{' => depth += 1,
                b')' | b']' | b'}' => depth -= 1,
                q @ (b'"' | b'\'') => {
                    if b[i..].starts_with(&[q, q, q]) {
                        in_str = Some(if q == b'"' { "\"\"\"" } else { "\'\'\'" });
                        i += 3;
                        continue;
                    }
                    // a one-line string
                    i += 1;
                    while i < b.len() && b[i] != q {
                        i += if b[i] == b'\\' { 2 } else { 1 };
                    }
                }
                _ => {}
            }
            i += 1;
        }
        if has_code {
            last_code.push(n);
        }
    }
    let mut out = Vec::new();
    for (idx, (line, indent, head)) in starts.iter().enumerate() {
        let (kind, rest) = if let Some(r) = head.strip_prefix("def ") {
            ("def", r)
        } else if let Some(r) = head.strip_prefix("async def ") {
            ("def", r)
        } else if let Some(r) = head.strip_prefix("class ") {
            ("class", r)
        } else {
            continue;
        };
        let name: String = rest
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        let next = starts[idx + 1..]
            .iter()
            .find(|(_, i, _)| i <= indent)
            .map(|(l, _, _)| *l)
            .unwrap_or(usize::MAX);
        let end = last_code
            .iter()
            .copied()
            .filter(|&l| l < next)
            .max()
            .unwrap_or(*line);
        out.push(PyBlock {
            kind,
            name,
            start: *line,
            end,
        });
    }
    out
}

/// Python functions over [`FN_MAX`] lines and files over [`FILE_MAX`]; with `strict`,
/// functions over [`PY_STRICT_FN_MAX`] and classes over [`PY_CLASS_MAX`] (rule `py-strict`).
fn python_lengths(rel: &str, text: &str, strict: bool) -> Vec<Violation> {
    let mut out = Vec::new();
    for b in python_blocks(text) {
        let n = b.end + 1 - b.start;
        let (rule, max): (&'static str, usize) = match (b.kind, strict) {
            ("def", false) => ("fn-length", FN_MAX),
            ("def", true) => ("py-strict", PY_STRICT_FN_MAX),
            (_, true) => ("py-strict", PY_CLASS_MAX),
            _ => continue,
        };
        if n > max {
            out.push(v(
                rel,
                b.start,
                rule,
                format!(
                    "{} {} is {n} lines (at most {max}): split it",
                    b.kind, b.name
                ),
            ));
        }
    }
    if !strict {
        out.extend(file_length(rel, text));
    }
    out
}

// ---------------------------------------------------------------------------------------
// Rule: colour constants

/// The leading digits of the sRGB/XYZ constants (absolute values, as written without `_`):
/// a literal starting with one of them (and as long or longer) is one. The IEC 61966-2-1
/// 4-digit matrices and the 7-digit tabulated ones, the D65 white in XYZ, Bradford's
/// matrix and the sRGB transfer curve's knee, slope and scale.
const COLOUR: &[&str] = &[
    // linear sRGB -> XYZ (4 and 7 digits)
    "0.4124",
    "0.3576",
    "0.3575",
    "0.1805",
    "0.1804",
    "0.2126",
    "0.7152",
    "0.7151",
    "0.0722",
    "0.0721",
    "0.0193",
    "0.1192",
    "0.1191",
    "0.9505",
    "0.9503",
    // XYZ -> linear sRGB (4 and 7 digits, and the derived 3.2410 ...)
    "3.2406",
    "3.2404",
    "3.2410",
    "1.5372",
    "1.5371",
    "1.5374",
    "0.4986",
    "0.4985",
    "0.9689",
    "0.9692",
    "1.8758",
    "1.8760",
    "0.0557",
    "0.0556",
    "0.2040",
    "1.0570",
    "1.0572",
    // D65 white in XYZ
    "0.95047",
    "1.08883",
    "1.0888",
    // Bradford
    "0.8951",
    "0.2664",
    "0.1614",
    "0.7502",
    "1.7135",
    "0.0367",
    "0.0389",
    "0.0685",
    "1.0296",
    // the sRGB transfer curve
    "0.0031308",
    "0.04045",
    "12.92",
    "1.055",
];

/// A numeric literal's text normalized: no `_`, no type suffix, no sign.
fn normalize_number(s: &str) -> String {
    let s: String = s.chars().filter(|c| *c != '_').collect();
    let s = s
        .trim_end_matches("f32")
        .trim_end_matches("f64")
        .trim_start_matches('-');
    s.to_string()
}

fn is_colour_constant(lit: &str) -> bool {
    let n = normalize_number(lit);
    n.contains('.') && COLOUR.iter().any(|c| n.starts_with(c))
}

/// 2.4 as the sRGB curve's exponent: on a line raising to a power.
fn is_srgb_exponent(lit: &str, line: &str) -> bool {
    normalize_number(lit) == "2.4" && (line.contains("pow") || line.contains("**"))
}

fn colour_msg(lit: &str) -> String {
    format!("sRGB/XYZ constant {lit} outside src/color: use day2night::color (or the extension)")
}

/// sRGB/XYZ constants in Rust source (literals only: comments and docs are not code).
fn colour_rust(rel: &str, text: &str) -> Vec<Violation> {
    let lines: Vec<&str> = text.lines().collect();
    tokens(rel, text)
        .into_iter()
        .filter(|(t, _, lit)| *lit && t.starts_with(|c: char| c.is_ascii_digit()))
        .filter(|(t, line, _)| {
            is_colour_constant(t) || is_srgb_exponent(t, lines.get(line - 1).copied().unwrap_or(""))
        })
        .map(|(t, line, _)| v(rel, line, "colour", colour_msg(&t)))
        .collect()
}

/// Python source with its strings and comments blanked (same lines; a non-ASCII character
/// inside a string becomes one blank per byte).
fn python_code_only(text: &str) -> String {
    let mut out = Vec::with_capacity(text.len());
    let mut in_str: Option<Vec<u8>> = None;
    for line in text.split_inclusive('\n') {
        let b = line.as_bytes();
        let mut i = 0;
        while i < b.len() {
            if b[i] == b'\n' {
                out.push(b'\n');
                i += 1;
                continue;
            }
            if let Some(q) = &in_str {
                if b[i..].starts_with(q) {
                    out.extend(std::iter::repeat_n(b' ', q.len()));
                    i += q.len();
                    in_str = None;
                } else {
                    let n = if b[i] == b'\\' { 2.min(b.len() - i) } else { 1 };
                    let n = if b.get(i + 1) == Some(&b'\n') { 1 } else { n };
                    out.extend(std::iter::repeat_n(b' ', n));
                    i += n;
                }
                continue;
            }
            match b[i] {
                b'#' => {
                    let rest = b[i..].iter().take_while(|c| **c != b'\n').count();
                    out.extend(std::iter::repeat_n(b' ', rest));
                    i += rest;
                }
                q @ (b'"' | b'\'') => {
                    let n = if b[i..].starts_with(&[q, q, q]) { 3 } else { 1 };
                    in_str = Some(vec![q; n]);
                    out.extend(std::iter::repeat_n(b' ', n));
                    i += n;
                }
                c => {
                    out.push(c);
                    i += 1;
                }
            }
        }
        // a one-line string cannot run on past its line
        if in_str.as_ref().is_some_and(|q| q.len() == 1) {
            in_str = None;
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// sRGB/XYZ constants in Python source (code only).
fn colour_python(rel: &str, text: &str) -> Vec<Violation> {
    let code = python_code_only(text);
    let mut out = Vec::new();
    for (k, line) in code.lines().enumerate() {
        let b = line.as_bytes();
        let mut i = 0;
        while i < b.len() {
            let starts = b[i].is_ascii_digit()
                && (i == 0
                    || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_' || b[i - 1] == b'.'));
            if !starts {
                i += 1;
                continue;
            }
            let j = i + line[i..]
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '.' || c == '_'))
                .unwrap_or(line.len() - i);
            let lit = &line[i..j];
            if is_colour_constant(lit) || is_srgb_exponent(lit, line) {
                out.push(v(rel, k + 1, "colour", colour_msg(lit)));
            }
            i = j;
        }
    }
    out
}

// ---------------------------------------------------------------------------------------
// Rule: paths named in docs

/// Top-level folders of the repository: a word starting with one of them is a path.
const TOP: &[&str] = &[
    "src/",
    "tests/",
    "docs/",
    "python/",
    "scripts/",
    "benches/",
    "examples/",
    "fixtures/",
    "calibration/",
    "fuzz/",
    ".ci/",
    "proptest-regressions/",
];

/// The repository paths named in `text` (with their line): words starting with a top-level
/// folder; a word followed by a pattern character (`*`, `<`, `{`, `$`, `[`) is a pattern,
/// not a path.
fn named_paths(text: &str) -> Vec<(String, usize)> {
    let mut out = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let b = line.as_bytes();
        for (i, _) in line.char_indices() {
            let boundary = i == 0 || {
                let p = b[i - 1];
                !(p.is_ascii_alphanumeric() || matches!(p, b'_' | b'/' | b'.' | b'-' | b'~' | b'$'))
            };
            if !boundary || !TOP.iter().any(|t| line[i..].starts_with(t)) {
                continue;
            }
            let len = line[i..]
                .find(|c: char| !(c.is_ascii_alphanumeric() || "_./-".contains(c)))
                .unwrap_or(line.len() - i);
            let after = line[i + len..].chars().next().unwrap_or(' ');
            if "*<{$[".contains(after) {
                continue;
            }
            let p = line[i..i + len].trim_end_matches(['.', ',', ':', ';']);
            if p.contains("..") || p.contains("//") {
                continue;
            }
            out.push((p.to_string(), k + 1));
        }
    }
    out
}

/// Relative Markdown link targets (`[text](target)`) in `text`, with their line.
fn md_links(text: &str) -> Vec<(String, usize)> {
    let mut out = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let mut rest = line;
        while let Some(at) = rest.find("](") {
            let after = &rest[at + 2..];
            let Some(end) = after.find(')') else { break };
            let target = after[..end].split('#').next().unwrap_or("").trim();
            let target = target.split_whitespace().next().unwrap_or("");
            if !target.is_empty()
                && !target.contains("://")
                && !target.starts_with("mailto:")
                && !target.starts_with('<')
            {
                out.push((target.to_string(), k + 1));
            }
            rest = &after[end..];
        }
    }
    out
}

/// The doc text of a Rust file: its `///` and `//!` comments (other lines blanked, so the
/// line numbers hold).
fn rust_doc_text(text: &str) -> String {
    text.lines()
        .map(|l| {
            let t = l.trim_start();
            if t.starts_with("///") || t.starts_with("//!") {
                t
            } else {
                ""
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// Paths named in the doc text `text` of file `rel` (Markdown when `markdown`) that
/// `exists` says are not there.
fn doc_paths(
    rel: &str,
    text: &str,
    markdown: bool,
    exists: &dyn Fn(&str) -> bool,
) -> Vec<Violation> {
    let mut out = Vec::new();
    for (p, line) in named_paths(text) {
        if !exists(&p) {
            out.push(v(
                rel,
                line,
                "doc-path",
                format!("names {p}, which does not exist: fix the reference"),
            ));
        }
    }
    if markdown {
        let dir = rel.rsplit_once('/').map(|(d, _)| d).unwrap_or("");
        for (target, line) in md_links(text) {
            let mut parts: Vec<&str> = if dir.is_empty() {
                vec![]
            } else {
                dir.split('/').collect()
            };
            let mut outside = false;
            for seg in target.split('/') {
                match seg {
                    "" | "." => {}
                    ".." => outside |= parts.pop().is_none(),
                    s => parts.push(s),
                }
            }
            let resolved = parts.join("/");
            if !outside && !exists(&resolved) {
                out.push(v(
                    rel,
                    line,
                    "doc-path",
                    format!("links to {target} ({resolved}), which does not exist"),
                ));
            }
        }
    }
    out
}

fn exists_in_repo(p: &str) -> bool {
    root().join(p).exists()
}

/// The docs checked for paths: the Markdown of the root, docs/, python/ and tests/
/// (CHANGELOG.md is history: it names files that were since moved), and docs/*.txt.
fn doc_files() -> Vec<(String, bool)> {
    let mut out: Vec<(String, bool)> = ["README.md", "python/README.md", "tests/README.md"]
        .iter()
        .map(|s| (s.to_string(), true))
        .collect();
    out.extend(
        files("docs", ".md")
            .into_iter()
            .filter(|f| f.matches('/').count() == 1)
            .map(|f| (f, true)),
    );
    out.extend(
        files("docs", ".txt")
            .into_iter()
            .filter(|f| f.matches('/').count() == 1)
            .map(|f| (f, false)),
    );
    out
}

// ---------------------------------------------------------------------------------------
// The checks of the repository

/// The Rust files of the library, the binary and the extension.
fn rust_sources() -> Vec<String> {
    let mut v = files("src", ".rs");
    v.extend(files("python/src", ".rs"));
    v
}

fn is_cli(rel: &str) -> bool {
    rel.starts_with("src/cli/") || rel == "src/main.rs"
}

fn env_print_found() -> Vec<Violation> {
    let rels: Vec<String> = rust_sources();
    let texts: Vec<String> = rels.iter().map(|r| read(r)).collect();
    let tests = test_module_files(&rels, &texts);
    let mut found = Vec::new();
    for (rel, text) in rels.iter().zip(&texts) {
        if !is_cli(rel) {
            found.extend(env_and_print(rel, text, tests.contains(rel)));
        }
    }
    found
}

fn length_found() -> Vec<Violation> {
    let mut found = Vec::new();
    for rel in rust_sources() {
        found.extend(rust_lengths(&rel, &read(&rel)));
    }
    for rel in files("python/pysrc", ".py") {
        found.extend(python_lengths(&rel, &read(&rel), false));
    }
    found
}

fn colour_found() -> Vec<Violation> {
    let mut found = Vec::new();
    let mut rust: Vec<String> = rust_sources();
    rust.extend(files("examples", ".rs"));
    rust.extend(files("benches", ".rs"));
    for rel in rust.iter().filter(|r| !r.starts_with("src/color/")) {
        found.extend(colour_rust(rel, &read(rel)));
    }
    let mut py = files("python/pysrc", ".py");
    py.extend(files("python/examples", ".py"));
    py.extend(files("benches", ".py"));
    py.extend(files("examples", ".py"));
    py.extend(files("scripts", ".py"));
    for rel in &py {
        found.extend(colour_python(rel, &read(rel)));
    }
    found
}

fn doc_path_found() -> Vec<Violation> {
    let mut found = Vec::new();
    for (rel, md) in doc_files() {
        found.extend(doc_paths(&rel, &read(&rel), md, &exists_in_repo));
    }
    let mut rust = rust_sources();
    for d in ["tests", "benches", "examples"] {
        rust.extend(files(d, ".rs"));
    }
    rust.push("build.rs".into());
    for rel in &rust {
        found.extend(doc_paths(
            rel,
            &rust_doc_text(&read(rel)),
            false,
            &exists_in_repo,
        ));
    }
    found
}

#[test]
fn no_env_read_or_print_outside_the_cli() {
    assert_clean("env/print", env_print_found());
}

#[test]
fn functions_and_files_within_their_lengths() {
    assert_clean("length", length_found());
}

#[test]
fn python_package_within_its_stricter_limits() {
    let mut found = Vec::new();
    for rel in files("python/pysrc", ".py") {
        found.extend(python_lengths(&rel, &read(&rel), true));
    }
    if PY_STRICT {
        assert_clean("python/pysrc length", found);
    } else {
        // Listed, not enforced yet (PY_STRICT): `cargo test --test tidy -- --nocapture`.
        for x in &found {
            eprintln!("{x}");
        }
    }
}

#[test]
fn colour_constants_only_in_src_color() {
    assert_clean("colour", colour_found());
}

#[test]
fn paths_named_in_docs_exist() {
    assert_clean("doc-path", doc_path_found());
}

/// The Python sources of the package: (path, text).
fn pysrc() -> Vec<(String, String)> {
    files("python/pysrc", ".py")
        .into_iter()
        .map(|rel| {
            let text = read(&rel);
            (rel, text)
        })
        .collect()
}

fn import_found() -> Vec<Violation> {
    let py = pysrc();
    let mut found: Vec<Violation> = py
        .iter()
        .flat_map(|(rel, text)| imports::function_imports(rel, text))
        .collect();
    found.extend(imports::python_cycles(&py));
    for rel in files("python/src", ".rs") {
        found.extend(imports::positional_params(&rel, &read(&rel)));
    }
    found
}

#[test]
fn imports_at_the_top_no_cycle_and_parameters_by_name() {
    assert_clean("import graph", import_found());
}

#[test]
fn every_allowance_is_still_needed_and_has_a_reason() {
    let mut all = env_print_found();
    all.extend(length_found());
    all.extend(colour_found());
    all.extend(doc_path_found());
    all.extend(import_found());
    for (rule, file, reason) in ALLOW {
        assert!(!reason.trim().is_empty(), "{rule} {file}: no reason");
        assert!(
            all.iter().any(|x| x.rule == *rule && x.file == *file),
            "ALLOW ({rule}, {file}): nothing to allow any more: remove the entry"
        );
    }
}

// ---------------------------------------------------------------------------------------
// Each rule catches a planted violation

fn rules(found: &[Violation]) -> Vec<(usize, &'static str)> {
    found.iter().map(|x| (x.line, x.rule)).collect()
}

#[test]
fn planted_env_reads_are_caught_in_every_spelling() {
    let src = "\
use std::env;
use std::env::{self, var_os};
fn a() -> Option<String> {
    std::env::var(\"X\").ok()
}
fn b() { let _ = env::vars(); }
// env::var in a comment
fn c() -> &'static str { \"env::var in a string\" }
/// env::var(\"DOC\") in a doc comment
fn d() {}
";
    let found = env_and_print("src/x.rs", src, false);
    assert_eq!(
        rules(&found),
        [(2, "env"), (4, "env"), (6, "env")],
        "{found:#?}"
    );
    assert!(found[0].to_string().starts_with("src/x.rs:2: [env]"));
}

#[test]
fn planted_prints_are_caught_outside_test_code() {
    let src = "\
fn a() { println!(\"x\"); }
fn b() { let v = 1; dbg!(v); eprint!(\"y\"); }
fn c() { let _ = format!(\"println!(no)\"); }
#[cfg(test)]
mod tests {
    #[test]
    fn t() { println!(\"fine in a test\"); }
}
#[test]
fn top_level_test() { eprintln!(\"fine\"); }
#[cfg(all(test, unix))]
fn helper() { print!(\"fine\"); }
#[cfg(not(test))]
fn live() { eprintln!(\"caught\"); }
";
    let found = env_and_print("src/x.rs", src, false);
    assert_eq!(
        rules(&found),
        [(1, "print"), (2, "print"), (2, "print"), (14, "print")],
        "{found:#?}"
    );
    // a test module's own file: its prints are test code
    assert!(env_and_print("src/x/tests.rs", "fn t() { println!(); }", true).is_empty());
    // which files are test modules: the children declared under #[cfg(test)]
    let rels = vec![
        "src/a/mod.rs".to_string(),
        "src/a/tests.rs".to_string(),
        "src/a/tests/more.rs".to_string(),
        "src/a/live.rs".to_string(),
    ];
    let texts = vec![
        "#[cfg(test)]\nmod tests;\nmod live;\n".to_string(),
        "mod more;\n".to_string(),
        String::new(),
        String::new(),
    ];
    let t = test_module_files(&rels, &texts);
    assert!(t.contains("src/a/tests.rs") && t.contains("src/a/tests/more.rs"));
    assert!(!t.contains("src/a/live.rs") && !t.contains("src/a/mod.rs"));
}

#[test]
fn planted_long_functions_and_files_are_caught() {
    let body = "    let x = 1;\n".repeat(FN_MAX - 2);
    let ok = format!("fn fits() {{\n{body}}}\n");
    assert!(rust_lengths("src/x.rs", &ok).is_empty());
    let long = format!("fn fits() {{\n{body}}}\nimpl S {{\n    pub fn long(&self) {{\n{body}    let y = 2;\n    }}\n}}\n");
    let found = rust_lengths("src/x.rs", &long);
    let at = FN_MAX + 2;
    assert_eq!(rules(&found), [(at, "fn-length")], "{found:#?}");
    assert!(
        found[0].msg.contains("fn long is 151 lines"),
        "{}",
        found[0]
    );
    let big = "const A: u8 = 0;\n".repeat(FILE_MAX + 1);
    assert_eq!(
        rules(&rust_lengths("src/x.rs", &big)),
        [(FILE_MAX + 1, "file-length")]
    );

    // Python: a def ends at the next line as indented as it, not at a docstring's or a
    // bracket's lines; classes and the stricter limits
    let py_body = "    x = 1\n".repeat(FN_MAX - 4);
    let py = format!(
        "def fits(a,\nb):\n    \"\"\"Doc\nstring at column 0.\"\"\"\n{py_body}\n\n# comment\ndef long():\n    y = [\n1]\n{py_body}    z = 2\n    w = 3\nclass C:\n    def m(self):\n        pass\n"
    );
    let blocks = python_blocks(&py);
    assert_eq!(
        blocks
            .iter()
            .map(|b| (b.name.as_str(), b.end + 1 - b.start))
            .collect::<Vec<_>>(),
        [("fits", FN_MAX), ("long", FN_MAX + 1), ("C", 3), ("m", 2)],
        "{blocks:#?}"
    );
    let found = python_lengths("python/pysrc/x.py", &py, false);
    assert_eq!(rules(&found), [(FN_MAX + 4, "fn-length")], "{found:#?}");
    let strict = python_lengths("python/pysrc/x.py", &py, true);
    assert_eq!(strict.len(), 2, "{strict:#?}");
    assert!(strict.iter().all(|x| x.rule == "py-strict"));
    let class = format!("class Big:\n{}", "    a = 1\n".repeat(PY_CLASS_MAX));
    assert_eq!(
        rules(&python_lengths("p.py", &class, true)),
        [(1, "py-strict")]
    );
}

#[test]
fn planted_colour_constants_are_caught_in_code_only() {
    let rs = "\
const M: [f64; 3] = [0.4124564, 0.357_576_1, 0.1805];
fn oetf(x: f32) -> f32 {
    if x <= 0.003_130_8 { 12.92 * x } else { 1.055 * x.powf(1.0 / 2.4) - 0.055 }
}
/// 3.2406 in a doc comment, 2.4 on its own
fn other() -> f64 { let _ = \"0.2126\"; 2.4 * 0.41 }
fn m() -> f64 { -1.5372_f64 }
";
    let found = colour_rust("src/x.rs", rs);
    let lines: Vec<usize> = found.iter().map(|x| x.line).collect();
    assert_eq!(lines, [1, 1, 1, 3, 3, 3, 3, 7], "{found:#?}");
    let py = "\
M = [[0.4124564, 0.3575761, 0.1804375]]  # 0.2126 in a comment
s = '12.92 in a string'
lin = ((c + 0.055) / 1.055) ** 2.4
doc = \"\"\"
1.055
\"\"\"
x = 10.9505 + a0.9505
";
    let found = colour_python("python/pysrc/x.py", py);
    let lines: Vec<usize> = found.iter().map(|x| x.line).collect();
    assert_eq!(lines, [1, 1, 1, 3, 3], "{found:#?}");
}

#[test]
fn planted_missing_paths_are_caught() {
    let have: BTreeSet<&str> = ["docs/a.md", "docs", "src/x.rs", "README.md", "src/cli"]
        .into_iter()
        .collect();
    let exists = |p: &str| have.contains(p.trim_end_matches('/'));
    let md = "\
See docs/a.md, src/x.rs and src/cli/; not docs/gone.md.
Patterns are fine: tests/it/<topic>.rs, docs/*.md, src/{a,b}.rs, ../shared/data,
https://github.com/o/r/blob/main/src/none.rs.
[ok](a.md) [up](../README.md) [anchor](#x) [web](https://x.org/y) [bad](b.md#s)
";
    let found = doc_paths("docs/z.md", md, true, &exists);
    let msgs: Vec<String> = found.iter().map(|x| x.to_string()).collect();
    assert_eq!(
        msgs,
        [
            "docs/z.md:1: [doc-path] names docs/gone.md, which does not exist: fix the reference",
            "docs/z.md:4: [doc-path] links to b.md (docs/b.md), which does not exist",
        ]
    );
    let rs = "//! The table (tests/it/option_table.rs) and src/x.rs.\n// src/plain_comment.rs\nfn f() {}\n";
    let found = doc_paths("src/y.rs", &rust_doc_text(rs), false, &exists);
    assert_eq!(rules(&found), [(1, "doc-path")], "{found:#?}");
    assert!(found[0].msg.contains("tests/it/option_table.rs"));
}

#[test]
fn planted_function_imports_and_torch_imports_are_caught() {
    let text = "\"\"\"Doc.\n\n    import not_code\n\"\"\"\nimport os\n\ntry:\n    import numpy\nexcept ImportError:\n    numpy = None\n\n\ndef f():\n    x = \"import no\"  # import no\n    raise ValueError(x) \\\n        from None\n    from .b import (\n        c,\n        d,\n    )\n    return x\n\n\nclass K:\n    def m(self):\n        import json\n        return json\n\n\nimport torch.nn as nn\n";
    let found = imports::function_imports("python/pysrc/day2night/x.py", text);
    assert_eq!(
        rules(&found),
        vec![(17, "py-import"), (26, "py-import"), (30, "py-import")],
        "{found:#?}"
    );
    assert!(
        found[0].msg.contains("inside the function of line 13"),
        "{}",
        found[0].msg
    );
    assert!(found[2].msg.contains("_torch.py"), "{}", found[2].msg);
    // torch at the top of its one module is fine
    let home = "try:\n    import torch\nexcept ImportError:\n    torch = None\n";
    assert!(imports::function_imports(imports::TORCH_HOME, home).is_empty());
}

#[test]
fn a_planted_python_import_cycle_is_caught_and_named() {
    let f = |rel: &str, text: &str| (format!("python/pysrc/{rel}"), text.to_string());
    let ok = vec![
        f("p/__init__.py", "from . import a\nfrom ._native import x\n"),
        f("p/a.py", "from .sub import b\nimport p.sub.c\n"),
        f("p/sub/__init__.py", ""),
        f("p/sub/b.py", ""),
        f("p/sub/c.py", "from . import b\n"),
    ];
    assert!(
        imports::python_cycles(&ok).is_empty(),
        "{:#?}",
        imports::python_cycles(&ok)
    );
    let g = imports::python_graph(&ok);
    assert_eq!(g["p.a"].keys().collect::<Vec<_>>(), ["p.sub.b", "p.sub.c"]);
    assert_eq!(g["p.sub.c"].keys().collect::<Vec<_>>(), ["p.sub.b"]);
    // b imports a back, inside a function: still an edge, so a cycle
    let mut bad = ok.clone();
    bad[3] = f(
        "p/sub/b.py",
        "import os\n\n\ndef late():\n    from ..a import thing\n",
    );
    let found = imports::python_cycles(&bad);
    assert_eq!(rules(&found), vec![(1, "py-cycle")], "{found:#?}");
    assert_eq!(found[0].file, "python/pysrc/p/a.py");
    assert!(
        found[0].msg.contains("p.a -> p.sub.b (line 1)")
            && found[0].msg.contains("p.sub.b -> p.a (line 5)"),
        "{}",
        found[0].msg
    );
}

#[test]
fn planted_positional_parameter_reads_are_caught() {
    let text = "fn f(args: &A) -> PyResult<()> {\n    let (p, options) = args::bind_params(\"f\", PARAMS, args, None, true)?;\n    let seed = p[0].extract::<u64>()?;\n    let ok = p.get(\"seed\")?;\n    let (q, _) = args::bind_params(\"g\", &G_PARAMS[1..], args, None, false)?;\n    let v = other[0];\n    Ok(())\n}\n";
    let found = imports::positional_params("python/src/x.rs", text);
    assert_eq!(
        rules(&found),
        vec![(3, "pyo3-by-name"), (5, "pyo3-by-name")],
        "{found:#?}"
    );
}
