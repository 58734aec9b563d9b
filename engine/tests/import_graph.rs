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
