//! The `nptreemap` binary: the command line lives in the library's `cli`
//! module (feature `cli`), so that the library's internals stay private.

fn main() -> std::process::ExitCode {
    nptreemap::cli::main()
}
