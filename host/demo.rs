//! Playing a scene without a window: the autopilot demo and replays, and the figures they
//! print.

use std::path::PathBuf;
use std::time::Instant;

use gpuwars_kernels::game::control::{DESTROYED, Input, Status, TOO_SLOW};
use serde::Serialize;

use crate::backend::device_name;
use crate::backend::floor::{self, Floor};
use crate::camera::Camera;
use crate::files::thousands;
use crate::game::Game;
use crate::game::engine::Options;
use crate::game::replay::Replay;
use crate::game::spec::Scene;
use crate::graphics::Renderer;
use crate::graphics::bodies::BodyRenderer;
use crate::graphics::headless::Headless;
use crate::pipeline::{Frame, Profile};
use crate::sim::WorldSpec;
use crate::terminal::progress;
use crate::{BackendKind, Device, Error};

/// What `gpuwars demo` and `gpuwars replay` print.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Report {
    /// The backend that ran the kernels.
    pub backend: BackendKind,
    /// The GPU's name, or the CPU emulation and its threads.
    pub device: String,
    /// The scene's name.
    pub scene: String,
    /// The seed of the generators.
    pub seed: u32,
    /// Steps played (fewer than asked if the game ended).
    pub steps: u64,
    /// Game seconds played.
    pub game_seconds: f64,
    /// Seconds to set the game up on the device (buffers, generators, plans).
    pub setup_s: f64,
    /// Steps per wall-clock second, status read-back included.
    pub sim_steps_per_s: f64,
    /// Kernel launches per step (as stages, where the step is one persistent launch).
    pub launches_per_step: usize,
    /// Why the step ran as one persistent launch, if it did (`--persistent`); absent from
    /// the JSON report if it did not.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub persistent: Option<String>,
    /// Whether each step replayed a CUDA graph.
    pub graphs: bool,
    /// Steps in flight before a status was read back.
    pub lag: usize,
    /// The final state hash, as `0x` and 16 hex digits.
    pub state_hash: String,
    /// Points scored.
    pub score: u32,
    /// Enemies alive at the end.
    pub enemies_alive: u32,
    /// Enemies that died.
    pub enemies_killed: u32,
    /// Shots fired.
    pub shots_fired: u64,
    /// The FPS meter at the end.
    pub fps_meter: f32,
    /// Whether the game ended.
    pub game_over: bool,
    /// Why it ended: "too slow", "ship destroyed", or "" while playing.
    pub game_over_reason: &'static str,
    /// Each colliding pair of kinds: whether its contacts are swept, and the rule that
    /// decided it.
    pub contacts: Vec<PairReport>,
    /// Per-stage times, with `--profile`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub profile: Option<ProfileReport>,
    /// The hash of the final frame, when one was drawn (`0x` and 16 hex digits).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frame_hash: Option<String>,
    /// What drew the frames, when any was drawn.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub renderer: Option<String>,
    /// The final frame, when one was drawn.
    #[serde(skip)]
    pub frame: Option<Frame>,
}

/// How one colliding pair of kinds has its contacts tested (see [`WorldSpec::pair_sweeps`]).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PairReport {
    /// The two kinds' names.
    pub kinds: [String; 2],
    /// Whether their contacts are swept over each step's motion.
    pub swept: bool,
    /// The rule that decided it, in words.
    pub rule: String,
}

impl PairReport {
    /// Every colliding pair of `world`'s kinds.
    pub fn all(world: &WorldSpec) -> Vec<PairReport> {
        world
            .pair_sweeps()
            .into_iter()
            .map(|p| PairReport {
                kinds: [p.kinds.0, p.kinds.1].map(|k| world.kinds[k].name.clone()),
                swept: p.swept,
                rule: p.rule,
            })
            .collect()
    }
}

/// The stage times of a profiled run, and the device's copy bandwidth and launch floor
/// measured in it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ProfileReport {
    /// Bytes per second of a large device-to-device copy (read plus written).
    pub copy_bandwidth: f64,
    /// Bytes per second of a copy as large as each stage's run, in the stages' order: the
    /// ceiling of a stage whose bytes stay in a cache, as the small worlds' do.
    pub stage_copies: Vec<f64>,
    /// A chain of as many one-touch launches as the step makes, over its slots.
    pub floor: Floor,
    /// The stages' times.
    #[serde(flatten)]
    pub profile: Profile,
}

