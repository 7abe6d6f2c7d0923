//! `gpuwars play` in a real window on a virtual display (Xvfb), treated roughly: a storm of
//! keys, every key held at once, the window shrunk to one pixel and back, hidden and shown
//! again (losing and regaining focus), closed by Esc or destroyed by the display mid-frame,
//! and random sequences of such events. No panic; the game ends cleanly, and its recording
//! replays headless to the state the window's game ended in.

mod common;

use std::path::Path;
use std::process::Command;
use std::sync::Mutex;

use gpuwars::demo::{self, RunOptions};
use gpuwars::game::replay::Replay;

/// One window at a time: two would share the machine's cores and the display server.
static ONE_WINDOW: Mutex<()> = Mutex::new(());

/// Opens the window, focused, and presses a first key (for a game that waits for one).
const OPEN: &str = r#"
set -u
"$GPUWARS" --backend cpu play --scene paper --seed 3 --mute --size 640x360 \
    --record "$DIR/played.json" >"$DIR/out.txt" 2>"$DIR/err.txt" &
pid=$!
win=$(timeout 120 xdotool search --sync --name '^GpuWars' | head -n 1)
xdotool windowfocus --sync "$win"
xdotool key space
sleep 1
"#;

/// The rough treatment.
const ROUGH: &str = r#"
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
"#;

/// Esc (`END=escape`) or the window destroyed (`END=destroy`), then the game's end. The
/// window is shown and focused first (hiding it, with no window manager, leaves the focus
/// nowhere); a game still running a minute later is stopped and the test fails.
const CLOSE: &str = r#"
xdotool windowmap "$win"
xdotool windowfocus --sync "$win"
if [ "$END" = destroy ]; then xdotool windowclose "$win"; else xdotool key Escape; fi
for i in $(seq 1 60); do kill -0 "$pid" 2>/dev/null || break; sleep 1; done
if kill -0 "$pid" 2>/dev/null; then
  echo "the game still ran a minute after $END" >>"$DIR/err.txt"
  kill "$pid"
fi
wait "$pid"
"#;

/// Keys and window actions drawn at random from `seed` (xorshift): what a script does
/// between [`OPEN`] and [`CLOSE`].
fn random_events(mut seed: u64, count: usize) -> String {
    const KEYS: &[&str] = &[
        "w",
        "a",
        "s",
        "d",
        "Up",
        "Down",
        "Left",
        "Right",
        "p",
        "m",
        "r",
        "F1",
        "F11",
        "x",
        "space",
        "Tab",
        "Return",
        "Shift_L",
        "Control_L",
        "plus",
        "minus",
        "KP_Add",
    ];
    let mut next = move |n: usize| {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed % n as u64) as usize
    };
    let mut script = String::new();
    for _ in 0..count {
        let key = KEYS[next(KEYS.len())];
        script += &match next(9) {
            0..=2 => format!("xdotool key --delay 0 {key}\n"),
            3 => format!("xdotool keydown {key}\n"),
            4 => format!("xdotool keyup {key}\n"),
            5 => format!(
                "xdotool windowsize \"$win\" {} {}\n",
                1 + next(1200),
                1 + next(800)
            ),
            6 => "xdotool windowunmap \"$win\"; xdotool windowmap \"$win\"\n".to_owned(),
            7 => "xdotool windowfocus \"$win\"\n".to_owned(),
            _ => format!("sleep 0.{}\n", next(4)),
        };
    }
    script
}

/// Runs [`OPEN`], `events` and [`CLOSE`] under `xvfb-run`, ending with `end`; returns its
/// output.
fn play_with(dir: &Path, events: &str, end: &str) -> std::process::Output {
    for tool in ["xvfb-run", "xdotool"] {
        let found = Command::new("which").arg(tool).output();
        assert!(
            found.is_ok_and(|o| o.status.success()),
            "{tool} not installed: run scripts/setup"
        );
    }
    Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 1024x768x24", "bash", "-c"])
        .arg(format!("{OPEN}{events}{CLOSE}"))
        .env("GPUWARS", env!("CARGO_BIN_EXE_gpuwars"))
        .env("DIR", dir)
        .env("END", end)
        .env("GPUWARS_DATA_DIR", dir)
        .env("LIBGL_ALWAYS_SOFTWARE", "1")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("xvfb-run runs")
}

fn survives(events: &str, end: &str) {
    let _one = ONE_WINDOW.lock().unwrap_or_else(|e| e.into_inner());
    let dir = tempfile::tempdir().unwrap();
    let out = play_with(dir.path(), events, end);
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
    let scene = replay.scene("the replay").unwrap();
    let report = demo::replay(common::cpu(), &scene, &replay, RunOptions::default()).unwrap();
    assert_eq!(report.state_hash, format!("{:#018x}", replay.state_hash));
    assert!(stdout.contains(&report.state_hash), "{end}: {stdout}");
}

#[test]
#[cfg_attr(
    not(unix),
    ignore = "drives the window with Linux tools (xvfb-run, xdotool): scripts/windows-check plays a Wine window instead"
)]
fn a_window_treated_roughly_and_closed_with_esc_keeps_its_game() {
    survives(ROUGH, "escape");
}

#[test]
#[cfg_attr(
    not(unix),
    ignore = "drives the window with Linux tools (xvfb-run, xdotool): scripts/windows-check plays a Wine window instead"
)]
fn a_window_destroyed_by_the_display_keeps_its_game() {
    survives(ROUGH, "destroy");
}

/// Random window events, from `GPUWARS_WINDOW_SEED` (a new seed each run otherwise, printed
/// to repeat a failure).
#[test]
#[cfg_attr(
    not(unix),
    ignore = "drives the window with Linux tools (xvfb-run, xdotool): scripts/windows-check plays a Wine window instead"
)]
fn random_window_events_keep_the_game() {
    let seed = std::env::var("GPUWARS_WINDOW_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| {
            let now = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH);
            now.map_or(1, |d| d.as_nanos() as u64) | 1
        });
    println!("GPUWARS_WINDOW_SEED={seed}");
    survives(&random_events(seed, 300), "escape");
}
