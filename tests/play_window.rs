//! `gpuwars play` in a real window, on a virtual display (Xvfb, Mesa's GL): real key and
//! mouse events move the ship, aim and fire, the game waits for the first key and ends
//! cleanly on Esc, and the game played in the window replays headless to the same state;
//! `gpuwars replay --window` plays a recording to its end and checks it.

mod common;

use std::path::Path;
use std::process::Command;
use std::sync::Mutex;

use gpuwars::demo::{self, RunOptions};
use gpuwars::game::Game;
use gpuwars::game::highscore::{self, HighScores};
use gpuwars::game::replay::Replay;
use gpuwars::kernels::game::control::{AIM_STEPS, Input, MOVE_SCALE};

/// One window at a time: two would share the machine's cores and the display server.
static ONE_WINDOW: Mutex<()> = Mutex::new(());

/// Runs `script` (bash) under `xvfb-run` with `$GPUWARS` the binary and `$DIR` the folder
/// (also the data folder), plus `env`; returns the process's output.
fn in_xvfb(dir: &Path, script: &str, env: &[(&str, &str)]) -> std::process::Output {
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
        .env("DIR", dir)
        .env("GPUWARS_DATA_DIR", dir)
        .env("LIBGL_ALWAYS_SOFTWARE", "1")
        .env_remove("WAYLAND_DISPLAY")
        .envs(env.iter().copied())
        .output()
        .expect("xvfb-run runs")
}

/// Starts `gpuwars play` on the paper scene recording to `$DIR/played.json`, finds and
/// focuses its window (`$win`) and runs `keys` (bash with xdotool) before waiting for it.
fn play_script(keys: &str) -> String {
    format!(
        r#"
set -eu
"$GPUWARS" --backend cpu play --scene paper --seed 3 --mute --size 640x360 \
    --render "${{RENDERER:-kernel}}" --record "$DIR/played.json" >"$DIR/out.txt" 2>"$DIR/err.txt" &
pid=$!
win=$(timeout 120 xdotool search --sync --name '^GpuWars' | head -n 1)
xdotool windowfocus --sync "$win"
{keys}
wait "$pid"
"#
    )
}

/// Asserts that the window's process succeeded without a panic; returns its stdout and
/// stderr (written to files in `dir`).
fn succeeded(dir: &Path, out: &std::process::Output) -> (String, String) {
    let read = |name: &str| std::fs::read_to_string(dir.join(name)).unwrap_or_default();
    let (stdout, stderr) = (read("out.txt"), read("err.txt"));
    assert!(
        out.status.success(),
        "the window failed: {}\n{}\nstdout: {stdout}\nstderr: {stderr}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    (stdout, stderr)
}

/// `gpuwars replay FILE` (headless) checks the recording; returns its report.
fn replays_headless(file: &Path) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_gpuwars"))
        .args(["--backend", "cpu", "replay"])
        .arg(file)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "the replay failed: {stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

fn keys_move_the_ship_and_the_game_replays(renderer: &str) {
    let _one = ONE_WINDOW.lock().unwrap_or_else(|e| e.into_inner());
    let dir = tempfile::tempdir().unwrap();
    // D going down starts the game and moves the ship; ten seconds of keys.
    let keys = "
xdotool keydown d keydown Right
sleep 5
xdotool keyup d keyup Right keydown w keydown Up
sleep 5
xdotool keyup w keyup Up key Escape";
    let out = in_xvfb(dir.path(), &play_script(keys), &[("RENDERER", renderer)]);
    let (stdout, _) = succeeded(dir.path(), &out);
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
    let scene = replay.scene("the replay").unwrap();
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
            at.push(game.snapshot().unwrap().bodies.pos[ship]);
        }
        game.step(Some(*input)).unwrap();
    }
    if at.len() < 3 {
        at.push(game.snapshot().unwrap().bodies.pos[ship]);
    }
    assert!(at[1].x > at[0].x + 10.0, "D moved the ship right: {at:?}");
    assert!(at[2].y > at[1].y + 10.0, "W moved the ship up: {at:?}");
}

