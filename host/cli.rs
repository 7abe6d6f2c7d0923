//! The command line: its commands and flags (clap), and the checks of their values, which
//! name what is allowed in words (`a whole number from 1 to 1,024`). The binary runs what
//! it parses; tests parse command lines here without starting it.

use std::path::{Path, PathBuf};

use anyhow::{anyhow, bail};
use clap::{ArgGroup, Args, Parser, Subcommand};

use crate::BackendRequest;
use crate::benchmark::{Outputs, scale};
use crate::camera::{Camera, CameraMode, DEFAULT_ZOOM, MAX_ZOOM, MIN_ZOOM};
use crate::demo::{DemoFlyer, Frames, RunOptions};
use crate::files::{RunFiles, shown, thousands};
use crate::game::Options;
use crate::game::replay::MAX_STEPS;

/// `play`'s window size where `--size` is not given (its flag's default says the same).
pub const PLAY_WINDOW: (u32, u32) = (1280, 720);
use crate::game::{highscore, scene};
use crate::graphics::Renderer;
use crate::pipeline::draw::MAX_SIDE;
use crate::pipeline::{Lanes, Persistent};
use crate::play::Flyer;

/// GpuWars: a top-down shooter whose whole game loop runs as GPU kernels.
#[derive(Parser)]
#[command(version, about)]
pub struct Cli {
    /// Where the kernels run: the GPU when present (auto), the GPU or fail (cuda), or the CPU
    /// emulation of the same kernels (cpu).
    #[arg(
        long,
        global = true,
        value_enum,
        env = "GPUWARS_BACKEND",
        default_value_t
    )]
    pub backend: BackendRequest,
    /// Worker threads of the CPU emulation (default: one per logical CPU; at most 8 per
    /// logical CPU are used, more only wait on each other).
    #[arg(long, global = true, env = "GPUWARS_CPU_THREADS", value_parser = whole(1u16, 1024))]
    pub cpu_threads: Option<u16>,
    /// On Hopper and newer GPUs, launch each kernel before the one it follows has ended,
    /// its threads waiting for it on the GPU (programmatic dependent launch): on (the
    /// default) or off, to compare.
    #[arg(
        long,
        global = true,
        env = "GPUWARS_DEPENDENT_LAUNCH",
        default_value = "on",
        value_name = "on|off",
        action = clap::ArgAction::Set,
        value_parser = on_off
    )]
    pub dependent_launch: bool,
    /// What to do; none plays in a window when a display is there, else runs the demo.
    #[command(subcommand)]
    pub command: Option<Command>,
}

