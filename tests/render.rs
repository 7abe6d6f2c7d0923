//! The kernel renderer: each body in its kind's colour at its place, the background
//! elsewhere, the top layer where bodies overlap, and the same pixels whatever the schedule
//! and on either backend.

mod common;

use common::sim::{circle, kind, rect, world};
use glam::Vec2;
use glium::texture::RawImage2d;
use gpuwars::Device;
use gpuwars::backend::Schedule;
use gpuwars::game::looks::{BACKGROUND, rgb};
use gpuwars::game::scene::built_in;
use gpuwars::game::{Game, Scene};
use gpuwars::graphics::bodies::BodyRenderer;
use gpuwars::graphics::headless::Headless;
use gpuwars::graphics::picture::DeviceImage;
use gpuwars::kernels::render::{Look, View};
use gpuwars::pipeline::Pipeline;
use gpuwars::pipeline::Simulation;
use gpuwars::pipeline::draw::Frame;
use gpuwars::sim::layout::kind_table;
use gpuwars::sim::{Boundary, WorldSpec};
use gpuwars::{BackendKind, game::looks};

/// A look with a nose and a hurt shade of its own colour, so a kind is one colour.
fn look(colour: u32, layer: u32) -> Look {
    Look {
        colour,
        nose: colour,
        layer,
        hurt: colour,
    }
}

/// Three kinds: a big circle, a rectangle, and a circle smaller than a pixel, in a 400 × 300
/// world shown one unit per pixel.
fn three_kinds() -> (WorldSpec, Vec<Look>) {
    let spec = world(
        Vec2::new(400.0, 300.0),
        Boundary::Clamp,
        vec![
            kind("big", circle(20.0), 2, &[]),
            kind("box", rect(12.0, 6.0), 1, &[]),
            kind("dot", circle(0.3), 1, &[]),
        ],
    );
    let looks = vec![
        look(rgb(200, 30, 30), 1),
        look(rgb(30, 200, 30), 5),
        look(rgb(30, 30, 200), 3),
    ];
    (spec, looks)
}

/// The pixel under world position `pos` in `view`.
fn pixel_at(frame: &Frame, view: &View, pos: Vec2) -> u32 {
    let p = view.to_image(pos);
    frame.pixel(p.x as u32, p.y as u32)
}

/// The three kinds' bodies placed in `sim`: (slot, position) of a big circle, a second big
/// circle under a box, the box, and a sub-pixel dot.
fn place_three(sim: &mut Simulation) -> [(u32, Vec2); 4] {
    let ranges = sim.layout().ranges.clone();
    let big = (ranges[0].start, Vec2::new(80.0, 200.0));
    // The box overlaps the second big circle: the box's layer is higher.
    let big_under = (ranges[0].start + 1, Vec2::new(300.0, 100.0));
    let boxed = (ranges[1].start, Vec2::new(310.0, 100.0));
    let dot = (ranges[2].start, Vec2::new(150.5, 50.5));
    let bodies = [big, big_under, boxed, dot];
    let placed: Vec<_> = bodies.iter().map(|&(s, p)| (s, p, Vec2::X)).collect();
    sim.place(&placed).unwrap();
    bodies
}

/// Checks a frame of the bodies of [`place_three`] against their shapes: each body's
/// colour at its place, the top layer where they overlap, every kind's colour present, and
/// the background far from every body.
fn check_three(frame: &Frame, view: &View, looks: &[Look], bodies: [(u32, Vec2); 4]) {
    let [big, big_under, boxed, dot] = bodies;
    let colour = |k: usize| looks[k].colour;
    // Each body's centre is its colour; the overlap is the box's.
    assert_eq!(pixel_at(frame, view, big.1), colour(0));
    assert_eq!(pixel_at(frame, view, boxed.1), colour(1));
    assert_eq!(pixel_at(frame, view, Vec2::new(304.0, 100.0)), colour(1));
    assert_eq!(pixel_at(frame, view, Vec2::new(285.0, 100.0)), colour(0));
    assert_eq!(
        pixel_at(frame, view, dot.1),
        colour(2),
        "a sub-pixel body still shows"
    );
    // Every pixel: well inside a body's shape, that body's kind (or one on top of it); well
    // outside every shape, the background. (A pixel's centre decides; the margin keeps the
    // check away from the rounding at the edge.)
    let shapes = [
        (big.1, 0, Vec2::splat(20.0)),
        (big_under.1, 0, Vec2::splat(20.0)),
        (boxed.1, 1, Vec2::new(12.0, 6.0)),
        (dot.1, 2, Vec2::splat(0.3)),
    ];
    let mut seen = [false; 3];
    for y in 0..frame.height {
        for x in 0..frame.width {
            let world_pos = view.origin
                + Vec2::new(x as f32 + 0.5, frame.height as f32 - y as f32 - 0.5) / view.scale;
            let got = frame.pixel(x, y);
            if let Some(k) = (0..3).find(|&k| got == colour(k)) {
                seen[k] = true;
            }
            let near = shapes.iter().any(|&(c, k, half)| {
                let d = world_pos - c;
                if k == 1 {
                    d.x.abs() <= half.x + 1.5 && d.y.abs() <= half.y + 1.5
                } else {
                    d.length() <= half.x + 1.5
                }
            });
            if !near {
                assert_eq!(got, BACKGROUND, "pixel ({x}, {y}) is far from every body");
            }
            let deep = shapes.iter().find(|&&(c, k, half)| {
                let d = world_pos - c;
                if k == 1 {
                    d.x.abs() <= half.x - 1.5 && d.y.abs() <= half.y - 1.5
                } else {
                    d.length() <= half.x - 1.5
                }
            });
            if let Some(&(_, k, _)) = deep {
                assert!(
                    got == colour(k) || looks[k].layer < looks[1].layer && got == colour(1),
                    "pixel ({x}, {y}) inside a body of kind {k} is {got:#010x}"
                );
            }
        }
    }
    assert_eq!(seen, [true; 3], "every kind's colour is in the frame");
}

