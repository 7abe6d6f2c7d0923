//! The `gpuwars` command.

use std::process::ExitCode;

use std::path::{Path, PathBuf};
use std::time::Duration;

use anyhow::{Context, bail};
use clap::{Args, Parser, Subcommand};
use gpuwars::benchmark::compare;
use gpuwars::benchmark::paper::{self, PaperOptions, PaperSummary};
use gpuwars::benchmark::scale::{self, ScaleOptions, ScaleSummary};
use gpuwars::game::demo::{self, Frames, Pilot, Report, RunOptions};
use gpuwars::game::replay::Replay;
use gpuwars::game::scene;
use gpuwars::game::{Options, Scene};
use gpuwars::graphics::Renderer;
use gpuwars::info::Info;
use gpuwars::pipeline::draw::MAX_SIDE;
use gpuwars::play::{self, Pilot as PlayPilot, PlayOptions};
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
    /// Version, backend and why, the GPU, the embedded PTX and its kernels.
    Info {
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Lists the built-in scenes.
    Scenes,
    /// The autopilot plays a scene without a window and prints its figures (the default).
    Demo(DemoArgs),
    /// Plays a scene in a window, at the keyboard (the default when a display is present).
    Play(PlayArgs),
    /// Measures: the paper's experiment, how the game scales, and the change between runs.
    Bench {
        #[command(subcommand)]
        which: BenchCommand,
    },
    /// Plays a recorded game again and checks that it ends in the recorded state.
    Replay {
        /// The replay file (written by `demo --record`).
        file: PathBuf,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
        #[command(flatten)]
        run: RunArgs,
    },
}

/// How a game runs on its device.
#[derive(Args)]
struct RunArgs {
    /// Steps in flight before the host reads a status back (1: wait for every step).
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u16).range(1..=1024))]
    lag: u16,
    /// Launch the kernels one by one instead of replaying the step as a CUDA graph.
    #[arg(long)]
    no_graphs: bool,
    /// Time every stage of every step and print the table (steps then wait for each stage).
    #[arg(long)]
    profile: bool,
}

impl RunArgs {
    fn options(&self) -> RunOptions {
        RunOptions {
            game: Options {
                lag: usize::from(self.lag),
                graphs: !self.no_graphs,
            },
            profile: self.profile,
            ..RunOptions::default()
        }
    }
}

#[derive(Args)]
struct DemoArgs {
    /// A built-in scene's name (see `gpuwars scenes`) or a path to a scene TOML file.
    #[arg(long, env = "GPUWARS_SCENE", default_value = "paper")]
    scene: String,
    /// Steps to play (the game may end sooner).
    #[arg(long, env = "GPUWARS_STEPS", default_value_t = 3600, value_parser = clap::value_parser!(u64).range(1..=1_000_000_000))]
    steps: u64,
    /// Seed of the random number generators.
    #[arg(long, default_value_t = 1)]
    seed: u32,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
    /// Write the game's inputs to this replay file.
    #[arg(long)]
    record: Option<PathBuf>,
    /// Who flies the ship: the autopilot, or nobody (it never moves and never fires).
    #[arg(long, value_enum, default_value_t)]
    pilot: Pilot,
    /// Draw the final state with the kernel renderer and write it to this PNG file (a bare
    /// `gpuwars` writes gpuwars-demo.png in the system's temporary folder).
    #[arg(long, env = "GPUWARS_SCREENSHOT")]
    screenshot: Option<PathBuf>,
    /// Write a frame every N steps into DIR, as frame-STEP.png (with --size), for a video.
    #[arg(long, num_args = 2, value_names = ["N", "DIR"])]
    frames_every: Option<Vec<String>>,
    /// Size of the screenshot and the frames, WIDTHxHEIGHT in pixels.
    #[arg(long, default_value = "1920x1080", value_parser = parse_size)]
    size: (u32, u32),
    /// What draws the screenshot and the frames: the kernel renderer, or GL without a
    /// window from a CUDA–GL interop vertex buffer (an EGL device).
    #[arg(long, value_enum, default_value_t)]
    render: Renderer,
    #[command(flatten)]
    run: RunArgs,
}