impl Report {
    /// The report as aligned lines of text.
    pub fn to_text(&self) -> String {
        let mut out = String::new();
        let mut line = |key: &str, value: String| out += &format!("{key:<18}{value}\n");
        line("backend:", self.backend.to_string());
        line("device:", self.device.clone());
        line("scene:", self.scene.clone());
        line("seed:", self.seed.to_string());
        line(
            "steps:",
            format!("{} ({:.1} s of game time)", self.steps, self.game_seconds),
        );
        line("setup_s:", format!("{:.3}", self.setup_s));
        line("sim_steps_per_s:", format!("{:.1}", self.sim_steps_per_s));
        line(
            "launches:",
            format!(
                "{} per step ({}, status read back {} step(s) late)",
                self.launches_per_step,
                match (&self.persistent, self.graphs) {
                    (Some(why), _) => format!("as stages of one persistent launch: {why}"),
                    (None, true) => "CUDA graph".into(),
                    (None, false) => "one by one".into(),
                },
                self.lag
            ),
        );
        line("state_hash:", self.state_hash.clone());
        line("score:", self.score.to_string());
        line("enemies_alive:", self.enemies_alive.to_string());
        line("enemies_killed:", self.enemies_killed.to_string());
        line("shots_fired:", self.shots_fired.to_string());
        line("fps_meter:", format!("{:.2}", self.fps_meter));
        let over = if self.game_over {
            format!("yes ({})", self.game_over_reason)
        } else {
            "no".to_string()
        };
        line("game_over:", over);
        // One line: each pair and the rule that decided it are in `--json`.
        let swept = self.contacts.iter().filter(|p| p.swept).count();
        line(
            "contacts:",
            format!(
                "{} colliding pairs of kinds, {swept} swept, {} tested at step ends (each \
                 pair's rule: --json)",
                self.contacts.len(),
                self.contacts.len() - swept
            ),
        );
        if let (Some(frame), Some(hash)) = (&self.frame, &self.frame_hash) {
            line(
                "frame:",
                format!("{}x{} pixels, hash {hash}", frame.width, frame.height),
            );
        }
        if let Some(renderer) = &self.renderer {
            line("renderer:", renderer.clone());
        }
        if let Some(p) = &self.profile {
            out += &format!(
                "\nstage times over {} (copy bandwidth {:.1} GB/s; a stage's `of copy` \
                 against a copy of as many bytes):\n{}{}\n",
                match p.profile.steps {
                    1 => "1 step".to_owned(),
                    n => format!("{} steps", thousands(n)),
                },
                p.copy_bandwidth / 1e9,
                p.profile.to_table(
                    Some(&p.stage_copies),
                    Some(p.floor.graph_s / p.floor.launches.max(1) as f64)
                ),
                p.floor.describe(p.profile.step_seconds())
            );
        }
        out
    }
}

/// Who flies the ship in a demo.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum DemoFlyer {
    /// The autopilot.
    #[default]
    Auto,
    /// Nobody: the ship never moves and never fires.
    None,
}

/// Frames written while a game plays, so that a run can be turned into a video.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Frames {
    /// A frame every this many steps (at least 1).
    pub every: u64,
    /// The folder they go to, as `frame-STEP.png` (STEP with six digits or more).
    pub dir: PathBuf,
    /// Their width and height in pixels.
    pub size: (u32, u32),
}

impl Frames {
    /// The name of the frame after step `step`: `frame-000060.png`.
    pub fn file_name(step: u64) -> String {
        format!("frame-{step:06}.png")
    }

    /// Whether `name` is one that [`Frames::file_name`] gives.
    pub fn is_file_name(name: &str) -> bool {
        let digits = name
            .strip_prefix("frame-")
            .and_then(|rest| rest.strip_suffix(".png"));
        digits.is_some_and(|d| d.len() >= 6 && d.bytes().all(|b| b.is_ascii_digit()))
    }
}

