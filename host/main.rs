//! The `gpuwars` command.

use std::path::Path;
use std::process::ExitCode;
use std::time::Duration;

use anyhow::bail;

use gpuwars::benchmark::compare;
use gpuwars::benchmark::paper::{self, PaperOptions, PaperSummary};
use gpuwars::benchmark::scale::{self, ScaleOptions, ScaleSummary};
use gpuwars::benchmark::tradeoff::{self, TradeoffOptions, TradeoffSummary};
use gpuwars::benchmark::tune::{self, Target, TuneOptions, TuneReport};
use gpuwars::camera::{Camera, DEFAULT_ZOOM};
use gpuwars::cli::{
    BenchCommand, Cli, Command, PLAY_WINDOW, THREADS_PER_CPU, cpu_threads, default_demo, defaults,
};
use gpuwars::demo::{self, Report, RunOptions};
use gpuwars::files::{excerpt, shown, thousands};
use gpuwars::game::Scene;
use gpuwars::game::engine::footprint;
use gpuwars::game::replay::Replay;
use gpuwars::game::scene;
use gpuwars::info::Info;
use gpuwars::pipeline::Lanes;
use gpuwars::play::{self, PlayOptions, PlayReport};
use gpuwars::{BackendKind, Device};

fn main() -> ExitCode {
    let cli = gpuwars::cli::parse_from(std::env::args_os()).unwrap_or_else(|mut e| {
        gpuwars::cli::quote_short(&mut e);
        e.exit()
    });
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("gpuwars: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// The default command: the game in a window when a display is there and answers, else the
/// demo (saying why, where a display is named but will not do: a stale login's `DISPLAY`).
fn default_command() -> Command {
    if !play::display_present() {
        return Command::Demo(default_demo());
    }
    match play::display::check() {
        Ok(()) => Command::Play(defaults()),
        Err(why) => {
            eprintln!("gpuwars: {why}: playing the demo without a window instead");
            Command::Demo(default_demo())
        }
    }
}

fn run(cli: Cli) -> anyhow::Result<()> {
    let command = cli.command.unwrap_or_else(default_command);
    // Before a run that could take hours: outputs it could not write, or that would replace
    // one of its inputs, are errors now.
    command.files().check()?;
    if let Command::Bench {
        which: BenchCommand::Compare { a, b },
    } = &command
    {
        let (a_name, b_name) = (shown(a), shown(b));
        let (a, b) = (compare::load(a)?, compare::load(b)?);
        let changes = compare::compare(&a, &a_name, &b, &b_name)?;
        print!("{}", compare::to_text(&changes, &a, &b));
        let (only_a, only_b) = compare::unshared(&a, &b);
        for (which, only) in [("A", only_a), ("B", only_b)] {
            if !only.is_empty() {
                println!("only in {which}: {}", only.join(", "));
            }
        }
        return Ok(());
    }
    if let Command::Scenes = command {
        for built_in in scene::BUILT_IN {
            let scene = Scene::from_toml(built_in.source, built_in.name)?;
            println!("{:<10}{}", scene.name, scene.description);
        }
        return Ok(());
    }
    let cpus = std::thread::available_parallelism().map_or(1, usize::from);
    let threads = cli.cpu_threads.map(|asked| {
        let (threads, capped) = cpu_threads(asked, cpus);
        if capped {
            eprintln!(
                "gpuwars: --cpu-threads {asked}: using {threads}, {THREADS_PER_CPU} for each of \
                 this machine's {cpus} logical CPUs (more only wait on each other)"
            );
        }
        threads
    });
    let device = Device::select(cli.backend, threads)?;
    device.set_dependent_launch(cli.dependent_launch);
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
                    camera,
                    out,
                },
        } => {
            let options = PaperOptions {
                duration: Duration::from_secs_f64(minutes * 60.0),
                size,
                renderer: render,
                // A window shows `play`'s view: the ship followed.
                camera: match window {
                    true => Camera::default(),
                    false => Camera::new(camera, DEFAULT_ZOOM),
                },
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
                    camera,
                    out,
                },
        } => {
            let options = ScaleOptions {
                max,
                time: Duration::from_secs_f64(seconds),
                size,
                camera,
                out: out.out,
                progress: !out.json,
            };
            let summary = scale::run(&device, &options)?;
            print_summary(&summary, out.json, ScaleSummary::to_text)?;
        }
        Command::Tradeoff {
            scene,
            quick,
            seed,
            out,
        } => {
            let loaded = load_scene(&scene)?;
            // Its game tables play the scene many times: a large one is said first.
            announce(&device, &loaded);
            let options = TradeoffOptions {
                scene_given: given_name(&loaded, scene),
                scene: loaded,
                quick,
                seed,
                out: out.out,
                progress: !out.json,
            };
            let summary = tradeoff::run(&device, &options)?;
            print_summary(&summary, out.json, TradeoffSummary::to_text)?;
        }
        Command::Tune {
            scene,
            steps_per_second,
            fps,
            size,
            margin,
            quick,
            choices,
            seed,
            out,
            json,
        } => {
            if size.is_some() && fps.is_none() {
                // Checked here: clap's `requires` lets it through beside the target group.
                gpuwars::cli::command()
                    .error(
                        clap::error::ErrorKind::MissingRequiredArgument,
                        "--size sets the frame of --fps: give --fps too",
                    )
                    .exit();
            }
            let loaded = load_scene(&scene)?;
            announce(&device, &loaded);
            let options = TuneOptions {
                scene_given: given_name(&loaded, scene),
                scene: loaded,
                target: match (steps_per_second, fps) {
                    (Some(rate), _) => Target::StepsPerSecond(rate),
                    (None, fps) => Target::FramesPerSecond {
                        fps: fps.expect("clap requires one of the two"),
                        size: size.unwrap_or(PLAY_WINDOW),
                    },
                },
                margin: margin / 100.0,
                quick,
                only: choices,
                seed,
                out,
                progress: !json,
            };
            let report = tune::run(&device, &options)?;
            print_summary(&report, json, TuneReport::to_text)?;
            // A tuned scene written under a built-in's name is not what that name plays.
            if let Some(note) = options.out.to_str().and_then(scene::shadowed) {
                eprintln!("gpuwars: note: {note}");
            }
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
            let scene = load_scene(&args.scene)?;
            let slow = announce(&device, &scene);
            let options = RunOptions {
                progress: slow && !args.json,
                pilot: args.pilot,
                frame: args.screenshot.as_ref().map(|_| args.size),
                frames: args.frames(args.size)?,
                renderer: args.render,
                camera: args.camera(),
                ..args.run.options()
            };
            let (report, replay) = demo::demo(&device, &scene, args.seed, args.steps, options)?;
            if let Some(path) = &args.record {
                replay.save(path)?;
            }
            if let (Some(path), Some(frame)) = (&args.screenshot, &report.frame) {
                frame.save_png(path)?;
            }
            print_report(&report, args.json, args.screenshot.as_deref())?;
        }
        Command::Play(args) => {
            let scene = load_scene(&args.scene)?;
            announce(&device, &scene);
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
            print_summary(&report, args.json, PlayReport::to_text)?;
        }
        Command::Replay {
            file,
            json,
            window,
            render,
            size,
            mute,
            run,
        } => {
            if window && (run.no_graphs || run.profile || run.lanes != Lanes::Auto) {
                bail!(
                    "--no-graphs, --profile and --lanes apply to a headless replay, not to --window"
                );
            }
            let replay = Replay::load(&file)?;
            let origin = format!("{} (scene `{}`)", file.display(), replay.scene);
            let scene = replay.scene(&origin)?;
            let progress = announce(&device, &scene) && !json;
            if window {
                let options = PlayOptions {
                    seed: replay.seed,
                    pilot: play::Flyer::default(),
                    muted: mute,
                    vsync: true,
                    renderer: render,
                    record: None,
                    size,
                    lag: usize::from(run.lag),
                };
                let report = play::watch(&device, &scene, replay, &file, options)?;
                return print_summary(&report, json, PlayReport::to_text);
            }
            let options = RunOptions {
                progress,
                ..run.options()
            };
            let report = demo::replay(&device, &scene, &replay, options)?;
            print_report(&report, json, None)?;
            let recorded = format!("{:#018x}", replay.state_hash);
            if report.state_hash != recorded {
                bail!(
                    "{}: the replay ended in state {} but was recorded ending in {recorded}",
                    shown(&file),
                    report.state_hash
                );
            }
        }
    }
    Ok(())
}

