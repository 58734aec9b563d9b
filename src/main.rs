use clap::Parser;

/// Counts live heap bytes for `quadsim bench` (two relaxed atomics per
/// allocation; a step allocates nothing, so stepping costs nothing extra).
#[global_allocator]
static ALLOC: quadsim::mem::CountingAlloc = quadsim::mem::CountingAlloc;

fn main() {
    let cli = quadsim::cli::Cli::parse();
    if let Err(e) = quadsim::cli::run(cli) {
        eprintln!("error: {e}");
        std::process::exit(e.exit_code());
    }
}
