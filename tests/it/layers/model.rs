//! The module model the layering test checks: every non-test source file of a crate, what it
//! defines and re-exports at its top level, and every path it uses (with its line), parsed
//! with `syn` (comments, strings and macros' own syntax cannot fool it). Paths are resolved
//! to the file that defines the named item, following re-exports (`pub use`), so a file
//! depends on another exactly when it names something defined there.
use proc_macro2::{TokenStream, TokenTree};
use std::collections::{BTreeMap, BTreeSet};
use syn::visit::Visit;

/// One source file: its module path inside its crate and what it holds.
#[derive(Debug, Default)]
pub struct FileModel {
    /// Repository-relative path, e.g. `src/synth/job.rs`.
    pub path: String,
    /// Module path from the crate root (`[]` for `lib.rs`/`main.rs`).
    pub module: Vec<String>,
    /// Child modules declared here (`mod x;`), by name.
    pub children: BTreeSet<String>,
    /// Items defined at the top level (fn, struct, enum, trait, type, const, static, macro).
    pub defines: BTreeSet<String>,
    /// Top-level `pub use` re-exports: exported name -> the path it names (absolute).
    pub reexports: BTreeMap<String, Vec<String>>,
    /// Top-level `pub use path::*` re-exports (absolute module paths).
    pub globs: Vec<Vec<String>>,
    /// Every path used (absolute, from the crate root) with its 1-based line, re-exports of
    /// the file's own descendants excepted (they are the file's API, not a dependency).
    pub uses: Vec<(Vec<String>, usize)>,
}

fn has_cfg_test(attrs: &[syn::Attribute]) -> bool {
    attrs.iter().any(|a| {
        a.path().is_ident("cfg") && {
            let t = a.meta.to_token_stream_string();
            // #[cfg(test)] and #[cfg(all(test, ...))]; not #[cfg(not(test))]
            t.contains("test") && !t.contains("not")
        }
    })
}

trait MetaString {
    fn to_token_stream_string(&self) -> String;
}

impl MetaString for syn::Meta {
    fn to_token_stream_string(&self) -> String {
        match self {
            syn::Meta::List(l) => l.tokens.to_string(),
            _ => String::new(),
        }
    }
}

/// A `use` tree expanded into (path, exported name or None for a glob).
fn expand_use(
    tree: &syn::UseTree,
    prefix: &mut Vec<String>,
    out: &mut Vec<(Vec<String>, Option<String>)>,
) {
    match tree {
        syn::UseTree::Path(p) => {
            prefix.push(p.ident.to_string());
            expand_use(&p.tree, prefix, out);
            prefix.pop();
        }
        syn::UseTree::Name(n) => {
            let name = n.ident.to_string();
            if name == "self" {
                out.push((prefix.clone(), prefix.last().cloned()));
            } else {
                let mut p = prefix.clone();
                p.push(name.clone());
                out.push((p, Some(name)));
            }
        }
        syn::UseTree::Rename(r) => {
            let mut p = prefix.clone();
            if r.ident != "self" {
                p.push(r.ident.to_string());
            }
            out.push((p, Some(r.rename.to_string())));
        }
        syn::UseTree::Glob(_) => out.push((prefix.clone(), None)),
        syn::UseTree::Group(g) => {
            for t in &g.items {
                expand_use(t, prefix, out);
            }
        }
    }
}

/// Collects paths (with lines) from everything but `#[cfg(test)]` items.
struct PathCollector<'a> {
    file: &'a FileCtx,
    found: Vec<(Vec<String>, usize)>,
}

/// What resolving relative paths in one file needs.
pub struct FileCtx {
    /// The file's module path.
    pub module: Vec<String>,
    /// Its child modules.
    pub children: BTreeSet<String>,
    /// Local names brought in by `use` of a module (alias -> absolute module path), so that
    /// `alias::item` paths are seen too.
    pub module_aliases: BTreeMap<String, Vec<String>>,
}

