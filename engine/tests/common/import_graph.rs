//! The import graph between the files of a crate's `src/`, read from its
//! source: an edge `a → b` when file `a` names a path into module `b`
//! (`use crate::b::…`, `crate::b::f(…)`, `use super::b`, `b::f` after
//! `use crate::b`…). Comments, strings' `//` and `#[cfg(test)]` modules are
//! left out: only what the library itself compiles counts. Shared by the
//! engine's and the systems' import tests (issue 28: no import circles).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Module path (`["kinematics"]`, `["kernels", "legs_x4"]`; `[]` the crate
/// root) of every `.rs` file under `src`.
fn modules(src: &Path) -> BTreeMap<Vec<String>, PathBuf> {
    let mut out = BTreeMap::new();
    let mut stack = vec![src.to_path_buf()];
    while let Some(dir) = stack.pop() {
        let mut entries: Vec<_> = std::fs::read_dir(&dir)
            .expect("read src dir")
            .map(|e| e.expect("dir entry").path())
            .collect();
        entries.sort();
        for p in entries {
            if p.is_dir() {
                stack.push(p);
                continue;
            }
            if p.extension().and_then(|e| e.to_str()) != Some("rs") {
                continue;
            }
            let rel = p.strip_prefix(src).expect("under src");
            let mut parts: Vec<String> = rel
                .iter()
                .map(|c| c.to_string_lossy().into_owned())
                .collect();
            let last = parts.pop().expect("file name");
            let stem = last.trim_end_matches(".rs").to_string();
            if !(stem == "mod" || (parts.is_empty() && (stem == "lib" || stem == "main"))) {
                parts.push(stem);
            }
            out.insert(parts, p);
        }
    }
    out
}

/// `text` without comments, string literals' contents and the bodies of
/// `#[cfg(test)]` items (which only `cargo test` compiles).
fn code_only(text: &str) -> String {
    let b = text.as_bytes();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < b.len() {
        if b[i..].starts_with(b"//") {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
        } else if b[i..].starts_with(b"/*") {
            i += 2;
            while i < b.len() && !b[i..].starts_with(b"*/") {
                i += 1;
            }
            i += 2;
        } else if b[i] == b'"' {
            i += 1;
            while i < b.len() && b[i] != b'"' {
                if b[i] == b'\\' {
                    i += 1;
                }
                i += 1;
            }
            i += 1;
            out.push_str("\"\"");
        } else if b[i] == b'\'' && i + 2 < b.len() && (b[i + 2] == b'\'' || b[i + 1] == b'\\') {
            // a char literal ('"', '\n'); lifetimes ('a) pass through
            i += 1;
            while i < b.len() && b[i] != b'\'' {
                if b[i] == b'\\' {
                    i += 1;
                }
                i += 1;
            }
            i += 1;
            out.push_str("' '");
        } else {
            let c = text[i..].chars().next().expect("char");
            out.push(c);
            i += c.len_utf8();
        }
    }
    strip_test_items(&out)
}

/// Drops every item after a `#[cfg(test)]` or `#[cfg(all(test, …))]`
/// attribute up to its matching closing brace (or semicolon).
fn strip_test_items(code: &str) -> String {
    let mut out = String::with_capacity(code.len());
    let mut rest = code;
    loop {
        let at = ["#[cfg(test)]", "#[cfg(all(test"]
            .iter()
            .filter_map(|m| rest.find(m))
            .min();
        let Some(at) = at else {
            out.push_str(rest);
            return out;
        };
        out.push_str(&rest[..at]);
        let item = &rest[at..];
        let mut depth = 0usize;
        let mut end = item.len();
        // skip the attribute's own brackets first
        let attr_end = item.find(']').map_or(item.len(), |e| e + 1);
        for (k, c) in item[attr_end..].char_indices() {
            match c {
                '{' => depth += 1,
                '}' => {
                    depth -= 1;
                    if depth == 0 {
                        end = attr_end + k + 1;
                        break;
                    }
                }
                ';' if depth == 0 => {
                    end = attr_end + k + 1;
                    break;
                }
                _ => {}
            }
        }
        rest = &item[end..];
    }
}

