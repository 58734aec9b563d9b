use clap::Parser;

fn main() {
    let cli = quadsim::cli::Cli::parse();
    if let Err(e) = quadsim::cli::run(cli) {
        eprintln!("error: {e}");
        std::process::exit(e.exit_code());
    }
}
