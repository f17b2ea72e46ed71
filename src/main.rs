//! The `gearbif` command-line tool: a thin layer over the library (see `gearbif --help`).
fn main() {
    std::process::exit(gearbif::cli::main());
}
