//! The root crate's files import each other without circles, and nothing
//! outside `cli/` imports from `cli/` (issue 28, item 5): the app layer
//! (run, report, log, studies) stands on its own under a thin CLI.
//!
//! The graph is read from the sources: every `crate::…`, `super::…` and
//! `self::…` path (in `use` trees and inline) and every path through a
//! child module declared with `mod x;`, resolved to the longest module path
//! that is a file. Comments and `#[cfg(test)]` modules are skipped; glob
//! imports (`use super::*`) name no file and are skipped too.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// A module path (`["study", "output"]`); the crate root is empty.
type Module = Vec<String>;

/// Source text without `//` comments (doc comments included) and `/* */` blocks.
fn strip_comments(src: &str) -> String {
    let mut out = String::with_capacity(src.len());
    let b = src.as_bytes();
    let (mut i, mut in_str) = (0, false);
    while i < b.len() {
        let c = b[i];
        if in_str {
            out.push(c as char);
            if c == b'\\' && i + 1 < b.len() {
                out.push(b[i + 1] as char);
                i += 2;
                continue;
            }
            if c == b'"' {
                in_str = false;
            }
            i += 1;
        } else if c == b'"' {
            in_str = true;
            out.push('"');
            i += 1;
        } else if c == b'/' && b.get(i + 1) == Some(&b'/') {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
        } else if c == b'/' && b.get(i + 1) == Some(&b'*') {
            i += 2;
            while i + 1 < b.len() && !(b[i] == b'*' && b[i + 1] == b'/') {
                i += 1;
            }
            i += 2;
        } else if c == b'\'' && b.get(i + 2) == Some(&b'\'') {
            // a char literal such as '"'
            out.push_str("' '");
            i += 3;
        } else {
            out.push(c as char);
            i += 1;
        }
    }
    out
}

fn is_ident(c: u8) -> bool {
    c.is_ascii_alphanumeric() || c == b'_'
}

/// Every full path of the use tree or path starting at byte `i` (just after
/// a leading `crate::`, `super::`, `self::` or `x::`), each with `prefix`.
fn paths_at(b: &[u8], mut i: usize, prefix: Vec<String>, out: &mut Vec<Vec<String>>) -> usize {
    let mut path = prefix;
    loop {
        if b.get(i) == Some(&b'{') {
            // a group: `a::{b, c::{d, e}}`
            i += 1;
            loop {
                while i < b.len() && (b[i] as char).is_whitespace() {
                    i += 1;
                }
                if i >= b.len() || b[i] == b'}' {
                    return i + 1;
                }
                if is_ident(b[i]) || b[i] == b'{' {
                    i = paths_at(b, i, path.clone(), out);
                } else {
                    i += 1; // `,` and `*`
                }
            }
        }
        let s = i;
        while i < b.len() && is_ident(b[i]) {
            i += 1;
        }
        if i == s {
            return i; // a glob (`super::*`) names no file
        }
        path.push(String::from_utf8_lossy(&b[s..i]).into_owned());
        if b[i..].starts_with(b"::") {
            i += 2;
            continue;
        }
        out.push(path);
        return i;
    }
}

/// The files' import graph: module → modules it imports from.
fn graph_of(files: &BTreeMap<Module, (bool, String)>) -> BTreeMap<Module, BTreeSet<Module>> {
    let resolve = |path: &[String]| -> Option<Module> {
        (0..=path.len())
            .rev()
            .map(|n| path[..n].to_vec())
            .find(|m| files.contains_key(m))
    };
    let mut edges: BTreeMap<Module, BTreeSet<Module>> = BTreeMap::new();
    for (module, (_is_dir_root, text)) in files {
        // test modules (at the end of a file, by convention) are not part
        // of the structure: their `super::` is the file itself
        let text = text.split("#[cfg(test)]").next().unwrap_or_default();
        let src = strip_comments(text);
        let b = src.as_bytes();
        let parent: Module = module[..module.len().saturating_sub(1)].to_vec();
        // child modules declared here (`mod x;`)
        let kids: BTreeSet<String> = src
            .split(';')
            .filter_map(|s| {
                let t = s.trim_start();
                let t = t.strip_prefix("pub ").unwrap_or(t).trim_start();
                let t = t.strip_prefix("pub(crate) ").unwrap_or(t).trim_start();
                t.strip_prefix("mod ")
                    .map(str::trim)
                    .filter(|n| n.bytes().all(is_ident))
                    .map(str::to_string)
            })
            .collect();
        let mut paths = Vec::new();
        let mut i = 0;
        while i < b.len() {
            let boundary = i == 0 || !(is_ident(b[i - 1]) || b[i - 1] == b':');
            if !boundary || !is_ident(b[i]) {
                i += 1;
                continue;
            }
            let s = i;
            while i < b.len() && is_ident(b[i]) {
                i += 1;
            }
            if !b[i..].starts_with(b"::") {
                continue;
            }
            let word = std::str::from_utf8(&b[s..i]).unwrap();
            let base: Module = match word {
                "crate" => Vec::new(),
                "super" => parent.clone(),
                "self" => module.clone(),
                k if kids.contains(k) => {
                    let mut m = module.clone();
                    m.push(k.to_string());
                    m
                }
                _ => continue,
            };
            i = paths_at(b, i + 2, base, &mut paths);
        }
        for p in paths {
            if let Some(t) = resolve(&p)
                && &t != module
                && !t.is_empty()
            {
                edges.entry(module.clone()).or_default().insert(t);
            }
        }
    }
    edges
}

