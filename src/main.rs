//! The `mmbm` command: a thin layer over the library. See `mmbm --help`.

mod cli;

fn main() {
    std::process::exit(cli::main());
}