impl FileCtx {
    /// The absolute path of `segs` as written in this file, if it is a path into the crate
    /// (`crate::`, `super::`, `self::`, a child module or a module alias); None for external
    /// crates, std, locals and prelude names.
    pub fn absolute(&self, segs: &[String]) -> Option<Vec<String>> {
        let first = segs.first()?;
        match first.as_str() {
            "crate" => Some(segs[1..].to_vec()),
            "self" => {
                let mut m = self.module.clone();
                m.extend_from_slice(&segs[1..]);
                Some(m)
            }
            "super" => {
                let mut m = self.module.clone();
                let mut rest = segs;
                while rest.first().map(|s| s == "super").unwrap_or(false) {
                    m.pop()?;
                    rest = &rest[1..];
                }
                m.extend_from_slice(rest);
                Some(m)
            }
            _ if self.children.contains(first) => {
                let mut m = self.module.clone();
                m.extend_from_slice(segs);
                Some(m)
            }
            _ => self.module_aliases.get(first).map(|abs| {
                let mut m = abs.clone();
                m.extend_from_slice(&segs[1..]);
                m
            }),
        }
    }
}

fn line_of(span: proc_macro2::Span) -> usize {
    span.start().line
}

impl<'ast> Visit<'ast> for PathCollector<'_> {
    fn visit_item(&mut self, i: &'ast syn::Item) {
        let attrs = match i {
            syn::Item::Mod(m) => &m.attrs,
            syn::Item::Fn(f) => &f.attrs,
            syn::Item::Impl(x) => &x.attrs,
            syn::Item::Use(u) => &u.attrs,
            syn::Item::Struct(s) => &s.attrs,
            syn::Item::Enum(e) => &e.attrs,
            syn::Item::Const(c) => &c.attrs,
            syn::Item::Static(s) => &s.attrs,
            syn::Item::Trait(t) => &t.attrs,
            syn::Item::Type(t) => &t.attrs,
            syn::Item::Macro(m) => &m.attrs,
            _ => return syn::visit::visit_item(self, i),
        };
        if has_cfg_test(attrs) {
            return;
        }
        // `use` statements are handled by the file walk (they need the re-export rule).
        if let syn::Item::Use(_) = i {
            return;
        }
        syn::visit::visit_item(self, i);
    }
    fn visit_impl_item_fn(&mut self, f: &'ast syn::ImplItemFn) {
        if !has_cfg_test(&f.attrs) {
            syn::visit::visit_impl_item_fn(self, f);
        }
    }
    fn visit_stmt(&mut self, s: &'ast syn::Stmt) {
        if let syn::Stmt::Item(syn::Item::Use(u)) = s {
            let mut out = Vec::new();
            expand_use(&u.tree, &mut Vec::new(), &mut out);
            for (p, _) in out {
                if let Some(abs) = self.file.absolute(&p) {
                    self.found.push((abs, line_of(u.use_token.span)));
                }
            }
            return;
        }
        syn::visit::visit_stmt(self, s);
    }
    fn visit_path(&mut self, p: &'ast syn::Path) {
        let segs: Vec<String> = p.segments.iter().map(|s| s.ident.to_string()).collect();
        if segs.len() > 1 {
            if let Some(abs) = self.file.absolute(&segs) {
                let line = p
                    .segments
                    .first()
                    .map(|s| line_of(s.ident.span()))
                    .unwrap_or(0);
                self.found.push((abs, line));
            }
        }
        syn::visit::visit_path(self, p);
    }
    fn visit_macro(&mut self, m: &'ast syn::Macro) {
        self.visit_path(&m.path);
        self.scan_tokens(m.tokens.clone());
    }
}

impl PathCollector<'_> {
    /// Paths inside macro arguments (`format!("{}", crate::VERSION)`): runs of
    /// `ident :: ident :: ...` starting at `crate`, `super`, `self` or a child module.
    fn scan_tokens(&mut self, ts: TokenStream) {
        let toks: Vec<TokenTree> = ts.into_iter().collect();
        let mut i = 0;
        while i < toks.len() {
            if let TokenTree::Group(g) = &toks[i] {
                self.scan_tokens(g.stream());
                i += 1;
                continue;
            }
            if let TokenTree::Ident(id) = &toks[i] {
                let mut segs = vec![id.to_string()];
                let line = line_of(id.span());
                let mut j = i + 1;
                while j + 2 < toks.len() + 1 {
                    let colons = matches!((toks.get(j), toks.get(j + 1)),
                        (Some(TokenTree::Punct(a)), Some(TokenTree::Punct(b))) if a.as_char() == ':' && b.as_char() == ':');
                    match (colons, toks.get(j + 2)) {
                        (true, Some(TokenTree::Ident(n))) => {
                            segs.push(n.to_string());
                            j += 3;
                        }
                        _ => break,
                    }
                }
                if segs.len() > 1 {
                    if let Some(abs) = self.file.absolute(&segs) {
                        self.found.push((abs, line));
                    }
                }
                i = j.max(i + 1);
                continue;
            }
            i += 1;
        }
    }
}

