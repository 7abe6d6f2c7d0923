//! `gpuwars play`: the game in a window. A fixed-step loop submits the steps that real time
//! has made due, each with the input of the moment (keyboard, mouse and gamepad merged by
//! [`controls::Controls`]), draws the world with the renderer asked for, and puts the HUD,
//! the start screen, the help and the game-over banner over it; sound effects follow each
//! step's events. The game waits for a first key, click or button, and pauses while the help
//! shows or the window is left.
//!
//! A slow frame never changes the outcome: the simulation's dt is the scene's, and a frame
//! that falls behind plays its due steps late (at most [`MAX_CATCH_UP`] per frame, after
//! which the game slows down rather than skipping). The inputs of every step are recorded,
//! so `--record` writes a replay that `gpuwars replay` plays headless to the same state, and
//! [`watch`] plays in the same window loop (`gpuwars replay --window`).

mod clock;
pub mod controls;
#[cfg(unix)]
pub mod display;
/// Where there is no X11 or Wayland display to wait for (Windows opens its windows itself).
#[cfg(not(unix))]
pub mod display {
    /// Nothing to ask: `Ok`.
    pub fn check() -> Result<(), String> {
        Ok(())
    }
}
mod draw;
mod events;
mod gamepad;
mod guard;
mod input;
pub mod keys;
mod steps;
mod window;

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{Context as _, anyhow, bail};
use glium::Display;
use glutin::surface::WindowSurface;
use gpuwars_kernels::render::Framing;
use gpuwars_kernels::render::camera::CameraState;
use serde::Serialize;
use winit::event_loop::{ControlFlow, EventLoop};
use winit::window::Window;

use crate::backend::device_name;
use crate::camera::Camera;
use crate::demo::Record;
use crate::game::highscore::{self, HighScores};
use crate::game::replay::Replay;
use crate::game::{Game, Options, Scene};
use crate::graphics::Renderer;
use crate::graphics::bodies::BodyRenderer;
use crate::graphics::headless::Target;
use crate::graphics::picture::{Blit, DeviceImage, Upload};
use crate::meter::Seconds;
use crate::sound::Sound;
use crate::{BackendKind, Device};
use clock::Clock;
use controls::Controls;
use gamepad::Gamepads;

/// The most steps one frame plays (times a replay's speed); beyond it the game slows down
/// instead.
pub const MAX_CATCH_UP: u64 = 8;

/// Who flies the ship in the window.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Flyer {
    /// The player, at the keyboard.
    #[default]
    Human,
    /// The autopilot.
    Auto,
    /// Nobody: the ship never moves and never fires.
    None,
}

/// How `play` runs.
#[derive(Clone, Debug)]
pub struct PlayOptions {
    /// Seed of the generators.
    pub seed: u32,
    /// Who flies the ship.
    pub pilot: Flyer,
    /// Start with the sound off.
    pub muted: bool,
    /// Swap frames with the display's refresh.
    pub vsync: bool,
    /// The renderer.
    pub renderer: Renderer,
    /// Write the last game's replay here on exit.
    pub record: Option<PathBuf>,
    /// The window's size in pixels.
    pub size: (u32, u32),
    /// Steps in flight before a status is read back.
    pub lag: usize,
}

/// What `play` prints when the window closes: the last game's figures.
#[derive(Clone, Debug, Serialize)]
pub struct PlayReport {
    /// The backend that ran the kernels.
    pub backend: BackendKind,
    /// The GPU's name, or the CPU emulation.
    pub device: String,
    /// The renderer and how its data reached GL.
    pub renderer: String,
    /// The scene.
    pub scene: String,
    /// The seed.
    pub seed: u32,
    /// Steps the last game played.
    pub steps: u64,
    /// Its game seconds.
    pub game_seconds: f64,
    /// The final state hash (`0x` and 16 hex digits), as `demo` and `replay` print it.
    pub state_hash: String,
    /// Points scored.
    pub score: u32,
    /// Enemies that died.
    pub enemies_killed: u32,
    /// The FPS meter at the end.
    pub fps_meter: f32,
    /// Whether the game ended.
    pub game_over: bool,
    /// Frames drawn in the whole session.
    pub frames: u64,
    /// Frames per second over the session.
    pub frame_rate: f64,
    /// For a replay: whether its end state matched the recording, or where it stopped.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub replay: Option<String>,
    /// Where this machine could not play the scene's steps in real time: how far behind,
    /// and the command that would tune the scene for it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub behind: Option<String>,
}