/// Every path a file names that starts with `crate`, `super`, `self` or
/// one of `children` (its own submodules), as written
/// (`crate::a::b::{c, d::e}` gives `crate::a::b::c` and `crate::a::b::d::e`,
/// a child's path `self::child::…`), each with whether it is a re-export
/// (`pub use`).
fn paths(code: &str, children: &BTreeSet<String>) -> Vec<(Vec<String>, bool)> {
    let words: Vec<&str> = tokenize(code);
    let mut out = Vec::new();
    let mut i = 0;
    while i < words.len() {
        let w = words[i];
        let prev = if i > 0 { words[i - 1] } else { "" };
        let starts = (w == "crate" || w == "super" || w == "self")
            || (children.contains(w) && words.get(i + 1) == Some(&"::"));
        if starts && prev != "::" && prev != "(" && prev != "mod" {
            let reexport = prev == "use" && {
                let before = &words[..i - 1];
                before.last() == Some(&"pub") || before.ends_with(&["pub", "(", "crate", ")"])
            };
            let (found, next) = parse_path(&words, i);
            for mut p in found {
                if children.contains(w) {
                    p.insert(0, "self".into());
                }
                out.push((p, reexport));
            }
            i = next.max(i + 1);
        } else {
            i += 1;
        }
    }
    out
}

/// Splits `code` into identifiers and punctuation (`::` kept whole).
fn tokenize(code: &str) -> Vec<&str> {
    let mut out = Vec::new();
    let b = code.as_bytes();
    let mut i = 0;
    while i < b.len() {
        let c = b[i] as char;
        if c.is_ascii_alphanumeric() || c == '_' {
            let s = i;
            while i < b.len() && ((b[i] as char).is_ascii_alphanumeric() || b[i] == b'_') {
                i += 1;
            }
            out.push(&code[s..i]);
        } else if b[i..].starts_with(b"::") {
            out.push("::");
            i += 2;
        } else if c.is_ascii_whitespace() || !c.is_ascii() {
            i += code[i..].chars().next().map_or(1, char::len_utf8);
        } else {
            out.push(&code[i..i + 1]);
            i += 1;
        }
    }
    out
}

/// The paths of a (possibly grouped) path expression starting at `words[i]`.
fn parse_path(words: &[&str], mut i: usize) -> (Vec<Vec<String>>, usize) {
    let mut prefix = Vec::new();
    loop {
        prefix.push(words[i].to_string());
        if words.get(i + 1) != Some(&"::") {
            return (vec![prefix], i + 1);
        }
        i += 2;
        match words.get(i) {
            Some(&"{") => {
                let mut out = Vec::new();
                i += 1;
                loop {
                    match words.get(i) {
                        None => return (out, i),
                        Some(&"}") => return (out, i + 1),
                        Some(&",") => i += 1,
                        Some(&"*") => {
                            out.push(prefix.clone());
                            i += 1;
                        }
                        Some(_) => {
                            let (sub, next) = parse_path(words, i);
                            for s in sub {
                                let mut p = prefix.clone();
                                p.extend(s);
                                out.push(p);
                            }
                            i = next;
                            // `as alias`
                            if words.get(i) == Some(&"as") {
                                i += 2;
                            }
                        }
                    }
                }
            }
            Some(&"*") => return (vec![prefix], i + 1),
            Some(w) if w.chars().all(|c| c.is_alphanumeric() || c == '_') => {}
            _ => return (vec![prefix], i),
        }
    }
}

/// `p` (as written in module `m`) as an absolute module path, or `None`.
fn absolute(m: &[String], p: &[String]) -> Option<Vec<String>> {
    let mut abs: Vec<String> = Vec::new();
    let mut rest = p;
    match rest.first().map(String::as_str) {
        Some("crate") => rest = &rest[1..],
        Some("self") => {
            abs = m.to_vec();
            rest = &rest[1..];
        }
        Some("super") => {
            abs = m.to_vec();
            while rest.first().map(String::as_str) == Some("super") {
                abs.pop();
                rest = &rest[1..];
            }
        }
        _ => return None,
    }
    abs.extend(rest.iter().cloned());
    Some(abs)
}

