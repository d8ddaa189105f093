//! The `viewcloth` command line: parses the arguments (`cli::args`), runs the command
//! (`cli`) and turns its error into one stderr line and the exit code.

use std::process::ExitCode;

use clap::Parser;

use viewcloth::cli::args::{Cli, Command};
use viewcloth::cli::{self, CliError, EXIT_INPUT};

/// Command-line errors as one line on stderr, exit code 2, like every input error; help and
/// version print as clap formats them.
fn parse_cli() -> Result<Cli, ExitCode> {
    Cli::try_parse().map_err(|e| {
        use clap::error::ErrorKind;
        let display =
            [ErrorKind::DisplayHelp, ErrorKind::DisplayVersion, ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand];
        if display.contains(&e.kind()) {
            let _ = e.print();
            return ExitCode::from(if e.use_stderr() { EXIT_INPUT } else { 0 });
        }
        let text = e.render().to_string();
        let parts: Vec<&str> = text
            .lines()
            .map(str::trim)
            .filter(|l| !l.is_empty() && !l.starts_with("Usage:") && !l.starts_with("For more information"))
            .collect();
        eprintln!("{}", parts.join(" "));
        ExitCode::from(EXIT_INPUT)
    })
}

fn main() -> ExitCode {
    let cli = match parse_cli() {
        Ok(cli) => cli,
        Err(code) => return code,
    };
    let threads = cli.command.threads();
    let result: Result<(), CliError> = cli::on_workers(threads, || match cli.command {
        Command::Simulate(args) => cli::simulate(args),
        Command::Resume(args) => cli::resume_run(args),
        Command::Check { files, base } => cli::check(&files, base.as_deref()),
        Command::Compare(args) => cli::compare_modes(args),
        Command::Render(args) => cli::render(args),
        Command::Resample(args) => cli::resample(args),
        Command::Batch(args) => cli::batch(args),
        Command::Crossings(args) => cli::crossings(args),
        Command::Upsample(cmd) => cli::upsample(cmd),
        Command::Convert { conf, out, base } => cli::convert(&conf, &out, base.as_deref()),
    });
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}