/// The advice for a game of `scene` (time step `dt`) that played `played` steps and gave up
/// `given_up` seconds of game time to keep up, where it gave up more than 2%.
pub fn behind(scene: &str, dt: f32, played: u64, given_up: f64) -> Option<String> {
    let played_s = played as f64 * f64::from(dt);
    let share = given_up / (played_s + given_up);
    let hz = 1.0 / f64::from(dt);
    (share > 0.02).then(|| {
        format!(
            "this machine played {:.0}% of the game's time ({:.0} of the {hz:.0} steps a second \
             the scene asks for): `gpuwars tune --scene {scene} --steps-per-second {hz:.0} --out \
             tuned.toml` writes the most accurate scene it holds",
            100.0 * (1.0 - share),
            hz * (1.0 - share)
        )
    })
}

impl PlayReport {
    /// The report as aligned lines of text.
    pub fn to_text(&self) -> String {
        let rows = [
            ("backend:", self.backend.to_string()),
            ("device:", self.device.clone()),
            ("renderer:", self.renderer.clone()),
            ("scene:", self.scene.clone()),
            ("seed:", self.seed.to_string()),
            (
                "steps:",
                format!("{} ({:.1} s of game time)", self.steps, self.game_seconds),
            ),
            ("state_hash:", self.state_hash.clone()),
            ("score:", self.score.to_string()),
            ("enemies_killed:", self.enemies_killed.to_string()),
            ("fps_meter:", format!("{:.2}", self.fps_meter)),
            (
                "game_over:",
                if self.game_over { "yes" } else { "no" }.into(),
            ),
            (
                "frames:",
                format!("{} ({:.1} per second)", self.frames, self.frame_rate),
            ),
        ];
        let replay = self.replay.iter().map(|r| ("replay:", r.clone()));
        let behind = self.behind.iter().map(|b| ("behind:", b.clone()));
        let rows = rows.into_iter().chain(replay).chain(behind);
        rows.map(|(k, v)| format!("{k:<18}{v}\n")).collect()
    }
}

/// Whether a display to open a window on is there: X11 or Wayland on Unix; on Windows
/// always (its windows need no display server to be named).
pub fn display_present() -> bool {
    cfg!(windows)
        || ["DISPLAY", "WAYLAND_DISPLAY"]
            .iter()
            .any(|v| std::env::var_os(v).is_some_and(|d| !d.is_empty()))
}

/// Plays `scene` in a window until Esc or the window is closed; returns the last game's
/// report (and writes its replay if asked).
pub fn play(device: &Device, scene: &Scene, options: PlayOptions) -> anyhow::Result<PlayReport> {
    display::check().map_err(|e| anyhow!("{e}; `gpuwars demo` plays without a window"))?;
    // winit's error quotes its own source file: the user is told what to do instead.
    let event_loop = EventLoop::new()
        .map_err(|_| anyhow!("no display to open a window on; `gpuwars demo` plays without one"))?;
    event_loop.set_control_flow(ControlFlow::Poll);
    let mut app = App::new(device, scene, options, None)?;
    if let Some(ran) = guard::surviving_winit(|| event_loop.run_app(&mut app)) {
        ran.context("running the window")?;
    }
    app.finish()
}

/// Plays `replay` (read from `file`, its scene already read from it) in a window, with
/// pause, single steps and speeds, until Esc or the window is closed; at its end, checks the
/// state against the recording's hash (a mismatch is an error). `options.seed` is ignored
/// for the replay's own.
pub fn watch(
    device: &Device,
    scene: &Scene,
    replay: Replay,
    file: &Path,
    options: PlayOptions,
) -> anyhow::Result<PlayReport> {
    let headless = format!(
        "`gpuwars replay {}` (without --window) checks it headless",
        crate::files::shown(file)
    );
    if !display_present() {
        bail!(
            "no display to open a window on (neither DISPLAY nor WAYLAND_DISPLAY is set): {headless}"
        );
    }
    display::check().map_err(|silent| anyhow!("{silent}; {headless}"))?;
    // winit's error quotes its own source file: the user is told what to do instead.
    let event_loop =
        EventLoop::new().map_err(|_| anyhow!("no display to open a window on: {headless}"))?;
    event_loop.set_control_flow(ControlFlow::Poll);
    let options = PlayOptions {
        seed: replay.seed,
        record: None,
        ..options
    };
    let watch = Watch {
        replay,
        file: file.display().to_string(),
        speed: 1,
        single: 0,
        checked: false,
    };
    let mut app = App::new(device, scene, options, Some(watch))?;
    if let Some(ran) = guard::surviving_winit(|| event_loop.run_app(&mut app)) {
        ran.context("running the window")?;
    }
    app.finish()
}