impl DemoArgs {
    /// `--frames-every N DIR`, checked: N from 1, DIR an existing folder.
    fn frames(&self, size: (u32, u32)) -> anyhow::Result<Option<Frames>> {
        let Some([every, dir]) = self.frames_every.as_deref() else {
            return Ok(None);
        };
        let every = every
            .parse::<u64>()
            .ok()
            .filter(|&n| n >= 1)
            .with_context(|| {
                format!("--frames-every: `{every}` is not a step count (1 or more)")
            })?;
        let dir = PathBuf::from(dir);
        if !dir.is_dir() {
            bail!("--frames-every: {} is not a folder", dir.display());
        }
        Ok(Some(Frames { every, dir, size }))
    }
}

#[derive(Subcommand)]
enum BenchCommand {
    /// The paper's experiment: `paper` played by the autopilot, one step and one frame per
    /// loop, frames per second every second (CSV, PNG plot, JSON summary).
    Paper {
        /// Minutes of wall time to play.
        #[arg(long, default_value_t = 5.0, value_parser = parse_minutes)]
        minutes: f64,
        /// Size of the frames, WIDTHxHEIGHT in pixels.
        #[arg(long, default_value = "1920x1080", value_parser = parse_size)]
        size: (u32, u32),
        /// What draws the frames: the kernel renderer or GL from the interop buffer.
        #[arg(long, value_enum, default_value_t)]
        render: Renderer,
        /// Seed of the game.
        #[arg(long, default_value_t = 1)]
        seed: u32,
        /// Draw the frames in `play`'s window (vsync off) instead of offscreen.
        #[arg(long)]
        window: bool,
        #[command(flatten)]
        out: BenchOut,
    },
    /// The paper's mix and density from 1,024 enemies up, doubling, to --max or the largest
    /// world that fits (CSV, log-log PNG plot, JSON summary).
    Scale {
        /// The most enemies (1,024 to 16,760,000; the last size if not a power of two).
        #[arg(long, default_value_t = scale::MAX_ENEMIES, value_parser = clap::value_parser!(u64).range(scale::MIN_ENEMIES..=scale::MAX_ENEMIES))]
        max: u64,
        /// Seconds spent on each measurement of a size.
        #[arg(long, default_value_t = 2.0, value_parser = parse_seconds)]
        seconds: f64,
        /// Size of the frames, WIDTHxHEIGHT in pixels.
        #[arg(long, default_value = "1920x1080", value_parser = parse_size)]
        size: (u32, u32),
        #[command(flatten)]
        out: BenchOut,
    },
    /// The change from run A to run B, figure by figure (two summaries of one benchmark).
    Compare {
        /// The first summary (bench-*.json).
        a: PathBuf,
        /// The second summary.
        b: PathBuf,
    },
}

/// Where a benchmark's files go, and how it reports.
#[derive(Args)]
struct BenchOut {
    /// The folder for bench-NAME.csv, .png and .json (made if missing).
    #[arg(long, default_value = ".")]
    out: PathBuf,
    /// Print the JSON summary instead of text (and no progress bar).
    #[arg(long)]
    json: bool,
}

/// Minutes: a number above 0 and at most a day.
fn parse_minutes(text: &str) -> Result<f64, String> {
    text.parse::<f64>()
        .ok()
        .filter(|m| *m > 0.0 && *m <= 1440.0)
        .ok_or_else(|| format!("`{text}` is not a number of minutes above 0 and at most 1440"))
}

/// Seconds: a number from 0.01 to 3600.
fn parse_seconds(text: &str) -> Result<f64, String> {
    text.parse::<f64>()
        .ok()
        .filter(|s| (0.01..=3600.0).contains(s))
        .ok_or_else(|| format!("`{text}` is not a number of seconds from 0.01 to 3600"))
}

