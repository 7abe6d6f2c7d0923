//! The `gpuwars` command.

use std::process::ExitCode;

use clap::{Parser, Subcommand};
use gpuwars::info::Info;
use gpuwars::{BackendRequest, Device};

/// GpuWars: a top-down shooter whose whole game loop runs as GPU kernels.
#[derive(Parser)]
#[command(version, about)]
struct Cli {
    /// Where the kernels run: the GPU when present (auto), the GPU or fail (cuda), or the CPU
    /// emulation of the same kernels (cpu).
    #[arg(
        long,
        global = true,
        value_enum,
        env = "GPUWARS_BACKEND",
        default_value_t
    )]
    backend: BackendRequest,
    /// Worker threads of the CPU emulation (default: one per logical CPU).
    #[arg(long, global = true, env = "GPUWARS_CPU_THREADS", value_parser = clap::value_parser!(u16).range(1..=1024))]
    cpu_threads: Option<u16>,
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Version, backend and why, the GPU, the embedded PTX and its kernels (the default).
    Info {
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("gpuwars: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> anyhow::Result<()> {
    let device = Device::select(cli.backend, cli.cpu_threads.map(usize::from))?;
    match cli.command.unwrap_or(Command::Info { json: false }) {
        Command::Info { json } => {
            let info = Info::gather(&device);
            if json {
                println!("{}", serde_json::to_string_pretty(&info)?);
            } else {
                print!("{}", info.to_text());
            }
        }
    }
    Ok(())
}