/// How `demo` and `replay` run a game.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunOptions {
    /// Who flies the ship (`demo` only; a replay flies its recorded inputs).
    pub pilot: DemoFlyer,
    /// Lag and graphs.
    pub game: Options,
    /// Time every stage of every step (steps then run stage by stage and wait).
    pub profile: bool,
    /// Draw the final state in a frame of this width and height (the kernel renderer).
    pub frame: Option<(u32, u32)>,
    /// Write frames while playing.
    pub frames: Option<Frames>,
    /// What draws the frames.
    pub renderer: Renderer,
    /// Show the steps played in a progress bar on stderr, when it is a terminal.
    pub progress: bool,
    /// What the frames show.
    pub camera: Camera,
}

/// What draws a demo's frames: the kernel renderer, or GL with no window (the interop
/// renderer, on an EGL device).
enum Painter {
    Kernel,
    Gl(Box<(Headless, BodyRenderer)>),
}

impl Painter {
    /// The painter `renderer` names, for `game`.
    fn new(renderer: Renderer, game: &Game) -> Result<Self, Error> {
        Ok(match renderer {
            Renderer::Kernel => Painter::Kernel,
            Renderer::Interop => Painter::Gl(Box::new(Headless::with_renderer(game)?)),
        })
    }

    /// What draws, in a few words.
    fn describe(&self) -> String {
        match self {
            Painter::Kernel => "kernel".into(),
            Painter::Gl(gl) => {
                let (gl, bodies) = &**gl;
                let feed = if bodies.is_interop() {
                    "CUDA–GL interop"
                } else {
                    "uploaded vertices"
                };
                format!("GL ({feed}) on {}", gl.device())
            }
        }
    }

    /// The world after every queued step as `camera` shows it (snapped to the ship), in a
    /// `width × height` frame.
    fn draw(
        &mut self,
        game: &mut Game,
        (width, height): (u32, u32),
        camera: &Camera,
    ) -> Result<Frame, Error> {
        match self {
            Painter::Kernel => game.draw(width, height, camera),
            Painter::Gl(gl) => {
                let (gl, bodies) = &mut **gl;
                let lens = game.lens(camera, width, height, 0.0);
                gl.draw(bodies, &mut game.drawing(), &lens)
            }
        }
    }
}

/// The statuses of a game as they come back, up to the first that ends it.
#[derive(Default)]
pub(crate) struct Record {
    /// The input each step applied: the replay.
    pub(crate) inputs: Vec<Input>,
    /// Shots fired.
    pub(crate) shots: u64,
    /// The latest status.
    pub(crate) last: Status,
    /// Whether the game has ended.
    pub(crate) over: bool,
}

impl Record {
    /// Takes the next step's status (those after the end repeat it and are ignored).
    pub(crate) fn take(&mut self, status: Status) {
        if self.over {
            // Steps queued after the end change nothing: their statuses repeat the last.
            return;
        }
        self.inputs.push(status.input);
        self.shots += u64::from(status.events.shots_fired);
        self.last = status;
        self.over = status.is_over();
    }
}