/// The commands.
#[derive(Subcommand)]
pub enum Command {
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
    /// Plays a scene in a window with the keyboard, the mouse or a gamepad (the default when
    /// a display is present). WASD, the left stick or the D-pad move; the arrow keys, the
    /// mouse (left button fires) or the right stick aim and fire; P, Space or Start pause;
    /// F1 shows every key. The game starts at the first key, click or button.
    Play(PlayArgs),
    /// Measures: the paper's experiment, how the game scales, and the change between runs.
    Bench {
        /// Which measurement.
        #[command(subcommand)]
        which: BenchCommand,
    },
    /// Speed against accuracy: every physics choice measured side by side (CSV, Markdown,
    /// a Pareto plot as PNG, JSON summary).
    Tradeoff {
        /// The game scene of the game and feature tables: a built-in name or a TOML file.
        #[arg(long, default_value = "paper")]
        scene: String,
        /// Small sizes and short runs (seconds, for CI).
        #[arg(long)]
        quick: bool,
        /// Seed of every world.
        #[arg(long, default_value_t = 1, value_parser = whole(0, u32::MAX))]
        seed: u32,
        /// Where the files go, and how the summary is printed.
        #[command(flatten)]
        out: BenchOut,
    },
    /// Measures a scene's game choices on this machine and writes, as a new scene file, the
    /// most accurate one that holds a speed: fewest contacts missed first, then the rest of
    /// the contacts' audit, then speed.
    #[command(group(ArgGroup::new("target").required(true).args(["steps_per_second", "fps"])))]
    Tune {
        /// The scene to tune: a built-in name or a TOML file (never written over).
        #[arg(long, default_value = "paper")]
        scene: String,
        /// Steps per second the tuned scene must hold on this machine.
        #[arg(long, value_parser = decimal(0.001, 1.0e9))]
        steps_per_second: Option<f64>,
        /// Frames per second the tuned scene must hold, each frame the steps due and the
        /// frame drawn as `play` draws it (instead of --steps-per-second); at least the rate
        /// at which a frame is the 8 steps `play` plays at most (7.5 for steps of 1/60 s).
        #[arg(long, value_parser = decimal(0.001, 1.0e6))]
        fps: Option<f64>,
        /// With --fps: the frame's size, WIDTHxHEIGHT in pixels [default: 1280x720, `play`'s
        /// window].
        #[arg(long, value_parser = parse_size, allow_hyphen_values = true)]
        size: Option<(u32, u32)>,
        /// How far above the target the slowest timed round of a choice must be, in percent.
        #[arg(long, default_value_t = 20.0, value_parser = decimal(0.0, 1000.0))]
        margin: f64,
        /// Small sizes and short runs (seconds; the figures less sure).
        #[arg(long)]
        quick: bool,
        /// Measure only this choice (its name as `tradeoff`'s game table gives it; repeat
        /// for more) besides the scene as given: for worlds where measuring every choice
        /// would take too long [default: every choice].
        #[arg(long = "choice", value_name = "NAME")]
        choices: Vec<String>,
        /// Seed of every game.
        #[arg(long, default_value_t = 1, value_parser = whole(0, u32::MAX))]
        seed: u32,
        /// The tuned scene file to write.
        #[arg(long)]
        out: PathBuf,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Plays a recorded game again and checks that it ends in the recorded state: headless,
    /// or in a window to watch (Space or P pauses, `.` or N steps, 1 2 3 4 set the speed).
    Replay {
        /// The replay file (written by `demo --record` or `play --record`).
        file: PathBuf,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
        /// Watch it in a window; the end state is checked when it reaches its end.
        #[arg(long)]
        window: bool,
        /// With --window: which renderer draws the world.
        #[arg(long, value_enum, default_value_t, requires = "window")]
        render: Renderer,
        /// With --window: the window's size, WIDTHxHEIGHT in pixels.
        #[arg(long, default_value = "1280x720", value_parser = parse_size, allow_hyphen_values = true, requires = "window")]
        size: (u32, u32),
        /// With --window: start with the sound off (M toggles it).
        #[arg(long, requires = "window")]
        mute: bool,
        /// How the game runs on its device.
        #[command(flatten)]
        run: RunArgs,
    },
}

impl Command {
    /// Every file this command reads and writes, with the flag that names it: the one place
    /// a new file flag is declared, so that [`RunFiles::check`] keeps its outputs off its
    /// inputs and each other before the run.
    pub fn files(&self) -> RunFiles {
        let scene = |name: &str| {
            let is_file = !scene::BUILT_IN.iter().any(|b| b.name == name);
            is_file.then(|| Path::new(name).to_owned())
        };
        let benchmark = |files: RunFiles, out: &BenchOut, name: &str| {
            let outputs = Outputs::at(&out.out, name);
            [&outputs.csv, &outputs.png, &outputs.json]
                .into_iter()
                .fold(files, |files, path| files.writes_into("--out", path))
        };
        match self {
            Command::Info { .. } | Command::Scenes => RunFiles::new(),
            Command::Demo(args) => RunFiles::new()
                .reads("--scene", scene(&args.scene).as_deref())
                .writes("--record", args.record.as_deref())
                .writes("--screenshot", args.screenshot.as_deref())
                .writes_many("--frames-every", frames_dir(args), Frames::is_file_name),
            // The high scores are read, and rewritten only when a game beats them: an
            // output on them is refused, a problem with them only warned of (as before).
            Command::Play(args) => RunFiles::new()
                .reads("--scene", scene(&args.scene).as_deref())
                .reads("the high scores", highscore::default_path().as_deref())
                .writes("--record", args.record.as_deref()),
            Command::Replay { file, .. } => RunFiles::new().reads("FILE", Some(file)),
            Command::Tune {
                scene: name, out, ..
            } => RunFiles::new()
                .reads("--scene", scene(name).as_deref())
                .writes("--out", Some(out)),
            Command::Tradeoff {
                scene: name, out, ..
            } => {
                let files = RunFiles::new().reads("--scene", scene(name).as_deref());
                let outputs = Outputs::at(&out.out, "tradeoff");
                benchmark(files, out, "tradeoff")
                    .writes_into("--out", &outputs.markdown())
                    .writes_into("--out", &outputs.game_png())
            }
            Command::Bench { which } => match which {
                BenchCommand::Paper { out, .. } => benchmark(RunFiles::new(), out, "paper"),
                BenchCommand::Scale { out, .. } => benchmark(RunFiles::new(), out, "scale"),
                BenchCommand::Compare { a, b } => {
                    RunFiles::new().reads("A", Some(a)).reads("B", Some(b))
                }
            },
        }
    }
}

/// The measurements of `gpuwars bench`.
#[derive(Subcommand)]
pub enum BenchCommand {
    /// The paper's experiment: `paper` played by the autopilot, one step and one frame per
    /// loop, frames per second every second (CSV, PNG plot, JSON summary).
    Paper {
        /// Minutes of wall time to play, counted in whole seconds (at least one; a part
        /// of a second is left out).
        #[arg(long, default_value_t = 5.0, value_parser = minutes_of_play)]
        minutes: f64,
        /// Size of the frames, WIDTHxHEIGHT in pixels.
        #[arg(long, default_value = "1920x1080", value_parser = parse_size, allow_hyphen_values = true)]
        size: (u32, u32),
        /// What draws the frames: the kernel renderer or GL from the interop buffer.
        #[arg(long, value_enum, default_value_t)]
        render: Renderer,
        /// Seed of the game.
        #[arg(long, default_value_t = 1, value_parser = whole(0, u32::MAX))]
        seed: u32,
        /// Draw the frames in `play`'s window (vsync off) instead of offscreen, as `play`
        /// shows them (the ship followed).
        #[arg(long)]
        window: bool,
        /// What the offscreen frames show: the whole field, as the paper's experiment and
        /// earlier runs drew it (field), or the ship followed at the default zoom with the
        /// radar, the view a player sees (follow).
        #[arg(long, value_enum, default_value_t = CameraMode::Field, conflicts_with = "window")]
        camera: CameraMode,
        /// Where the files go, and how the summary is printed.
        #[command(flatten)]
        out: BenchOut,
    },
    /// The paper's mix and density from 1,024 enemies up, doubling, to --max or the largest
    /// world that fits (CSV, log-log PNG plot, JSON summary).
    Scale {
        /// The most enemies, a multiple of 8 from 1,024 to 16,760,000 (the last size if not a
        /// power of two).
        #[arg(long, default_value_t = scale::MAX_ENEMIES, value_parser = enemies)]
        max: u64,
        /// Seconds spent on each measurement of a size.
        #[arg(long, default_value_t = 2.0, value_parser = decimal(0.01, 3600.0))]
        seconds: f64,
        /// Size of the frames, WIDTHxHEIGHT in pixels.
        #[arg(long, default_value = "1920x1080", value_parser = parse_size, allow_hyphen_values = true)]
        size: (u32, u32),
        /// What the frames show: the whole field, as earlier runs drew it (field), or the
        /// ship followed at the default zoom with the radar, the view a player sees (follow).
        #[arg(long, value_enum, default_value_t = CameraMode::Field)]
        camera: CameraMode,
        /// Where the files go, and how the summary is printed.
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
pub struct BenchOut {
    /// The folder for bench-NAME.csv, .png and .json (made if missing).
    #[arg(long, default_value = ".")]
    pub out: PathBuf,
    /// Print the JSON summary instead of text (and no progress bar).
    #[arg(long)]
    pub json: bool,
}

/// A value parser for a number from `low` to `high`, whose errors say so. The bounds hold
/// for the number as written, not only once rounded to `T` (8.0000004 is past 8, though
/// as an `f32` it is 8).
pub fn decimal<T>(low: T, high: T) -> impl Fn(&str) -> Result<T, String> + Clone + Send + Sync
where
    T: std::str::FromStr + PartialOrd + std::fmt::Display + Copy + Send + Sync + 'static,
{
    move |text| {
        let allowed = format!("allowed a number from {low} to {high}");
        let exact = |t: &str| t.parse::<f64>().ok();
        let written = match (
            exact(text.trim()),
            exact(&low.to_string()),
            exact(&high.to_string()),
        ) {
            (Some(v), Some(lo), Some(hi)) => lo <= v && v <= hi,
            _ => true,
        };
        match text.trim().parse::<T>() {
            Ok(v) if written && low <= v && v <= high => Ok(v),
            Ok(_) => Err(format!("out of range ({allowed})")),
            Err(_) => Err(format!("not a number ({allowed})")),
        }
    }
}

/// A value parser for `bench paper --minutes`: a number of minutes that holds at least
/// one whole second (the run counts frames second by second), up to a day.
fn minutes_of_play(text: &str) -> Result<f64, String> {
    let allowed = "allowed a number of minutes from 0.0167, one second, to 1440";
    let minutes: f64 = (text.trim().parse()).map_err(|_| format!("not a number ({allowed})"))?;
    if !(0.0..=1440.0).contains(&minutes) {
        Err(format!("out of range ({allowed})"))
    } else if minutes * 60.0 < 1.0 {
        Err(format!(
            "too short to count ({allowed}: the run counts whole seconds)"
        ))
    } else {
        Ok(minutes)
    }
}

/// A value parser for `on` or `off` (the words the usage shows), whose error names both
/// ways of giving it.
fn on_off(text: &str) -> Result<bool, String> {
    match text.trim().to_ascii_lowercase().as_str() {
        "on" => Ok(true),
        "off" => Ok(false),
        _ => Err("allowed: on or off (as --dependent-launch or GPUWARS_DEPENDENT_LAUNCH)".into()),
    }
}

/// Shortens the values a command-line error quotes, and escapes their control characters,
/// as errors show file names (see [`crate::files::short_name`]): a 100,000-character value
/// is quoted by its start and its end, a newline as `\n`.
pub fn quote_short(error: &mut clap::Error) {
    use clap::error::{ContextKind, ContextValue};
    for kind in [
        ContextKind::InvalidValue,
        ContextKind::InvalidArg,
        ContextKind::InvalidSubcommand,
    ] {
        if let Some(ContextValue::String(value)) = error.get(kind) {
            let short = crate::files::short_name(value);
            error.insert(kind, ContextValue::String(short));
        }
    }
}

/// Parses `args` (the program's name first) as [`command`] does.
pub fn parse_from<I, T>(args: I) -> Result<Cli, clap::Error>
where
    I: IntoIterator<Item = T>,
    T: Into<std::ffi::OsString> + Clone,
{
    use clap::FromArgMatches;
    let args: Vec<std::ffi::OsString> = args.into_iter().map(Into::into).collect();
    let mut matches =
        (command().try_get_matches_from(&args)).map_err(|e| from_environment(e, &args))?;
    Cli::from_arg_matches_mut(&mut matches).map_err(|e| e.format(&mut command()))
}

/// `error` with a tip naming the environment variable its value came from: where the flag
/// it names is not on the command line `args` but its variable is set (`GPUWARS_STEPS=abc`
/// is refused as `--steps`'s value).
fn from_environment(mut error: clap::Error, args: &[std::ffi::OsString]) -> clap::Error {
    use clap::error::{ContextKind, ContextValue};
    fn flags(command: &clap::Command) -> Vec<clap::Arg> {
        let own = command.get_arguments().cloned();
        own.chain(command.get_subcommands().flat_map(flags))
            .collect()
    }
    let Some(ContextValue::String(arg)) = error.get(ContextKind::InvalidArg) else {
        return error;
    };
    let flag = arg.split_whitespace().next().unwrap_or_default().to_owned();
    let given = (args.iter().filter_map(|a| a.to_str()))
        .any(|a| a == flag || a.starts_with(&format!("{flag}=")));
    let variable = flags(&command())
        .into_iter()
        .find(|a| a.get_long().is_some_and(|long| format!("--{long}") == flag))
        .and_then(|a| a.get_env().map(|v| v.to_string_lossy().into_owned()))
        .filter(|v| std::env::var_os(v).is_some());
    if let (false, Some(variable)) = (given, variable) {
        let tip = format!("the value is the environment's {variable}: unset it, or give {flag}");
        error.insert(
            ContextKind::Suggested,
            ContextValue::StyledStrs(vec![tip.into()]),
        );
    }
    error
}

/// [`Cli`]'s command in which a flag that takes a value takes a negative number too, so that
/// `--steps -5` gets the flag's own range error rather than "unexpected argument '-5'".
pub fn command() -> clap::Command {
    fn negatives_as_values(command: clap::Command) -> clap::Command {
        command
            .mut_args(|arg| {
                let takes_value = arg.get_action().takes_values();
                arg.allow_negative_numbers(takes_value)
            })
            .mut_subcommands(negatives_as_values)
    }
    negatives_as_values(<Cli as clap::CommandFactory>::command())
}

/// `--lanes`: `auto`, or a power of two from 1 to 32.
fn parse_lanes(text: &str) -> Result<Lanes, String> {
    let text = text.trim();
    if text == "auto" {
        return Ok(Lanes::Auto);
    }
    match text.parse::<u32>() {
        Ok(n) if n.is_power_of_two() && n <= 32 => Ok(Lanes::Fixed(n)),
        // The value itself is quoted by the error around this (shortened, escaped).
        _ => Err("not allowed (allowed: auto, 1, 2, 4, 8, 16 or 32)".to_owned()),
    }
}

/// How a game runs on its device.
#[derive(Args)]
pub struct RunArgs {
    /// Steps in flight before the host reads a status back (1: wait for every step).
    #[arg(long, default_value_t = 4, value_parser = whole(1u16, 1024))]
    pub lag: u16,
    /// Launch the kernels one by one instead of replaying the step as a CUDA graph.
    #[arg(long)]
    pub no_graphs: bool,
    /// Threads each body's neighbour queries get: `auto` (teams sized by the neighbours a
    /// kind expects, on the GPU), or 1, 2, 4, 8, 16 or 32 for every kind. Speed only: the
    /// results are the same.
    #[arg(long, default_value = "auto", value_parser = parse_lanes)]
    pub lanes: Lanes,
    /// Run each step as one persistent launch (its stages with a barrier across the GPU
    /// between them): `auto` (the plan of launches, faster wherever measured), `on` or
    /// `off`. Speed only: the results are the same.
    #[arg(long, value_enum, default_value_t = Persistent::Auto)]
    pub persistent: Persistent,
    /// Time every stage of every step and print the table (steps then wait for each stage).
    #[arg(long)]
    pub profile: bool,
}

impl RunArgs {
    /// The options a game runs with.
    pub fn options(&self) -> RunOptions {
        RunOptions {
            game: Options {
                lag: usize::from(self.lag),
                graphs: !self.no_graphs,
                lanes: self.lanes,
                persistent: self.persistent,
            },
            profile: self.profile,
            ..RunOptions::default()
        }
    }
}

/// What `gpuwars demo` plays, and what it writes.
#[derive(Args)]
pub struct DemoArgs {
    /// A built-in scene's name (see `gpuwars scenes`) or a path to a scene TOML file.
    #[arg(long, env = "GPUWARS_SCENE", default_value = "paper")]
    pub scene: String,
    /// Steps to play (the game may end sooner).
    #[arg(long, env = "GPUWARS_STEPS", default_value_t = 3600, value_parser = whole(1, MAX_STEPS))]
    pub steps: u64,
    /// Seed of the random number generators.
    #[arg(long, default_value_t = 1, value_parser = whole(0, u32::MAX))]
    pub seed: u32,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
    /// Write the game's inputs to this replay file.
    #[arg(long)]
    pub record: Option<PathBuf>,
    /// Who flies the ship: the autopilot, or nobody (it never moves and never fires).
    #[arg(long, value_enum, default_value_t)]
    pub pilot: DemoFlyer,
    /// Draw the final state with the kernel renderer and write it to this PNG file (a bare
    /// `gpuwars` writes gpuwars-demo.png in the system's temporary folder).
    #[arg(long, env = "GPUWARS_SCREENSHOT", value_parser = png_path)]
    pub screenshot: Option<PathBuf>,
    /// Write a frame every N steps into DIR, as frame-STEP.png (with --size), for a video.
    #[arg(long, num_args = 2, value_names = ["N", "DIR"])]
    pub frames_every: Option<Vec<String>>,
    /// Size of the screenshot and the frames, WIDTHxHEIGHT in pixels.
    #[arg(long, default_value = "1920x1080", value_parser = parse_size, allow_hyphen_values = true)]
    pub size: (u32, u32),
    /// What draws the screenshot and the frames: the kernel renderer, or GL without a
    /// window from a CUDA–GL interop vertex buffer (an EGL device).
    #[arg(long, value_enum, default_value_t)]
    pub render: Renderer,
    /// What the screenshot and the frames show: the ship, centred, with the radar in a
    /// corner (follow), or the whole field (field).
    #[arg(long, env = "GPUWARS_CAMERA", value_enum, default_value_t)]
    pub camera: CameraMode,
    /// How close the camera follows the ship: pixels per field unit are zoom × height /
    /// 1080 (at least the whole field, at most 8 times zoom 1's).
    #[arg(
        long,
        env = "GPUWARS_ZOOM",
        default_value_t = DEFAULT_ZOOM,
        value_parser = decimal(MIN_ZOOM, MAX_ZOOM)
    )]
    pub zoom: f32,
    /// How the game runs on its device.
    #[command(flatten)]
    pub run: RunArgs,
}

impl DemoArgs {
    /// The camera of `--camera` and `--zoom`.
    pub fn camera(&self) -> Camera {
        Camera::new(self.camera, self.zoom)
    }

