//! No import circles between the systems' files (issue 28), read as the
//! engine's test reads its own (engine/tests/common/import_graph.rs).

#[path = "../../engine/tests/common/import_graph.rs"]
mod import_graph;

#[test]
fn systems_files_import_each_other_in_no_circle() {
    let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let graph = import_graph::file_graph(&src);
    assert!(graph.len() > 10, "read the systems' files: {}", graph.len());
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