fn a_frame_shows_each_body_in_its_kinds_colour(device: &Device) {
    let (spec, looks) = three_kinds();
    let mut sim = Simulation::new(device, &spec, 1).unwrap();
    let bodies = place_three(&mut sim);
    let view = View::whole(spec.size, 400, 300, BACKGROUND);
    let frame = sim.draw(&view, &looks).unwrap();
    check_three(&frame, &view, &looks, bodies);
    // Nothing alive, nothing drawn.
    let empty = Simulation::new(device, &spec, 1)
        .unwrap()
        .draw(&view, &looks)
        .unwrap();
    assert!(empty.pixels.iter().all(|&p| p == BACKGROUND));
}

fn bad_frames_are_refused(device: &Device) {
    let (spec, looks) = three_kinds();
    let mut sim = Simulation::new(device, &spec, 1).unwrap();
    let view = View::whole(spec.size, 400, 300, BACKGROUND);
    let err = sim.draw(&view, &looks[..2]).unwrap_err().to_string();
    assert!(err.contains("2 looks for a world of 3 kinds"), "{err}");
    let wide = View { width: 0, ..view };
    let err = sim.draw(&wide, &looks).unwrap_err().to_string();
    assert!(err.contains("0x300") && err.contains("1 to 16384"), "{err}");
    let flat = View { scale: 0.0, ..view };
    assert!(sim.draw(&flat, &looks).is_err());
}

fn paper() -> Scene {
    built_in("paper").unwrap().unwrap()
}

/// The frame of `paper` after `steps` autopilot steps.
fn paper_frame(device: &Device, steps: u32) -> Frame {
    let mut game = Game::new(device, &paper(), 1).unwrap();
    for _ in 0..steps {
        game.submit(None).unwrap();
    }
    game.draw(640, 360).unwrap()
}

#[test]
fn frames_do_not_depend_on_the_schedule() {
    let in_order = paper_frame(common::cpu(), 120);
    let shuffled = Device::cpu_scheduled(Some(2), Schedule::Shuffled { seed: 9 }, "tests").unwrap();
    assert_eq!(paper_frame(&shuffled, 120).hash(), in_order.hash());
}

#[test]
fn the_gpu_draws_the_same_frame_as_the_cpu() {
    let Some(gpu) = common::gpu() else { return };
    let cpu = paper_frame(common::cpu(), 300);
    let on_gpu = paper_frame(gpu, 300);
    println!(
        "paper frame after 300 steps: cpu {:#018x}, gpu {:#018x}",
        cpu.hash(),
        on_gpu.hash()
    );
    assert_eq!(on_gpu, cpu);
}

/// A GL context without a window: NVIDIA's EGL device with the GPU (so that interop works),
/// Mesa's software device without.
fn headless(device: &Device) -> Headless {
    Headless::new(device.kind() == BackendKind::Cuda).expect("an EGL device (see scripts/setup)")
}

/// How many pixels of two frames of one size differ.
fn differing(a: &Frame, b: &Frame) -> usize {
    assert_eq!((a.width, a.height), (b.width, b.height));
    a.pixels
        .iter()
        .zip(&b.pixels)
        .filter(|(p, q)| p != q)
        .count()
}

/// The GL renderer's frame of `pipeline`, whose kinds are `spec`'s.
fn gl_frame(
    gl: &Headless,
    pipeline: &Pipeline,
    spec: &WorldSpec,
    looks: &[Look],
    view: &View,
) -> (Frame, bool) {
    let mut renderer = BodyRenderer::new(gl.facade(), pipeline, &kind_table(spec), looks).unwrap();
    if let Some(why) = renderer.fallback() {
        panic!("the GPU's vertices are uploaded: {why}");
    }
    let frame = gl.draw(&mut renderer, pipeline, view).unwrap();
    (frame, renderer.is_interop())
}

