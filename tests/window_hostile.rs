//! `gpuwars play` in a real window on a virtual display (Xvfb), treated roughly: a storm of
//! keys, every key held at once, the window shrunk to one pixel and back, hidden and shown
//! again (losing and regaining focus), and closed by Esc or destroyed by the display
//! mid-frame. No panic; the game ends cleanly, and its recording replays headless to the
//! state the window's game ended in.

mod common;

use std::path::Path;
use std::process::Command;
use std::sync::Mutex;

use gpuwars::game::Scene;
use gpuwars::game::demo::{self, RunOptions};
use gpuwars::game::replay::Replay;

/// One window at a time: two would share the machine's cores and the display server.
static ONE_WINDOW: Mutex<()> = Mutex::new(());

/// The rough treatment, then Esc (`END=escape`) or the window destroyed (`END=destroy`).
const SCRIPT: &str = r#"
set -u
"$GPUWARS" --backend cpu play --scene paper --seed 3 --mute --size 640x360 \
    --record "$DIR/played.json" >"$DIR/out.txt" 2>"$DIR/err.txt" &
pid=$!
win=$(timeout 120 xdotool search --sync --name '^GpuWars' | head -n 1)
xdotool windowfocus --sync "$win"
# A first key, for a game that waits for one.
xdotool key space
sleep 1
for i in $(seq 1 20); do
  xdotool key --delay 0 w a s d Up Down Left Right p p m m r F1 F1 x z 1 2 Tab Return space
done
keys="w a s d Up Down Left Right p m r F1 F11 F11 x z q e Shift_L Control_L Alt_L Tab space"
xdotool keydown $keys
sleep 1
xdotool keyup $keys
xdotool windowsize "$win" 1 1
sleep 1
xdotool windowsize "$win" 640 360
sleep 1
xdotool windowunmap "$win"
sleep 1
xdotool windowmap "$win"
xdotool windowfocus "$win"
xdotool keydown d
sleep 1
xdotool keyup d
if [ "$END" = destroy ]; then xdotool windowclose "$win"; else xdotool key Escape; fi
wait "$pid"
"#;

/// Runs [`SCRIPT`] under `xvfb-run`, ending with `end`; returns its output.
fn play_roughly(dir: &Path, end: &str) -> std::process::Output {
    for tool in ["xvfb-run", "xdotool"] {
        let found = Command::new("which").arg(tool).output();
        assert!(
            found.is_ok_and(|o| o.status.success()),
            "{tool} not installed: run scripts/setup"
        );
    }
    Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 1024x768x24", "bash", "-c", SCRIPT])
        .env("GPUWARS", env!("CARGO_BIN_EXE_gpuwars"))
        .env("DIR", dir)
        .env("END", end)
        .env("GPUWARS_DATA_DIR", dir)
        .env("LIBGL_ALWAYS_SOFTWARE", "1")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("xvfb-run runs")
}

fn survives(end: &str) {
    let _one = ONE_WINDOW.lock().unwrap_or_else(|e| e.into_inner());
    let dir = tempfile::tempdir().unwrap();
    let out = play_roughly(dir.path(), end);
    let read = |name: &str| std::fs::read_to_string(dir.path().join(name)).unwrap_or_default();
    let (stdout, stderr) = (read("out.txt"), read("err.txt"));
    assert!(
        out.status.success(),
        "{end}: play failed: {}\nstdout: {stdout}\nstderr: {stderr}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(!stderr.contains("panicked"), "{end}: {stderr}");
    assert!(!stderr.contains(".cargo/registry"), "{end}: {stderr}");
    // The recording is whole: it replays headless to the state the window's game ended in.
    let replay = Replay::load(&dir.path().join("played.json")).unwrap();
    assert!(!replay.inputs.is_empty(), "{end}: nothing was played");
    let scene = Scene::from_toml(&replay.scene_toml, "the replay").unwrap();
    let report = demo::replay(common::cpu(), &scene, &replay, RunOptions::default()).unwrap();
    assert_eq!(report.state_hash, format!("{:#018x}", replay.state_hash));
    assert!(stdout.contains(&report.state_hash), "{end}: {stdout}");
}

#[test]
fn a_window_treated_roughly_and_closed_with_esc_keeps_its_game() {
    survives("escape");
}

#[test]
fn a_window_destroyed_by_the_display_keeps_its_game() {
    survives("destroy");
}