/// Runs `scene` in the window for `duration` as the benchmark's loop does (one step per
/// frame, whatever the time), counting frames second by second with one profiled frame per
/// second; returns the seconds and whether the game ended.
pub fn measure(
    device: &Device,
    scene: &Scene,
    options: PlayOptions,
    duration: Duration,
) -> anyhow::Result<(Seconds, bool)> {
    display::check().map_err(|e| anyhow!("{e}; leave out --window to render offscreen"))?;
    let event_loop = EventLoop::new().map_err(|_| {
        anyhow!("no display to open a window on; leave out --window to render offscreen")
    })?;
    event_loop.set_control_flow(ControlFlow::Poll);
    let mut app = App::new(device, scene, options, None)?;
    app.begun = true;
    // The paper's experiment draws the whole field (see `benchmark::paper`).
    app.camera = Camera::field();
    app.bench = Some(Bench {
        seconds: Seconds::new(Instant::now()),
        duration,
        until: None,
    });
    event_loop.run_app(&mut app).context("running the window")?;
    app.screen = None;
    if let Some(error) = app.failure.take() {
        return Err(error);
    }
    let bench = app.bench.take().expect("set above");
    Ok((bench.seconds, app.round.record.over))
}

/// The benchmark's loop in the window: its frame counter, and when it ends.
struct Bench {
    seconds: Seconds,
    duration: Duration,
    /// Set at the first frame, so that opening the window is not counted.
    until: Option<Instant>,
}

/// A replay playing in the window: the pilot is the recording.
struct Watch {
    replay: Replay,
    /// The file it came from, for messages.
    file: String,
    /// Times real time.
    speed: u32,
    /// Steps asked for one at a time while paused, not yet played.
    single: u64,
    /// The end state has been checked against the recording.
    checked: bool,
}

/// The window and what draws into it.
struct Screen {
    // Dropped in this order: GL objects before the display, the display before the window.
    bodies: Option<BodyRenderer>,
    /// The kernel renderer's frames on the GPU, in a GL pixel buffer registered with CUDA:
    /// `Err` once that failed (GL not on the NVIDIA driver), and frames are uploaded.
    device_image: Result<Option<DeviceImage>, ()>,
    target: Option<Target>,
    picture: Upload,
    hud: Upload,
    overlay: Upload,
    /// The text and scale the overlay texture holds.
    overlay_shown: Option<(Vec<String>, u32)>,
    blit: Blit,
    display: Display<WindowSurface>,
    window: Window,
}

/// One game in progress and what the loop knows of it.
struct Round<'d> {
    game: Game<'d>,
    record: Record,
    submitted: u64,
    clock: Clock,
    scored: bool,
}

/// The window's loop and its state; what it does is split by kind: playing the steps
/// ([`steps`]), the player's input ([`input`]), drawing ([`draw`]) and winit's calls
/// ([`events`]).
struct App<'d> {
    device: &'d Device,
    scene: Scene,
    options: PlayOptions,
    screen: Option<Screen>,
    round: Round<'d>,
    controls: Controls,
    /// The gamepads, when a player flies the ship.
    gamepads: Option<Gamepads>,
    /// A replay playing instead of a game.
    watch: Option<Watch>,
    /// The first key, click or button has come (the start screen is gone).
    begun: bool,
    paused: bool,
    help: bool,
    sound: Sound,
    /// The high scores, where the user has a data folder.
    scores: Option<HighScores>,
    flash: u32,
    frames: u64,
    started: Instant,
    /// Frames and steps over the last HUD period, for its rates.
    rates: (u64, u64, Instant),
    shown: (f64, f64),
    hud_at: Option<Instant>,
    renderer: String,
    failure: Option<anyhow::Error>,
    /// The benchmark's loop, when `measure` runs the window.
    bench: Option<Bench>,
    /// What the frames show.
    camera: Camera,
    /// When the last frame was drawn: the camera glides by the time since.
    drawn_at: Option<Instant>,
    /// The camera as the host follows it, from the statuses read back, with the device's
    /// own functions: the view the mouse aims through (the device's, a few steps late).
    aim_camera: CameraState,
    /// The last frame's view by [`App::aim_camera`].
    aim_view: Option<Framing>,
}

