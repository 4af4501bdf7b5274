//! `terracast-sim`: see `terracast-sim --help`.

use clap::error::ErrorKind;
use clap::Parser;
use std::process::ExitCode;
use terracast_sim::cli::{run, Cli};

fn main() -> ExitCode {
    // Last resort: a bug must still end in one line, not a backtrace.
    std::panic::set_hook(Box::new(|info| {
        eprintln!(
            "terracast-sim: internal error: {}",
            info.to_string().replace('\n', " ")
        );
    }));
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) if !e.use_stderr() => {
            let _ = e.print();
            return ExitCode::SUCCESS;
        }
        Err(e) if e.kind() == ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
            // A bare command: the list of what it takes, as --help prints.
            let _ = e.print();
            return ExitCode::from(2);
        }
        Err(e) => {
            // clap explains over several lines; keep the explanation, drop
            // the usage, and fold it into one line.
            let text = e.to_string();
            let explanation = text.split("\n\n").next().unwrap_or("invalid arguments");
            let line = explanation.split_whitespace().collect::<Vec<_>>().join(" ");
            eprintln!("terracast-sim: {}", line.trim_start_matches("error: "));
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