/// Bytes of a world from which the CPU emulation says, before allocating it, how large it is.
const LARGE_WORLD_BYTES: u64 = 1 << 30;

/// The scene of `--scene`, with a note on stderr where a built-in's name is also a file
/// here (see [`scene::shadowed`]).
fn load_scene(name_or_path: &str) -> Result<Scene, scene::SceneError> {
    if let Some(note) = scene::shadowed(name_or_path) {
        eprintln!("gpuwars: note: {note}");
    }
    Scene::load(name_or_path)
}

/// Says on stderr, before a large world is allocated on the CPU emulation, how large it is
/// and that it plays slowly there (the device's free memory is checked next); returns
/// whether it did, so that the run shows its progress.
fn announce(device: &Device, scene: &Scene) -> bool {
    let (slots, bytes) = footprint(scene);
    let large = device.kind() == BackendKind::Cpu && bytes >= LARGE_WORLD_BYTES;
    if large {
        eprintln!(
            "gpuwars: scene `{}` has {} slots, which take {:.1} GB of host memory; the CPU \
             emulation may take seconds per step",
            excerpt(&scene.name),
            thousands(slots),
            bytes as f64 / 1e9
        );
    }
    large
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

/// Prints a summary as JSON or as its text.
/// A scene as the user named it (`given`): its name, and the file it came from if that
/// is not a built-in's name.
fn given_name(scene: &Scene, given: String) -> String {
    match scene.name == given {
        true => given,
        false => format!("{} ({})", scene.name, shown(Path::new(&given))),
    }
}

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