/// Prints a summary as JSON or as its text.
fn print_summary<T: serde::Serialize>(
    summary: &T,
    json: bool,
    text: impl FnOnce(&T) -> String,
) -> anyhow::Result<()> {
    if json {
        println!("{}", serde_json::to_string_pretty(summary)?);
    } else {
        print!("{}", text(summary));
    }
    Ok(())
}

#[derive(Args)]
struct PlayArgs {
    /// A built-in scene's name (see `gpuwars scenes`) or a path to a scene TOML file.
    #[arg(long, env = "GPUWARS_SCENE", default_value = "paper")]
    scene: String,
    /// Seed of the random number generators.
    #[arg(long, default_value_t = 1)]
    seed: u32,
    /// Who flies the ship: you (WASD moves, the arrow keys fire), the autopilot, or nobody.
    #[arg(long, value_enum, default_value_t)]
    pilot: PlayPilot,
    /// Start with the sound off (M toggles it).
    #[arg(long)]
    mute: bool,
    /// Draw frames as fast as possible instead of with the display's refresh.
    #[arg(long)]
    no_vsync: bool,
    /// Write the last game's inputs to this replay file when the window closes.
    #[arg(long)]
    record: Option<PathBuf>,
    /// Which renderer draws the world: a kernel's image, or GL from a CUDA–GL interop
    /// vertex buffer.
    #[arg(long, value_enum, default_value_t)]
    render: Renderer,
    /// The window's size, WIDTHxHEIGHT in pixels.
    #[arg(long, default_value = "1280x720", value_parser = parse_size)]
    size: (u32, u32),
    /// Steps in flight before the host reads a status back.
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u16).range(1..=1024))]
    lag: u16,
    /// Print JSON instead of text when the window closes.
    #[arg(long)]
    json: bool,
}

/// `WIDTHxHEIGHT`, each side 1 to 16384 pixels.
fn parse_size(text: &str) -> Result<(u32, u32), String> {
    let bad = || format!("`{text}` is not WIDTHxHEIGHT with each side 1 to {MAX_SIDE} pixels");
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(bad)?;
    let side = |s: &str| {
        s.trim()
            .parse::<u32>()
            .ok()
            .filter(|v| (1..=MAX_SIDE).contains(v))
    };
    Ok((side(w).ok_or_else(bad)?, side(h).ok_or_else(bad)?))
}

/// Arguments `T` at their defaults (and the environment's settings).
fn defaults<T: Args + clap::FromArgMatches>() -> T {
    #[derive(Parser)]
    struct Defaults<T: Args + clap::FromArgMatches> {
        #[command(flatten)]
        args: T,
    }
    Defaults::<T>::parse_from(["gpuwars"]).args
}