    /// `--frames-every N DIR`, checked: N from 1, DIR an existing folder.
    pub fn frames(&self, size: (u32, u32)) -> anyhow::Result<Option<Frames>> {
        let Some([every, dir]) = self.frames_every.as_deref() else {
            return Ok(None);
        };
        let every = whole(1, MAX_STEPS)(every).map_err(|e| anyhow!("--frames-every: N: {e}"))?;
        let dir = PathBuf::from(dir);
        match std::fs::metadata(&dir) {
            Ok(meta) if meta.is_dir() => {}
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => bail!(
                "--frames-every: the folder {} does not exist (make it first)",
                shown(&dir)
            ),
            // Windows reads no metadata of some paths that are not folders (`/dev/null`).
            Ok(_) | Err(_) => bail!("--frames-every: {} is not a folder", shown(&dir)),
        }
        Ok(Some(Frames { every, dir, size }))
    }
}

/// The folder of `--frames-every N DIR`.
fn frames_dir(args: &DemoArgs) -> Option<&Path> {
    args.frames_every
        .as_deref()
        .and_then(|values| values.get(1))
        .map(Path::new)
}

/// What `gpuwars play` plays, and how.
#[derive(Args)]
pub struct PlayArgs {
    /// A built-in scene's name (see `gpuwars scenes`) or a path to a scene TOML file.
    #[arg(long, env = "GPUWARS_SCENE", default_value = "paper")]
    pub scene: String,
    /// Seed of the random number generators.
    #[arg(long, default_value_t = 1, value_parser = whole(0, u32::MAX))]
    pub seed: u32,
    /// Who flies the ship: you (keyboard, mouse or gamepad), the autopilot, or nobody.
    #[arg(long, value_enum, default_value_t)]
    pub pilot: Flyer,
    /// Start with the sound off (M toggles it).
    #[arg(long)]
    pub mute: bool,
    /// Draw frames as fast as possible instead of with the display's refresh.
    #[arg(long)]
    pub no_vsync: bool,
    /// Write the last game's inputs to this replay file when the window closes.
    #[arg(long)]
    pub record: Option<PathBuf>,
    /// Which renderer draws the world: a kernel's image, or GL from a CUDA–GL interop
    /// vertex buffer.
    #[arg(long, value_enum, default_value_t)]
    pub render: Renderer,
    /// The window's size, WIDTHxHEIGHT in pixels.
    #[arg(long, default_value = "1280x720", value_parser = parse_size, allow_hyphen_values = true)]
    pub size: (u32, u32),
    /// Steps in flight before the host reads a status back.
    #[arg(long, default_value_t = 4, value_parser = whole(1u16, 1024))]
    pub lag: u16,
    /// Print JSON instead of text when the window closes.
    #[arg(long)]
    pub json: bool,
}

/// A path whose name ends in `.png` (in any case): what a PNG file is written to, not a
/// `.jpg` that would hold a PNG.
fn png_path(text: &str) -> Result<PathBuf, String> {
    let path = PathBuf::from(text);
    match path.extension() {
        Some(ext) if ext.eq_ignore_ascii_case("png") => Ok(path),
        _ => Err("not a PNG file's name (allowed a name ending in .png)".to_owned()),
    }
}

/// `WIDTHxHEIGHT`, each side 1 to 16,384 pixels.
pub fn parse_size(text: &str) -> Result<(u32, u32), String> {
    let bad = || {
        let max = thousands(MAX_SIDE);
        format!("not WIDTHxHEIGHT (allowed each side a whole number of pixels from 1 to {max})")
    };
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
pub fn defaults<T: Args + clap::FromArgMatches>() -> T {
    #[derive(Parser)]
    struct Defaults<T: Args + clap::FromArgMatches> {
        #[command(flatten)]
        args: T,
    }
    // A bad value from the environment is quoted as the command line's are.
    Defaults::<T>::try_parse_from(["gpuwars"])
        .unwrap_or_else(|mut e| {
            quote_short(&mut e);
            e.exit()
        })
        .args
}

/// The default demo: with no window, the last frame goes to a PNG, and the report says
/// where.
pub fn default_demo() -> DemoArgs {
    let mut demo: DemoArgs = defaults();
    demo.screenshot
        .get_or_insert_with(|| std::env::temp_dir().join("gpuwars-demo.png"));
    demo
}

/// Enemies of `bench scale`: a multiple of 8 (the kinds' shares of the mix are whole) from
/// [`scale::MIN_ENEMIES`] to [`scale::MAX_ENEMIES`].
pub fn enemies(text: &str) -> Result<u64, String> {
    let n = whole(scale::MIN_ENEMIES, scale::MAX_ENEMIES)(text)?;
    match n.is_multiple_of(8) {
        true => Ok(n),
        false => Err(format!(
            "not a multiple of 8 (allowed a multiple of 8 from {} to {})",
            thousands(scale::MIN_ENEMIES),
            thousands(scale::MAX_ENEMIES)
        )),
    }
}

/// Threads of the CPU emulation for `asked` on a machine of `cpus` logical CPUs: at most
/// [`THREADS_PER_CPU`] per CPU (beyond that they only wait on each other: 1,024 threads on
/// 2 CPUs made a step over 100 times slower than 128 did), and whether that capped it.
pub fn cpu_threads(asked: u16, cpus: usize) -> (usize, bool) {
    let most = cpus.max(1).saturating_mul(THREADS_PER_CPU);
    let asked = usize::from(asked);
    (asked.min(most), asked > most)
}

/// Most CPU emulation threads per logical CPU.
pub const THREADS_PER_CPU: usize = 8;

/// A value parser for a whole number from `low` to `high`, whose errors say so.
pub fn whole<T>(low: T, high: T) -> impl Fn(&str) -> Result<T, String> + Clone + Send + Sync
where
    T: Copy + Into<i128> + TryFrom<i128> + Send + Sync + 'static,
{
    move |text| {
        let allowed = format!(
            "allowed a whole number from {} to {}",
            thousands(low),
            thousands(high)
        );
        match text.trim().parse::<i128>() {
            Ok(v) if (low.into()..=high.into()).contains(&v) => {
                T::try_from(v).map_err(|_| format!("out of range ({allowed})"))
            }
            Ok(_) => Err(format!("out of range ({allowed})")),
            Err(_) => Err(format!("not a whole number ({allowed})")),
        }
    }
}
