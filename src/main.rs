//! The `mint` binary: a thin shell over `mint_cli`, which owns argument
//! parsing, progress reporting and exit codes.

fn main() -> std::process::ExitCode {
    mint_cli::main()
}
