//! `terracast-sim`: see `terracast-sim --help`.

use clap::Parser;
use std::process::ExitCode;
use terracast_sim::cli::{run, Cli};

fn main() -> ExitCode {
    // Last resort: a bug must still end in one line, not a backtrace.
    std::panic::set_hook(Box::new(|info| {
        eprintln!("terracast-sim: internal error: {}", info.to_string().replace('\n', " "));
    }));
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) if !e.use_stderr() => {
            let _ = e.print();
            return ExitCode::SUCCESS;
        }
        Err(e) => {
            let text = e.to_string();
            let first = text.lines().next().unwrap_or("invalid arguments");
            eprintln!("terracast-sim: {}", first.trim_start_matches("error: "));
            return ExitCode::from(2);
        }
    };
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("terracast-sim: {e}");
            ExitCode::FAILURE
        }
    }
}