/// Plays up to `steps` steps (fewer if the game ends), each with the input `pilot` gives for
/// its index (`None`: the autopilot's), and reports. The inputs actually applied and the
/// final state hash are returned too, for a replay. Statuses come back `lag` steps late;
/// the game ends at the same step whatever the lag, since the device decides it.
fn play(
    game: &mut Game,
    setup_s: f64,
    seed: u32,
    steps: u64,
    options: RunOptions,
    mut pilot: impl FnMut(u64) -> Option<Input>,
) -> Result<(Report, Vec<Input>, u64), Error> {
    let mut record = Record::default();
    let mut profile = options.profile.then(Profile::default);
    let drawing = options.frame.is_some() || options.frames.is_some();
    let mut painter = match drawing {
        true => Some(Painter::new(options.renderer, game)?),
        false => None,
    };
    let mut bar = progress(steps, options.progress, "demo", "steps");
    let start = Instant::now();
    for i in 0..steps {
        bar.inc(1);
        match &mut profile {
            Some(profile) => game.submit_profiled(pilot(i), profile)?,
            None => game.submit(pilot(i))?,
        }
        while let Some(status) = game.ready_status()? {
            record.take(status);
        }
        if let Some(frames) = &options.frames
            && (i + 1) % frames.every.max(1) == 0
        {
            // Every status first, so that the replay has every input; then the frame.
            while let Some(status) = game.next_status()? {
                record.take(status);
            }
            let path = frames.dir.join(Frames::file_name(i + 1));
            let painter = painter.as_mut().expect("made when frames are asked for");
            painter
                .draw(game, frames.size, &options.camera)?
                .save_png(&path)?;
        }
        if record.over {
            break;
        }
    }
    while let Some(status) = game.next_status()? {
        record.take(status);
    }
    bar.finish_and_clear();
    let seconds = start.elapsed().as_secs_f64();
    let hash = game.state_hash()?;
    let frame = match (options.frame, &mut painter) {
        (Some(size), Some(painter)) => Some(painter.draw(game, size, &options.camera)?),
        _ => None,
    };
    let pipeline = game.pipeline();
    let device = pipeline.device();
    let profile = match profile {
        Some(profile) => Some(ProfileReport {
            copy_bandwidth: device.copy_bandwidth(u64::MAX)?,
            stage_copies: (profile.run_bytes())
                .map(|bytes| device.copy_bandwidth(bytes))
                .collect::<Result<_, _>>()?,
            floor: floor::measure(
                device,
                pipeline.launches_per_step(),
                pipeline.layout().slots,
            )?,
            profile,
        }),
        None => None,
    };
    let status = record.last;
    let played = record.inputs.len() as u64;
    let report = Report {
        backend: device.kind(),
        device: device_name(device),
        scene: game.scene().name.clone(),
        seed,
        steps: played,
        game_seconds: played as f64 * f64::from(game.scene().world.dt),
        setup_s,
        sim_steps_per_s: played as f64 / seconds.max(f64::MIN_POSITIVE),
        launches_per_step: pipeline.launches_per_step(),
        graphs: pipeline.uses_graphs() && !options.profile,
        persistent: match pipeline.persistent() {
            (true, why) if !options.profile => Some(why.to_string()),
            _ => None,
        },
        lag: options.game.lag,
        state_hash: format!("{hash:#018x}"),
        score: status.score,
        enemies_alive: status.enemies_alive,
        enemies_killed: status.enemies_killed,
        shots_fired: record.shots,
        fps_meter: status.fps_meter,
        game_over: status.is_over(),
        game_over_reason: match status.game_over {
            TOO_SLOW => "too slow",
            DESTROYED => "ship destroyed",
            _ => "",
        },
        contacts: PairReport::all(&game.scene().world),
        profile,
        frame_hash: frame.as_ref().map(|f| format!("{:#018x}", f.hash())),
        renderer: painter.as_ref().map(Painter::describe),
        frame,
    };
    Ok((report, record.inputs, hash))
}

/// The pilot `options` names (the autopilot by default) plays `scene` for up to `steps`
/// steps; returns the report and the replay of the game.
pub fn demo(
    device: &Device,
    scene: &Scene,
    seed: u32,
    steps: u64,
    options: RunOptions,
) -> Result<(Report, Replay), Error> {
    let start = Instant::now();
    let mut game = Game::with_options(device, scene, seed, options.game)?;
    let setup_s = start.elapsed().as_secs_f64();
    let pilot = match options.pilot {
        DemoFlyer::Auto => None,
        DemoFlyer::None => Some(Input::default()),
    };
    let (report, inputs, state_hash) = play(&mut game, setup_s, seed, steps, options, |_| pilot)?;
    let replay = Replay {
        version: crate::game::replay::VERSION,
        scene: scene.name.clone(),
        scene_toml: scene.source.clone(),
        seed,
        backend: report.backend,
        state_hash,
        inputs,
    };
    Ok((report, replay))
}

/// Plays `replay`'s inputs on its scene (already read from its `scene_toml`) and reports;
/// the caller compares [`Report::state_hash`] with the recorded one.
pub fn replay(
    device: &Device,
    scene: &Scene,
    replay: &Replay,
    options: RunOptions,
) -> Result<Report, Error> {
    let start = Instant::now();
    let mut game = Game::with_options(device, scene, replay.seed, options.game)?;
    let setup_s = start.elapsed().as_secs_f64();
    let inputs = &replay.inputs;
    let (report, _, _) = play(
        &mut game,
        setup_s,
        replay.seed,
        inputs.len() as u64,
        options,
        |i| Some(inputs[i as usize]),
    )?;
    Ok(report)
}
