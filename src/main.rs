//! The `emcy-decode` binary. The application lives in the library's `app`
//! module (command line, commands, exit codes); this only starts it.
#![forbid(unsafe_code)]

fn main() -> std::process::ExitCode {
    emcy_decode::cli_main()
}