#[test]
#[cfg_attr(
    not(unix),
    ignore = "drives the window with Linux tools (xvfb-run, xdotool): scripts/windows-check plays a Wine window instead"
)]
fn the_kernel_renderer_window_plays() {
    keys_move_the_ship_and_the_game_replays("kernel");
}

#[test]
#[cfg_attr(
    not(unix),
    ignore = "drives the window with Linux tools (xvfb-run, xdotool): scripts/windows-check plays a Wine window instead"
)]
fn the_interop_renderer_window_plays() {
    keys_move_the_ship_and_the_game_replays("interop");
}

#[test]
#[cfg_attr(
    not(unix),
    ignore = "drives the window with Linux tools (xvfb-run, xdotool): scripts/windows-check plays a Wine window instead"
)]
fn the_mouse_aims_at_the_cursor_and_fires() {
    let _one = ONE_WINDOW.lock().unwrap_or_else(|e| e.into_inner());
    let dir = tempfile::tempdir().unwrap();
    // The ship starts in the middle of the window: the cursor goes 200 pixels right of it,
    // the click starts the game, and the button stays down four seconds.
    let keys = "
xdotool mousemove --window \"$win\" 520 180
sleep 1
xdotool mousedown 1
sleep 4
xdotool mouseup 1
sleep 1
xdotool key Escape";
    let out = in_xvfb(dir.path(), &play_script(keys), &[]);
    succeeded(dir.path(), &out);
    let file = dir.path().join("played.json");
    let replay = Replay::load(&file).unwrap();
    let firing: Vec<&Input> = replay.inputs.iter().filter(|i| i.fire == 1).collect();
    assert!(
        firing.len() > 30,
        "fired {} steps of {}",
        firing.len(),
        replay.inputs.len()
    );
    // Every aim points right, towards the cursor, give or take the ship's drift (5°).
    let near_right = |aim: u32| aim.min(AIM_STEPS - aim) < AIM_STEPS / 72;
    let off: Vec<u32> = replay
        .inputs
        .iter()
        .map(|i| i.aim)
        .filter(|&aim| !near_right(aim))
        .collect();
    assert!(off.is_empty(), "aims not towards the cursor: {off:?}");
    assert!(
        replay.inputs.iter().all(|i| i.move_x == 0 && i.move_y == 0),
        "the mouse moved the ship"
    );
    // The shots were fired, and the recording replays headless to its hash.
    let report = replays_headless(&file);
    let shots: u64 = report
        .lines()
        .find_map(|l| l.strip_prefix("shots_fired:"))
        .and_then(|n| n.trim().parse().ok())
        .unwrap_or_else(|| panic!("no shots_fired in {report}"));
    assert!(shots > 5, "{shots} shots fired\n{report}");
    assert!(
        report.contains(&format!("{:#018x}", replay.state_hash)),
        "{report}"
    );
}

#[test]
#[cfg_attr(
    not(unix),
    ignore = "drives the window with Linux tools (xvfb-run, xdotool): scripts/windows-check plays a Wine window instead"
)]
fn the_start_screen_holds_the_game_until_a_key() {
    let _one = ONE_WINDOW.lock().unwrap_or_else(|e| e.into_inner());
    let dir = tempfile::tempdir().unwrap();
    // Three seconds on the start screen, the cursor moving over it, then Esc.
    let keys = "
xdotool mousemove --window \"$win\" 100 100
sleep 3
xdotool mousemove --window \"$win\" 300 200 key Escape";
    let out = in_xvfb(dir.path(), &play_script(keys), &[]);
    let (stdout, _) = succeeded(dir.path(), &out);
    let replay = Replay::load(&dir.path().join("played.json")).unwrap();
    assert_eq!(replay.inputs, [], "steps played before any key");
    assert!(stdout.contains("steps:            0 "), "{stdout}");
}

