use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = vanefit::cli::Cli::parse();
    match vanefit::cli::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(vanefit::cli::Failure(msg)) => {
            eprintln!("error: {msg}");
            ExitCode::from(1)
        }
    }
}