impl<'d> App<'d> {
    fn new(
        device: &'d Device,
        scene: &Scene,
        options: PlayOptions,
        watch: Option<Watch>,
    ) -> anyhow::Result<Self> {
        let round = Round::new(device, scene, &options)?;
        let scores = match highscore::default_path() {
            Some(path) => {
                let (scores, problem) = HighScores::load(path);
                if let Some(problem) = problem {
                    eprintln!("gpuwars: {problem}: it will be replaced");
                }
                Some(scores)
            }
            None => None,
        };
        let now = Instant::now();
        Ok(App {
            device,
            scene: scene.clone(),
            sound: Sound::open(options.muted),
            scores,
            screen: None,
            round,
            controls: Controls::new(),
            gamepads: (options.pilot == Flyer::Human && watch.is_none()).then(Gamepads::open),
            // A replay plays at once: nobody is there to start it.
            begun: watch.is_some(),
            watch,
            paused: false,
            help: false,
            flash: 0,
            frames: 0,
            started: now,
            rates: (0, 0, now),
            shown: (0.0, 0.0),
            hud_at: None,
            renderer: String::new(),
            failure: None,
            bench: None,
            camera: Camera::default(),
            drawn_at: None,
            aim_camera: CameraState::default(),
            aim_view: None,
            options,
        })
    }

    /// The last game's report, its replay written if asked; the window's failure if one
    /// closed it.
    fn finish(mut self) -> anyhow::Result<PlayReport> {
        // GL goes before the game's device buffers that interop registered.
        self.screen = None;
        if let Some(error) = self.failure.take() {
            return Err(error);
        }
        while let Some(status) = self.round.game.next_status()? {
            self.take(status);
        }
        if self.at_end() {
            self.check_replay()?;
        }
        self.keep_score();
        let hash = self.round.game.state_hash()?;
        let record = &self.round.record;
        let status = record.last;
        let played = record.inputs.len() as u64;
        if let Some(path) = &self.options.record {
            let replay = Replay {
                version: crate::game::replay::VERSION,
                scene: self.scene.name.clone(),
                scene_toml: self.scene.source.clone(),
                seed: self.options.seed,
                backend: self.device.kind(),
                state_hash: hash,
                inputs: record.inputs.clone(),
            };
            replay.save(path)?;
        }
        let seconds = self.started.elapsed().as_secs_f64().max(1e-9);
        Ok(PlayReport {
            backend: self.device.kind(),
            device: device_name(self.device),
            renderer: self.renderer,
            scene: self.scene.name.clone(),
            seed: self.options.seed,
            steps: played,
            game_seconds: played as f64 * f64::from(self.scene.world.dt),
            state_hash: format!("{hash:#018x}"),
            score: status.score,
            enemies_killed: status.enemies_killed,
            fps_meter: status.fps_meter,
            game_over: status.is_over(),
            frames: self.frames,
            frame_rate: self.frames as f64 / seconds,
            behind: match self.watch {
                Some(_) => None,
                None => behind(
                    &self.scene.name,
                    self.scene.world.dt,
                    played,
                    self.round.clock.given_up(),
                ),
            },
            replay: self.watch.as_ref().map(|w| match w.checked {
                true => "the end state matches the recording".into(),
                false => format!(
                    "stopped at step {} of {}: the end state was not checked",
                    played,
                    w.replay.inputs.len()
                ),
            }),
        })
    }
}

impl<'d> Round<'d> {
    fn new(device: &'d Device, scene: &Scene, options: &PlayOptions) -> anyhow::Result<Self> {
        let game = Game::with_options(
            device,
            scene,
            options.seed,
            Options {
                lag: options.lag,
                ..Options::default()
            },
        )?;
        Ok(Round {
            game,
            record: Record::default(),
            submitted: 0,
            clock: Clock::new(scene.world.dt),
            scored: false,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::behind;

    #[test]
    fn a_game_that_fell_behind_is_told_how_to_tune_its_scene() {
        // Kept up, or gave up 1%: nothing to say.
        assert_eq!(behind("paper", 1.0 / 60.0, 6000, 0.0), None);
        assert_eq!(behind("paper", 1.0 / 60.0, 6000, 1.0), None);
        // 60 s of game time played, 60 s given up: half the steps a second.
        let advice = behind("paper", 1.0 / 60.0, 3600, 60.0).unwrap();
        assert!(
            advice.contains("played 50%") && advice.contains("30 of the 60"),
            "{advice}"
        );
        assert!(
            advice.contains("gpuwars tune --scene paper --steps-per-second 60"),
            "{advice}"
        );
    }
}
