//! No import circles between the engine's files (issue 28): the file graph
//! read from `use crate::…`/`super::…` paths (tests/common/import_graph.rs)
//! is acyclic.

#[path = "common/import_graph.rs"]
mod import_graph;

use std::path::Path;

#[test]
fn engine_files_import_each_other_in_no_circle() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let graph = import_graph::file_graph(&src);
    assert!(graph.len() > 50, "read the engine's files: {}", graph.len());
    let circles = import_graph::circles(&graph);
    for c in &circles {
        eprintln!("circle of {} files: {}", c.len(), c.join(", "));
        for f in c {
            let inside: Vec<_> = graph[f].iter().filter(|d| c.contains(d)).collect();
            eprintln!("  {f} -> {inside:?}");
        }
    }
    assert!(circles.is_empty(), "{} import circles", circles.len());
}

/// Study B's validation code lives in `validation/` (quadsim-validation),
/// beside the tests, not in the engine's core: the engine neither depends on
/// that crate (so it cannot import it: Cargo has no dependency cycles) nor
/// names it, and the Study B files are no longer among its sources.
#[test]
fn engine_does_not_import_the_validation_crate() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let manifest = std::fs::read_to_string(root.join("Cargo.toml")).unwrap();
    assert!(
        !manifest.contains("quadsim-validation") && !manifest.contains("quadsim_validation"),
        "engine/Cargo.toml names the validation crate"
    );
    let graph = import_graph::file_graph(&root.join("src"));
    assert!(
        !graph.keys().any(|f| f.contains("study_b")),
        "Study B's files are back in the engine: {:?}",
        graph
            .keys()
            .filter(|f| f.contains("study_b"))
            .collect::<Vec<_>>()
    );
    let mut stack = vec![root.join("src")];
    while let Some(dir) = stack.pop() {
        for e in std::fs::read_dir(&dir).unwrap() {
            let path = e.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|x| x == "rs") {
                let text = std::fs::read_to_string(&path).unwrap();
                assert!(
                    !text.contains("quadsim_validation"),
                    "{} names the validation crate",
                    path.display()
                );
            }
        }
    }
}

/// The reader itself: a small crate with a known circle and a known
/// acyclic rest, so that the test above could fail.
#[test]
fn the_reader_finds_a_planted_circle() {
    let dir = std::env::temp_dir().join(format!("quadsim-import-graph-{}", std::process::id()));
    let src = dir.join("src");
    std::fs::create_dir_all(src.join("k")).unwrap();
    std::fs::write(
        src.join("lib.rs"),
        "pub mod a;\npub mod b;\npub mod c;\npub mod k;\npub use a::A;\n",
    )
    .unwrap();
    std::fs::write(
        src.join("a.rs"),
        "use crate::b::B; // crate::c in a comment\npub struct A;\n",
    )
    .unwrap();
    std::fs::write(
        src.join("b.rs"),
        "pub struct B;\npub fn f() -> crate::A { crate::A }\n",
    )
    .unwrap();
    std::fs::write(
        src.join("c.rs"),
        "use crate::{a::A, k::{K, j}};\n#[cfg(test)]\nmod tests { use crate::c; }\n",
    )
    .unwrap();
    std::fs::write(src.join("k/mod.rs"), "mod j;\npub use j::K;\n").unwrap();
    std::fs::write(
        src.join("k/j.rs"),
        "pub struct K;\nconst S: &str = \"crate::c\";\n",
    )
    .unwrap();
    let graph = import_graph::file_graph(&src);
    std::fs::remove_dir_all(&dir).ok();
    let deps = |m: &str| graph[m].iter().cloned().collect::<Vec<_>>();
    assert_eq!(deps("a"), ["b"]);
    assert_eq!(
        deps("b"),
        ["a"],
        "crate::A is a's, through lib.rs's re-export"
    );
    assert_eq!(
        deps("c"),
        ["a", "k::j"],
        "K is k::j's, through k's re-export"
    );
    assert!(
        deps("k").is_empty(),
        "a façade's re-export of its child is no edge"
    );
    assert!(
        deps("k::j").is_empty(),
        "strings and test modules are no imports"
    );
    assert_eq!(
        import_graph::circles(&graph),
        vec![vec!["a".to_string(), "b".to_string()]]
    );
}