/// Watches `file` in a window until it says it ended (or the process ends), then presses
/// Esc; returns the output and the folder's stdout and stderr.
fn watch(dir: &Path, file: &Path) -> (std::process::Output, String, String) {
    let script = r#"
set -u
"$GPUWARS" --backend cpu replay "$FILE" --window --mute --size 320x180 \
    >"$DIR/out.txt" 2>"$DIR/err.txt" &
pid=$!
win=$(timeout 120 xdotool search --sync --name '^GpuWars' | head -n 1)
for _ in $(seq 300); do
    grep -q "in the recorded state" "$DIR/err.txt" && break
    kill -0 "$pid" 2>/dev/null || break
    sleep 1
done
xdotool windowfocus --sync "$win" key Escape 2>/dev/null || true
wait "$pid"
"#;
    let out = in_xvfb(dir, script, &[("FILE", file.to_str().unwrap())]);
    let read = |name: &str| std::fs::read_to_string(dir.join(name)).unwrap_or_default();
    (out, read("out.txt"), read("err.txt"))
}

#[test]
#[cfg_attr(
    not(unix),
    ignore = "drives the window with Linux tools (xvfb-run, xdotool): scripts/windows-check plays a Wine window instead"
)]
fn a_replay_plays_in_the_window_to_its_checked_end() {
    let _one = ONE_WINDOW.lock().unwrap_or_else(|e| e.into_inner());
    let dir = tempfile::tempdir().unwrap();
    let cpu = common::cpu();
    let scene = gpuwars::game::scene::built_in("paper").unwrap().unwrap();
    let options = RunOptions::default();
    let (_, replay) = demo::demo(cpu, &scene, 4, 90, options).unwrap();
    let file = dir.path().join("short.json");
    replay.save(&file).unwrap();
    let (out, stdout, stderr) = watch(dir.path(), &file);
    assert!(out.status.success(), "{stdout}\n{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(stdout.contains("steps:            90 "), "{stdout}");
    assert!(
        stdout.contains("replay:           the end state matches the recording"),
        "{stdout}"
    );
    assert!(
        stdout.contains(&format!("{:#018x}", replay.state_hash)),
        "{stdout}"
    );

    // A recording whose end state is not what it says: an error, naming the file.
    let mut wrong = replay.clone();
    wrong.state_hash ^= 1;
    let file = dir.path().join("wrong.json");
    wrong.save(&file).unwrap();
    let (out, stdout, stderr) = watch(dir.path(), &file);
    assert!(!out.status.success(), "{stdout}\n{stderr}");
    assert!(
        stderr.contains("wrong.json") && stderr.contains("was recorded ending in"),
        "{stderr}"
    );
}

#[test]
#[cfg_attr(
    not(unix),
    ignore = "drives the window with Linux tools (xvfb-run, xdotool): scripts/windows-check plays a Wine window instead"
)]
fn leaving_the_window_pauses_the_game_until_p() {
    let _one = ONE_WINDOW.lock().unwrap_or_else(|e| e.into_inner());
    let dir = tempfile::tempdir().unwrap();
    // D starts the game and moves right; the window is left (unmapped, so it loses the
    // focus) and shown again; W is held while paused, then P goes on and ← aims left.
    let keys = "
xdotool keydown d
sleep 2
xdotool keyup d
xdotool windowunmap --sync \"$win\"
sleep 1
xdotool windowmap --sync \"$win\"
xdotool windowfocus --sync \"$win\"
xdotool keydown w
sleep 2
xdotool keyup w key p keydown Left
sleep 2
xdotool keyup Left key Escape";
    let out = in_xvfb(dir.path(), &play_script(keys), &[]);
    succeeded(dir.path(), &out);
    let replay = Replay::load(&dir.path().join("played.json")).unwrap();
    let inputs = &replay.inputs;
    let right = inputs.iter().filter(|i| i.move_x == MOVE_SCALE).count();
    let left = inputs
        .iter()
        .filter(|i| i.aim == AIM_STEPS / 2 && i.fire == 1)
        .count();
    assert!(right > 10 && left > 10, "D for {right} steps, ← for {left}");
    assert!(
        inputs.iter().all(|i| i.move_y == 0),
        "W was held while paused, yet steps played"
    );
}