/// The file graph of the crate at `src`: for each module, the modules whose
/// files it names. A name a module re-exports (`pub use`) counts as the
/// file that defines it, and a module's own re-exports of its descendants
/// (a façade) are no edge.
pub fn file_graph(src: &Path) -> BTreeMap<String, BTreeSet<String>> {
    let mods = modules(src);
    let children = |m: &Vec<String>| -> BTreeSet<String> {
        mods.keys()
            .filter(|k| k.len() == m.len() + 1 && k.starts_with(m))
            .map(|k| k[m.len()].clone())
            .collect()
    };
    let mut all: BTreeMap<Vec<String>, Vec<(Vec<String>, bool)>> = BTreeMap::new();
    let mut reexports: BTreeMap<(Vec<String>, String), Vec<String>> = BTreeMap::new();
    for (m, file) in &mods {
        let code = code_only(&std::fs::read_to_string(file).expect("read source"));
        let mut list = Vec::new();
        for (p, re) in paths(&code, &children(m)) {
            if let Some(abs) = absolute(m, &p) {
                if re && let Some(last) = abs.last() {
                    reexports.insert((m.clone(), last.clone()), abs.clone());
                }
                list.push((abs, re));
            }
        }
        all.insert(m.clone(), list);
    }
    // the file that defines the item at `abs`, following re-exports
    let resolve = |abs: &Vec<String>| -> Option<Vec<String>> {
        let mut abs = abs.clone();
        for _ in 0..8 {
            let k = (0..=abs.len())
                .rev()
                .find(|&k| mods.contains_key(&abs[..k]))?;
            let t = abs[..k].to_vec();
            match abs
                .get(k)
                .and_then(|n| reexports.get(&(t.clone(), n.clone())))
            {
                Some(to) if to != &abs => {
                    let mut next = to.clone();
                    next.extend(abs[k + 1..].iter().cloned());
                    abs = next;
                }
                _ => return Some(t),
            }
        }
        None
    };
    let mut graph = BTreeMap::new();
    for (m, list) in &all {
        let mut deps = BTreeSet::new();
        for (abs, re) in list {
            if *re && abs.starts_with(m) {
                continue;
            }
            if let Some(t) = resolve(abs)
                && &t != m
            {
                deps.insert(name(&t));
            }
        }
        graph.insert(name(m), deps);
    }
    graph
}

/// A module path as `a::b` (`crate` for the root).
fn name(m: &[String]) -> String {
    if m.is_empty() {
        "crate".into()
    } else {
        m.join("::")
    }
}

/// Every circle of `graph`, as the strongly connected components of more
/// than one file (Tarjan's algorithm), each sorted.
pub fn circles(graph: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
    struct T<'g> {
        g: &'g BTreeMap<String, BTreeSet<String>>,
        index: BTreeMap<&'g str, usize>,
        low: BTreeMap<&'g str, usize>,
        stack: Vec<&'g str>,
        on: BTreeSet<&'g str>,
        next: usize,
        out: Vec<Vec<String>>,
    }
    fn visit<'g>(t: &mut T<'g>, v: &'g str) {
        t.index.insert(v, t.next);
        t.low.insert(v, t.next);
        t.next += 1;
        t.stack.push(v);
        t.on.insert(v);
        let g = t.g;
        for w in g.get(v).into_iter().flatten() {
            let w = w.as_str();
            if !g.contains_key(w) {
                continue;
            }
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
            loop {
                let w = t.stack.pop().expect("on stack");
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
        g: graph,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on: BTreeSet::new(),
        next: 0,
        out: Vec::new(),
    };
    for v in graph.keys() {
        if !t.index.contains_key(v.as_str()) {
            visit(&mut t, v);
        }
    }
    t.out
}