fn item_name(item: &syn::Item) -> Option<String> {
    Some(match item {
        syn::Item::Fn(f) => f.sig.ident.to_string(),
        syn::Item::Struct(s) => s.ident.to_string(),
        syn::Item::Enum(e) => e.ident.to_string(),
        syn::Item::Trait(t) => t.ident.to_string(),
        syn::Item::Type(t) => t.ident.to_string(),
        syn::Item::Const(c) => c.ident.to_string(),
        syn::Item::Static(s) => s.ident.to_string(),
        syn::Item::Union(u) => u.ident.to_string(),
        syn::Item::Macro(m) => m.ident.as_ref()?.to_string(),
        _ => return None,
    })
}

fn item_attrs(item: &syn::Item) -> &[syn::Attribute] {
    match item {
        syn::Item::Fn(f) => &f.attrs,
        syn::Item::Struct(s) => &s.attrs,
        syn::Item::Enum(e) => &e.attrs,
        syn::Item::Trait(t) => &t.attrs,
        syn::Item::Type(t) => &t.attrs,
        syn::Item::Const(c) => &c.attrs,
        syn::Item::Static(s) => &s.attrs,
        syn::Item::Union(u) => &u.attrs,
        syn::Item::Macro(m) => &m.attrs,
        syn::Item::Mod(m) => &m.attrs,
        syn::Item::Use(u) => &u.attrs,
        syn::Item::Impl(i) => &i.attrs,
        _ => &[],
    }
}

/// Parse one file. `module` is its module path; the file's `#[cfg(test)]` items are left
/// out, and child modules declared under `#[cfg(test)]` are returned in `test_children` so
/// that their files are skipped.
pub fn parse_file(
    path: &str,
    module: Vec<String>,
    text: &str,
    test_children: &mut BTreeSet<String>,
) -> Result<FileModel, String> {
    let ast = syn::parse_file(text).map_err(|e| format!("{path}: {e}"))?;
    let mut m = FileModel {
        path: path.to_string(),
        module: module.clone(),
        ..FileModel::default()
    };
    let mut uses = Vec::new();
    for item in &ast.items {
        let test = has_cfg_test(item_attrs(item));
        match item {
            syn::Item::Mod(md) if md.content.is_none() => {
                if test {
                    test_children.insert(md.ident.to_string());
                } else {
                    m.children.insert(md.ident.to_string());
                }
            }
            syn::Item::Use(u) if !test => uses.push(u),
            _ if test => {}
            _ => {
                if let Some(n) = item_name(item) {
                    m.defines.insert(n);
                }
            }
        }
    }
    let mut ctx = FileCtx {
        module: module.clone(),
        children: m.children.clone(),
        module_aliases: BTreeMap::new(),
    };
    // `use` statements: imports (edges) and re-exports (name resolution).
    let mut expanded = Vec::new();
    for u in &uses {
        let mut out = Vec::new();
        expand_use(&u.tree, &mut Vec::new(), &mut out);
        let public = !matches!(u.vis, syn::Visibility::Inherited);
        for (p, name) in out {
            expanded.push((p, name, public, line_of(u.use_token.span)));
        }
    }
    for (p, name, _, _) in &expanded {
        // a name imported (`use super::sidecar;`, `use crate::isp::opcodes as ops;`) can
        // start later paths (`sidecar::Sidecar::read`)
        if let (Some(abs), Some(name)) = (ctx.absolute(p), name) {
            ctx.module_aliases.entry(name.clone()).or_insert(abs);
        }
    }
    for (p, name, public, line) in expanded {
        let Some(abs) = ctx.absolute(&p) else {
            continue;
        };
        if public {
            match &name {
                Some(n) => {
                    m.reexports.insert(n.clone(), abs.clone());
                }
                None => m.globs.push(abs.clone()),
            }
            // re-exporting one's own descendants is API, not a dependency
            if abs.len() > module.len() && abs[..module.len()] == module[..] {
                continue;
            }
        }
        m.uses.push((abs, line));
    }
    let mut pc = PathCollector {
        file: &ctx,
        found: Vec::new(),
    };
    for item in &ast.items {
        if !matches!(item, syn::Item::Use(_)) {
            pc.visit_item(item);
        }
    }
    m.uses.extend(pc.found);
    Ok(m)
}
