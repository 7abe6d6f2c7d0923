//! One command a step from every device: synthetic keys, mouse positions and buttons, and
//! stick deflections merged by `Controls` into the step's `Input`.

use glam::Vec2;
use gpuwars::kernels::game::control::{AIM_STEPS, Input, MOVE_SCALE};
use gpuwars::play::controls::{Aimer, Controls, DEAD_ZONE, Pad, beyond_dead_zone};
use winit::keyboard::KeyCode;

/// The aim `turns` of a full turn counter-clockwise from +x.
fn turns(turns: f32) -> u32 {
    (turns * AIM_STEPS as f32).round() as u32 % AIM_STEPS
}

/// Where the ship is drawn in these tests, in window pixels.
const SHIP: Vec2 = Vec2::new(320.0, 180.0);

#[test]
fn the_mouse_aims_at_the_cursor_and_fires_while_the_left_button_is_down() {
    let mut controls = Controls::new();
    // Right of the ship (window y points down).
    controls.cursor(SHIP + Vec2::new(100.0, 0.0));
    assert_eq!(controls.aimer(), Aimer::Mouse);
    let input = controls.input(SHIP);
    assert_eq!((input.aim, input.fire), (0, 0), "aims right, holds fire");
    controls.click(true);
    let input = controls.input(SHIP);
    assert_eq!((input.aim, input.fire), (0, 1));
    // Above the ship on screen: a quarter turn; below it, three quarters; up-left, 3/8.
    for (offset, expected) in [
        (Vec2::new(0.0, -50.0), 0.25),
        (Vec2::new(0.0, 80.0), 0.75),
        (Vec2::new(-30.0, -30.0), 0.375),
        (Vec2::new(-200.0, 0.0), 0.5),
    ] {
        controls.cursor(SHIP + offset);
        let input = controls.input(SHIP);
        assert_eq!(input.aim, turns(expected), "cursor at {offset}");
        assert_eq!(input.fire, 1);
        assert_eq!(
            (input.move_x, input.move_y),
            (0, 0),
            "the mouse does not move"
        );
    }
    // The ship moved under a still cursor: the aim follows.
    let cursor = SHIP + Vec2::new(-200.0, 0.0);
    let input = controls.input(cursor + Vec2::new(0.0, 10.0));
    assert_eq!(input.aim, turns(0.25));
    controls.click(false);
    let input = controls.input(SHIP);
    assert_eq!((input.aim, input.fire), (turns(0.5), 0));
    // The cursor right on the ship: no direction, the last aim stays.
    controls.cursor(SHIP);
    assert_eq!(controls.input(SHIP).aim, turns(0.5));
}

#[test]
fn keys_move_and_aim_in_eight_directions() {
    let mut controls = Controls::new();
    assert_eq!(controls.input(SHIP), Input::default(), "nothing held");
    controls.key(KeyCode::KeyD, true);
    controls.key(KeyCode::KeyW, true);
    assert!(controls.key(KeyCode::ArrowLeft, true));
    let input = controls.input(SHIP);
    let diagonal = (MOVE_SCALE as f32 / 2f32.sqrt()).round() as i32;
    assert_eq!((input.move_x, input.move_y), (diagonal, diagonal));
    assert_eq!((input.aim, input.fire), (turns(0.5), 1));
    controls.key(KeyCode::ArrowLeft, false);
    let input = controls.input(SHIP);
    assert_eq!((input.aim, input.fire), (turns(0.5), 0), "keeps its aim");
    assert!(
        !controls.key(KeyCode::KeyP, true),
        "P neither moves nor aims"
    );
}

