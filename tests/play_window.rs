//! `gpuwars play` in a real window, on a virtual display (Xvfb, Mesa's GL): real key events
//! move the ship and fire, the game runs ten seconds and ends cleanly on Esc, and the game
//! played in the window replays headless to the same state.

mod common;

use std::path::Path;
use std::process::Command;
use std::sync::Mutex;

use gpuwars::game::demo::{self, RunOptions};
use gpuwars::game::highscore::{self, HighScores};
use gpuwars::game::replay::Replay;
use gpuwars::game::{Game, Scene};
use gpuwars::kernels::game::control::{AIM_STEPS, Input, MOVE_SCALE};

/// One window at a time: two would share the machine's cores and the display server.
static ONE_WINDOW: Mutex<()> = Mutex::new(());

/// Opens the window under `xvfb-run`, holds D and → for five seconds, then W and ↑ for
/// five more, then presses Esc; returns the process's output.
fn play_scripted(dir: &Path, renderer: &str) -> std::process::Output {
    let script = r#"
set -eu
"$GPUWARS" --backend cpu play --scene paper --seed 3 --mute --size 640x360 \
    --render "$RENDERER" --record "$DIR/played.json" >"$DIR/out.txt" 2>"$DIR/err.txt" &
pid=$!
win=$(timeout 120 xdotool search --sync --name '^GpuWars' | head -n 1)
xdotool windowfocus --sync "$win"
xdotool keydown d keydown Right
sleep 5
xdotool keyup d keyup Right keydown w keydown Up
sleep 5
xdotool keyup w keyup Up key Escape
wait "$pid"
"#;
    let missing: Vec<_> = ["xvfb-run", "xdotool"]
        .into_iter()
        .filter(|tool| {
            Command::new("which")
                .arg(tool)
                .output()
                .is_ok_and(|o| !o.status.success())
        })
        .collect();
    assert!(
        missing.is_empty(),
        "{missing:?} not installed: run scripts/setup"
    );
    Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 1024x768x24", "bash", "-c", script])
        .env("GPUWARS", env!("CARGO_BIN_EXE_gpuwars"))
        .env("RENDERER", renderer)
        .env("DIR", dir)
        .env("GPUWARS_DATA_DIR", dir)
        .env("LIBGL_ALWAYS_SOFTWARE", "1")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("xvfb-run runs")
}

fn keys_move_the_ship_and_the_game_replays(renderer: &str) {
    let _one = ONE_WINDOW.lock().unwrap_or_else(|e| e.into_inner());
    let dir = tempfile::tempdir().unwrap();
    let out = play_scripted(dir.path(), renderer);
    let read = |name: &str| std::fs::read_to_string(dir.path().join(name)).unwrap_or_default();
    let (stdout, stderr) = (read("out.txt"), read("err.txt"));
    assert!(
        out.status.success(),
        "play failed: {}\n{}\nstdout: {stdout}\nstderr: {stderr}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    let replay = Replay::load(&dir.path().join("played.json")).unwrap();
    let steps = replay.inputs.len();
    println!("{renderer}: {steps} steps played in the window\n{stdout}");
    // Ten seconds of keys: at least a few seconds of game time even on a slow machine.
    assert!(steps >= 120, "only {steps} steps played");
    let is_right = |i: &Input| i.move_x == MOVE_SCALE && i.move_y == 0 && i.fire == 1 && i.aim == 0;
    let is_up = |i: &Input| {
        i.move_y == MOVE_SCALE && i.move_x == 0 && i.fire == 1 && i.aim == AIM_STEPS / 4
    };
    let right: Vec<usize> = (0..steps)
        .filter(|&s| is_right(&replay.inputs[s]))
        .collect();
    let up: Vec<usize> = (0..steps).filter(|&s| is_up(&replay.inputs[s])).collect();
    assert!(
        right.len() > 30 && up.len() > 30,
        "D+→ for {} steps, W+↑ for {}",
        right.len(),
        up.len()
    );

    // The same game, headless: the same final state as the window's.
    let cpu = common::cpu();
    let scene = Scene::from_toml(&replay.scene_toml, "the replay").unwrap();
    let report = demo::replay(cpu, &scene, &replay, RunOptions::default()).unwrap();
    assert_eq!(report.state_hash, format!("{:#018x}", replay.state_hash));
    assert!(stdout.contains(&report.state_hash), "{stdout}");
    // The score was kept, in the data folder the environment named.
    let (scores, problem) = HighScores::load(dir.path().join(highscore::FILE_NAME));
    assert!(problem.is_none(), "{problem:?}");
    assert_eq!(
        scores.best("paper").map(|e| e.score),
        Some(report.score),
        "the game's score is the scene's best"
    );

    // The ship went right, then up.
    let mut game = Game::new(cpu, &scene, replay.seed).unwrap();
    let ship = game.pipeline().layout().ranges
        [scene.world.kind_index(&scene.game.ship.kind).unwrap()]
    .start as usize;
    // Where it was before D went down, when D came up, and when W came up.
    let marks = [right[0], right[right.len() - 1] + 1, up[up.len() - 1] + 1];
    let mut at = Vec::new();
    for (i, input) in replay.inputs.iter().enumerate() {
        if marks.contains(&i) {
            at.push(game.snapshot().unwrap().pos[ship]);
        }
        game.step(Some(*input)).unwrap();
    }
    if at.len() < 3 {
        at.push(game.snapshot().unwrap().pos[ship]);
    }
    assert!(at[1].x > at[0].x + 10.0, "D moved the ship right: {at:?}");
    assert!(at[2].y > at[1].y + 10.0, "W moved the ship up: {at:?}");
}

#[test]
fn the_kernel_renderer_window_plays() {
    keys_move_the_ship_and_the_game_replays("kernel");
}

#[test]
fn the_interop_renderer_window_plays() {
    keys_move_the_ship_and_the_game_replays("interop");
}