/// A circle of the graph, if it has one (as the modules along it).
fn find_cycle(edges: &BTreeMap<Module, BTreeSet<Module>>) -> Option<Vec<Module>> {
    #[derive(Clone, Copy, PartialEq)]
    enum Mark {
        Open,
        Done,
    }
    fn visit(
        m: &Module,
        edges: &BTreeMap<Module, BTreeSet<Module>>,
        marks: &mut BTreeMap<Module, Mark>,
        stack: &mut Vec<Module>,
    ) -> Option<Vec<Module>> {
        match marks.get(m) {
            Some(Mark::Done) => return None,
            Some(Mark::Open) => {
                let at = stack.iter().position(|s| s == m).unwrap();
                let mut c = stack[at..].to_vec();
                c.push(m.clone());
                return Some(c);
            }
            None => {}
        }
        marks.insert(m.clone(), Mark::Open);
        stack.push(m.clone());
        for t in edges.get(m).into_iter().flatten() {
            if let Some(c) = visit(t, edges, marks, stack) {
                return Some(c);
            }
        }
        stack.pop();
        marks.insert(m.clone(), Mark::Done);
        None
    }
    let mut marks = BTreeMap::new();
    for m in edges.keys() {
        if let Some(c) = visit(m, edges, &mut marks, &mut Vec::new()) {
            return Some(c);
        }
    }
    None
}

/// Imports from outside `cli/` into `cli/`.
fn upward(edges: &BTreeMap<Module, BTreeSet<Module>>) -> Vec<(Module, Module)> {
    let in_cli = |m: &Module| m.first().is_some_and(|s| s == "cli");
    edges
        .iter()
        .filter(|(from, _)| !in_cli(from))
        .flat_map(|(from, to)| {
            to.iter()
                .filter(|t| in_cli(t))
                .map(move |t| (from.clone(), t.clone()))
        })
        .collect()
}

/// Every `.rs` file under `dir` (but the binary's `main.rs`) by module path.
fn crate_files(dir: &Path) -> BTreeMap<Module, (bool, String)> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push(p);
            }
        }
    }
    let mut paths = Vec::new();
    walk(dir, &mut paths);
    let mut files = BTreeMap::new();
    for p in paths {
        let rel = p.strip_prefix(dir).unwrap().with_extension("");
        let mut m: Module = rel
            .components()
            .map(|c| c.as_os_str().to_string_lossy().into_owned())
            .collect();
        if m == ["main"] {
            continue;
        }
        let dir_root = matches!(m.last().map(String::as_str), Some("mod" | "lib"));
        if dir_root {
            m.pop();
        }
        files.insert(m, (dir_root, std::fs::read_to_string(&p).unwrap()));
    }
    files
}

fn show(m: &Module) -> String {
    if m.is_empty() {
        "crate".into()
    } else {
        m.join("::")
    }
}

#[test]
fn the_root_crate_has_no_import_circles_and_nothing_imports_from_cli() {
    let files = crate_files(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"));
    assert!(files.len() > 50, "{} files read", files.len());
    let edges = graph_of(&files);
    assert!(
        edges.values().map(BTreeSet::len).sum::<usize>() > 100,
        "the graph is implausibly small"
    );
    if let Some(c) = find_cycle(&edges) {
        panic!(
            "import circle: {}",
            c.iter().map(show).collect::<Vec<_>>().join(" -> ")
        );
    }
    let up = upward(&edges);
    assert!(
        up.is_empty(),
        "imports into cli/ from outside it: {}",
        up.iter()
            .map(|(a, b)| format!("{} -> {}", show(a), show(b)))
            .collect::<Vec<_>>()
            .join(", ")
    );
}

/// The checker itself finds what it looks for: a circle through a parent's
/// `mod.rs` and a child's `super::`, a circle through a use group, and an
/// import into `cli/`.
#[test]
fn the_checker_finds_circles_and_imports_into_cli() {
    let file = |m: &[&str], text: &str| {
        (
            m.iter().map(|s| s.to_string()).collect::<Module>(),
            (false, text.to_string()),
        )
    };
    let files: BTreeMap<_, _> = [
        file(&[], "pub mod a;\npub mod cli;\npub mod log;"),
        file(&["a"], "pub mod b;\npub use b::Thing;\npub struct Top;"),
        // `super::Top` is `a`'s mod.rs: a -> a::b -> a
        file(&["a", "b"], "use super::Top;\npub struct Thing;"),
        file(&["cli"], "pub mod run;"),
        file(&["cli", "run"], "pub const V: u32 = 1;"),
        // an upward import, inline, after a comment naming crate::a
        file(
            &["log"],
            "// crate::a::b\nfn f() -> u32 { crate::cli::run::V }",
        ),
    ]
    .into_iter()
    .collect();
    let edges = graph_of(&files);
    let c = find_cycle(&edges).expect("the circle a -> a::b -> a");
    assert_eq!(c.len(), 3, "{c:?}");
    assert_eq!(
        upward(&edges),
        vec![(vec!["log".to_string()], vec!["cli".into(), "run".into()])]
    );
    assert!(!edges[&vec!["log".to_string()]].contains(&vec!["a".to_string(), "b".into()]));
    // a group import closes a circle too
    let files: BTreeMap<_, _> = [
        file(&["x"], "use crate::{y::{Y, Z}, w};"),
        file(&["y"], "use crate::x::X;"),
    ]
    .into_iter()
    .collect();
    assert!(find_cycle(&graph_of(&files)).is_some());
}
