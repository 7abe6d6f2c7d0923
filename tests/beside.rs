//! A frame drawn beside the next step (`Game::submit_beside_frame`) is the frame drawn
//! before it, pixel for pixel, and the step the step taken alone, bit for bit: the whole
//! field and the view followed, with explosions and without, through the world's
//! renumbering, on either backend and whatever the schedule.

mod common;

use common::game::{crashing, without_effects};
use gpuwars::Device;
use gpuwars::backend::Schedule;
use gpuwars::camera::Camera;
use gpuwars::game::scene::built_in;
use gpuwars::game::{Game, Scene};
use gpuwars::pipeline::draw::Frame;

/// Frame size: small, and not a multiple of a warp's pixels.
const SIZE: (u32, u32) = (320, 182);

/// Every `every`-th frame of `steps` loops of `scene` through `camera`, and the state hash
/// after them: each loop a step and a frame of the world before it, drawn beside the step
/// (`beside`) or before it.
fn loops(
    device: &Device,
    scene: &Scene,
    camera: &Camera,
    (steps, every): (u32, u32),
    beside: bool,
) -> (Vec<Frame>, u64) {
    let mut game = Game::new(device, scene, 3).unwrap();
    let mut frames = Vec::new();
    for step in 1..=steps {
        if beside {
            game.submit_beside_frame(None, SIZE, camera).unwrap();
        } else {
            game.render(SIZE.0, SIZE.1, camera, 0.0).unwrap();
            game.submit(None).unwrap();
        }
        if step % every == 0 {
            frames.push(game.pipeline().frame().unwrap());
        }
    }
    (frames, game.state_hash().unwrap())
}

/// The frames and the state of loops beside the step are those of loops one after the
/// other: `paper` (renumbering every few steps), kamikazes crashing into the ship (a burst
/// of particles nearly every step) and the same without explosions, the field and the ship
/// followed.
fn a_frame_beside_the_step_is_the_frame_before_it(device: &Device) {
    let paper = built_in("paper").unwrap().unwrap();
    for scene in [paper, crashing(), without_effects(&crashing())] {
        for camera in [Camera::field(), Camera::default()] {
            let serial = loops(device, &scene, &camera, (90, 9), false);
            let beside = loops(device, &scene, &camera, (90, 9), true);
            assert_eq!(beside.1, serial.1, "{} {camera:?}: the state", scene.name);
            for (i, (a, b)) in beside.0.iter().zip(&serial.0).enumerate() {
                let differ = a.pixels.iter().zip(&b.pixels).filter(|(a, b)| a != b);
                assert!(
                    a == b,
                    "{} {camera:?}, frame {i}: {} pixels differ",
                    scene.name,
                    differ.count()
                );
            }
            // Frames that show something: not every pixel the background's.
            assert!(
                serial
                    .0
                    .iter()
                    .all(|f| f.pixels.iter().any(|&p| p != f.pixels[0]))
            );
        }
    }
}

on_both_backends!(a_frame_beside_the_step_is_the_frame_before_it);

/// Under a shuffled schedule the frame's branch starts before the step or after it, on a
/// thread of its own: the frames and the state are still those drawn one after the other.
#[test]
fn frames_beside_the_step_do_not_depend_on_the_schedule() {
    let paper = built_in("paper").unwrap().unwrap();
    let serial = loops(common::cpu(), &paper, &Camera::default(), (60, 12), false);
    for seed in [1, 2, 3] {
        let shuffled =
            Device::cpu_scheduled(Some(2), Schedule::Shuffled { seed }, "tests").unwrap();
        let beside = loops(&shuffled, &paper, &Camera::default(), (60, 12), true);
        assert!(beside == serial, "seed {seed}");
    }
}