fn gl_draws_each_body_in_its_kinds_colour(device: &Device) {
    let gl = headless(device);
    let (spec, looks) = three_kinds();
    let mut sim = Simulation::new(device, &spec, 1).unwrap();
    let bodies = place_three(&mut sim);
    let view = View::whole(spec.size, 400, 300, BACKGROUND);
    let (frame, interop) = gl_frame(&gl, &sim, &spec, &looks, &view);
    assert_eq!(interop, device.kind() == BackendKind::Cuda);
    check_three(&frame, &view, &looks, bodies);
    let kernel = sim.draw(&view, &looks).unwrap();
    let differ = differing(&frame, &kernel);
    println!(
        "three bodies, GL on {}: {differ} of {} pixels differ from the kernel renderer's",
        gl.device(),
        frame.pixels.len()
    );
    assert!(
        differ <= 8,
        "only rounding at an edge may differ: {differ} pixels"
    );
}

fn gl_draws_a_game_as_the_kernel_does(device: &Device) {
    let gl = headless(device);
    let scene = paper();
    let mut game = Game::new(device, &scene, 1).unwrap();
    for _ in 0..300 {
        game.submit(None).unwrap();
    }
    let kernel = game.draw(640, 360).unwrap();
    let view = looks::whole_field(&scene, 640, 360);
    let looks = looks::looks(&scene);
    let (frame, _) = gl_frame(&gl, game.pipeline(), &scene.world, &looks, &view);
    let differ = differing(&frame, &kernel);
    println!(
        "paper after 300 steps, GL on {}: {differ} of {} pixels differ from the kernel \
         renderer's (frame hash {:#018x})",
        gl.device(),
        frame.pixels.len(),
        frame.hash()
    );
    let state = game.snapshot().unwrap();
    for kind in state.live().map(|slot| state.kind[slot] as usize) {
        let look = &looks[kind];
        let drawn = [look.colour, look.nose, look.hurt];
        assert!(
            frame.pixels.iter().any(|p| drawn.contains(p)),
            "kind {kind} lives but is not drawn"
        );
    }
    assert!(
        differ * 1000 <= frame.pixels.len(),
        "{differ} pixels differ"
    );
}

#[test]
fn the_gpus_interop_frame_matches_the_cpus() {
    let Some(gpu) = common::gpu() else { return };
    let gl = headless(gpu);
    let scene = paper();
    let mut game = Game::new(gpu, &scene, 1).unwrap();
    for _ in 0..300 {
        game.submit(None).unwrap();
    }
    let _ = game.snapshot().unwrap();
    let view = looks::whole_field(&scene, 640, 360);
    let looks = looks::looks(&scene);
    let (on_gpu, interop) = gl_frame(&gl, game.pipeline(), &scene.world, &looks, &view);
    assert!(interop);
    let cpu = paper_frame(common::cpu(), 300);
    println!(
        "paper after 300 steps: the H200's interop frame ({}) and the CPU's kernel frame \
         differ in {} of {} pixels (hashes {:#018x}, {:#018x})",
        gl.device(),
        differing(&on_gpu, &cpu),
        cpu.pixels.len(),
        on_gpu.hash(),
        cpu.hash()
    );
    assert!(differing(&on_gpu, &cpu) * 1000 <= cpu.pixels.len());
}

#[test]
fn kernel_frames_shown_from_a_gl_pixel_buffer_are_the_frames() {
    let Some(gpu) = common::gpu() else { return };
    let gl = headless(gpu);
    let mut game = Game::new(gpu, &paper(), 1).unwrap();
    for _ in 0..300 {
        game.submit(None).unwrap();
    }
    let (width, height) = (640, 360);
    let mut image = DeviceImage::new(gl.facade(), gpu, width, height).unwrap();
    // SAFETY: the mapped buffer holds the frame's pixels; only these launches touch it.
    let texture = image
        .set(|pixels| unsafe { game.render_into(width, height, pixels) })
        .unwrap();
    let shown: RawImage2d<u8> = texture.read();
    let shown = Frame {
        width,
        height,
        pixels: bytemuck::cast_slice(&shown.data).to_vec(),
    };
    let drawn = game.draw(width, height).unwrap();
    println!(
        "kernel frame through a GL pixel buffer on {}: {} of {} pixels differ",
        gl.device(),
        differing(&shown, &drawn),
        drawn.pixels.len()
    );
    assert_eq!(shown.hash(), drawn.hash());
}

on_both_backends!(
    a_frame_shows_each_body_in_its_kinds_colour,
    bad_frames_are_refused,
    gl_draws_each_body_in_its_kinds_colour,
    gl_draws_a_game_as_the_kernel_does,
);