/// The default demo: with no window, the last frame goes to a PNG, and the report says
/// where.
fn default_demo() -> DemoArgs {
    let mut demo: DemoArgs = defaults();
    demo.screenshot
        .get_or_insert_with(|| std::env::temp_dir().join("gpuwars-demo.png"));
    demo
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

/// The default command: the game in a window when a display is there, else the demo.
fn default_command() -> Command {
    if play::display_present() {
        Command::Play(defaults())
    } else {
        Command::Demo(default_demo())
    }
}

fn run(cli: Cli) -> anyhow::Result<()> {
    let command = cli.command.unwrap_or_else(default_command);
    if let Command::Bench {
        which: BenchCommand::Compare { a, b },
    } = &command
    {
        let (a, b) = (compare::load(a)?, compare::load(b)?);
        print!("{}", compare::to_text(&compare::compare(&a, &b)?, &a, &b));
        return Ok(());
    }
    if let Command::Scenes = command {
        for built_in in scene::BUILT_IN {
            let scene = Scene::from_toml(built_in.source, built_in.name)?;
            println!("{:<10}{}", scene.name, scene.description);
        }
        return Ok(());
    }
    let device = Device::select(cli.backend, cli.cpu_threads.map(usize::from))?;
    match command {
        Command::Scenes
        | Command::Bench {
            which: BenchCommand::Compare { .. },
        } => unreachable!("handled above"),
        Command::Bench {
            which:
                BenchCommand::Paper {
                    minutes,
                    size,
                    render,
                    seed,
                    window,
                    out,
                },
        } => {
            let options = PaperOptions {
                duration: Duration::from_secs_f64(minutes * 60.0),
                size,
                renderer: render,
                seed,
                out: out.out,
                progress: !out.json,
            };
            let summary = if window {
                paper::run_in_window(&device, &options)?
            } else {
                paper::run(&device, &options)?
            };
            print_summary(&summary, out.json, PaperSummary::to_text)?;
        }
        Command::Bench {
            which:
                BenchCommand::Scale {
                    max,
                    seconds,
                    size,
                    out,
                },
        } => {
            let options = ScaleOptions {
                max,
                time: Duration::from_secs_f64(seconds),
                size,
                out: out.out,
                progress: !out.json,
            };
            let summary = scale::run(&device, &options)?;
            print_summary(&summary, out.json, ScaleSummary::to_text)?;
        }
        Command::Info { json } => {
            let info = Info::gather(&device);
            if json {
                println!("{}", serde_json::to_string_pretty(&info)?);
            } else {
                print!("{}", info.to_text());
            }
        }
        Command::Demo(args) => {
            let scene = Scene::load(&args.scene)?;
            let options = RunOptions {
                pilot: args.pilot,
                frame: args.screenshot.as_ref().map(|_| args.size),
                frames: args.frames(args.size)?,
                renderer: args.render,
                ..args.run.options()
            };
            let (report, replay) = demo::demo(&device, &scene, args.seed, args.steps, options)?;
            if let Some(path) = &args.record {
                replay.save(path)?;
            }
            if let (Some(path), Some(frame)) = (&args.screenshot, &report.frame) {
                frame
                    .save_png(path)
                    .with_context(|| format!("writing the screenshot {}", path.display()))?;
            }
            print_report(&report, args.json, args.screenshot.as_deref())?;
        }
        Command::Play(args) => {
            let scene = Scene::load(&args.scene)?;
            let options = PlayOptions {
                seed: args.seed,
                pilot: args.pilot,
                muted: args.mute,
                vsync: !args.no_vsync,
                renderer: args.render,
                record: args.record,
                size: args.size,
                lag: usize::from(args.lag),
            };
            let report = play::play(&device, &scene, options)?;
            if args.json {
                println!("{}", serde_json::to_string_pretty(&report)?);
            } else {
                print!("{}", report.to_text());
            }
        }
        Command::Replay { file, json, run } => {
            let replay = Replay::load(&file)?;
            let origin = format!("{} (scene `{}`)", file.display(), replay.scene);
            let scene = Scene::from_toml(&replay.scene_toml, &origin)?;
            let report = demo::replay(&device, &scene, &replay, run.options())?;
            print_report(&report, json, None)?;
            let recorded = format!("{:#018x}", replay.state_hash);
            if report.state_hash != recorded {
                bail!(
                    "{}: the replay ended in state {} but was recorded ending in {recorded}",
                    file.display(),
                    report.state_hash
                );
            }
        }
    }
    Ok(())
}

/// The report, and where the screenshot went if one was written.
fn print_report(report: &Report, json: bool, screenshot: Option<&Path>) -> anyhow::Result<()> {
    if json {
        let mut value = serde_json::to_value(report)?;
        if let Some(path) = screenshot {
            value["screenshot"] = path.display().to_string().into();
        }
        println!("{}", serde_json::to_string_pretty(&value)?);
    } else {
        print!("{}", report.to_text());
        if let Some(path) = screenshot {
            println!("{:<18}{}", "screenshot:", path.display());
        }
    }
    Ok(())
}