#[test]
fn sticks_move_aim_and_fire_beyond_the_dead_zone() {
    let mut controls = Controls::new();
    // Inside the dead zone: nothing, and the keys keep the aim.
    controls.left_stick(Vec2::new(0.2, -0.1));
    controls.right_stick(Vec2::new(0.0, 0.2));
    assert_eq!(controls.aimer(), Aimer::Keys);
    assert_eq!(controls.input(SHIP), Input::default());
    // Full deflection up-right, both sticks.
    let corner = Vec2::new(1.0, 1.0).normalize();
    controls.left_stick(corner);
    controls.right_stick(Vec2::new(-1.0, 0.0));
    assert_eq!(controls.aimer(), Aimer::Stick);
    let input = controls.input(SHIP);
    let diagonal = (MOVE_SCALE as f32 / 2f32.sqrt()).round() as i32;
    assert_eq!((input.move_x, input.move_y), (diagonal, diagonal));
    assert_eq!((input.aim, input.fire), (turns(0.5), 1));
    // Half way out of the dead zone, half speed.
    controls.left_stick(Vec2::new(0.0, -(1.0 + DEAD_ZONE) / 2.0));
    let input = controls.input(SHIP);
    assert_eq!((input.move_x, input.move_y), (0, -MOVE_SCALE / 2));
    // A diagonal of the right stick: an eighth of a turn down-right.
    controls.right_stick(Vec2::new(0.6, -0.6));
    assert_eq!(controls.input(SHIP).aim, turns(0.875));
    // Let go: no fire, the aim stays.
    controls.right_stick(Vec2::new(0.05, 0.0));
    let input = controls.input(SHIP);
    assert_eq!((input.aim, input.fire), (turns(0.875), 0));
    // A stick pushed past the edge (some pads report a square) stays at full speed.
    assert!((beyond_dead_zone(Vec2::new(1.0, 1.0)).length() - 1.0).abs() < 1e-6);
    assert_eq!(beyond_dead_zone(Vec2::NAN), Vec2::ZERO);
}

#[test]
fn keys_stick_and_d_pad_add_up_to_full_speed_at_most() {
    let mut controls = Controls::new();
    controls.key(KeyCode::KeyD, true);
    controls.left_stick(Vec2::new(1.0, 0.0));
    controls.pad(Pad::Right, true);
    let input = controls.input(SHIP);
    assert_eq!((input.move_x, input.move_y), (MOVE_SCALE, 0));
    // Opposite devices cancel.
    controls.key(KeyCode::KeyD, false);
    controls.left_stick(Vec2::ZERO);
    controls.pad(Pad::Right, false);
    controls.pad(Pad::Down, true);
    controls.key(KeyCode::KeyW, true);
    assert_eq!(controls.input(SHIP), Input::default());
    controls.release_all();
    controls.pad(Pad::Left, true);
    let input = controls.input(SHIP);
    assert_eq!((input.move_x, input.move_y), (-MOVE_SCALE, 0));
}

#[test]
fn the_device_used_last_aims() {
    let mut controls = Controls::new();
    controls.cursor(SHIP + Vec2::new(0.0, -10.0));
    controls.click(true);
    assert_eq!(controls.input(SHIP).aim, turns(0.25));
    // An arrow takes the aim back from the mouse, though the button is still down.
    controls.key(KeyCode::ArrowDown, true);
    assert_eq!(controls.aimer(), Aimer::Keys);
    assert_eq!(controls.input(SHIP).aim, turns(0.75));
    controls.key(KeyCode::ArrowDown, false);
    // A key that only moves does not.
    controls.cursor(SHIP + Vec2::new(10.0, 0.0));
    controls.key(KeyCode::KeyA, true);
    assert_eq!(controls.aimer(), Aimer::Mouse);
    let input = controls.input(SHIP);
    assert_eq!((input.aim, input.fire, input.move_x), (0, 1, -MOVE_SCALE));
    // The right stick takes it, and the mouse moving takes it back.
    controls.right_stick(Vec2::new(0.0, 1.0));
    assert_eq!(controls.input(SHIP).aim, turns(0.25));
    controls.cursor(SHIP + Vec2::new(0.0, 10.0));
    assert_eq!(controls.input(SHIP).aim, turns(0.75));
    // Losing the focus lets go of everything, and the ship keeps its aim.
    controls.release_all();
    let input = controls.input(SHIP);
    assert_eq!((input.move_x, input.fire, input.aim), (0, 0, turns(0.75)));
}
