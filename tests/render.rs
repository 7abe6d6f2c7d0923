//! The kernel renderer: each body in its kind's colour and silhouette at its place, the
//! background elsewhere, the top layer where bodies overlap, the camera on the ship, the
//! radar, and the same pixels whatever the schedule and on either backend; the GL renderer
//! draws the same picture.

mod common;

use common::game::{crashing, without_effects};
use common::sim::{circle, kind, rect, world};
use glam::Vec2;
use glium::texture::RawImage2d;
use gpuwars::Device;
use gpuwars::backend::Schedule;
use gpuwars::camera::{self, Camera, CameraMode};
use gpuwars::game::looks::{BACKGROUND, rgb};
use gpuwars::game::scene::built_in;
use gpuwars::game::{Game, Scene};
use gpuwars::graphics::bodies::BodyRenderer;
use gpuwars::graphics::headless::Headless;
use gpuwars::graphics::picture::DeviceImage;
use gpuwars::kernels::registry;
use gpuwars::kernels::render::camera::{CameraState, Lens};
use gpuwars::kernels::render::radar::{self, radar_box};
use gpuwars::kernels::render::shapes::{self, DISC};
use gpuwars::kernels::render::{FOLD_CAMERA_SLOTS, Framing, Look, NO_SHIP, Shown, backdrop, fade};
use gpuwars::pipeline::Drawing;
use gpuwars::pipeline::Simulation;
use gpuwars::pipeline::draw::Frame;
use gpuwars::sim::{Boundary, WorldSpec};
use gpuwars::{BackendKind, game::looks};

/// A look with a nose and a hurt shade of its own colour, so a kind is one colour; a disc.
fn look(colour: u32, layer: u32) -> Look {
    Look {
        colour,
        nose: colour,
        layer,
        hurt: colour,
        silhouette: DISC,
        radar: 1,
    }
}

/// The whole field of a world of `size` with no ship in a `width × height` frame.
fn field_lens(size: Vec2, width: u32, height: u32) -> Lens {
    Camera::field().lens(size, (width, height), NO_SHIP, 0.0, BACKGROUND)
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
fn pixel_at(frame: &Frame, view: &Framing, pos: Vec2) -> u32 {
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
fn check_three(frame: &Frame, view: &Framing, looks: &[Look], bodies: [(u32, Vec2); 4]) {
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
    let view = Framing::whole(spec.size, 400, 300, BACKGROUND);
    let lens = field_lens(spec.size, 400, 300);
    let frame = sim.draw(&lens, &looks).unwrap();
    assert_eq!(
        sim.shown().unwrap().view,
        view,
        "the field camera shows it all"
    );
    check_three(&frame, &view, &looks, bodies);
    // Nothing alive, nothing drawn.
    let empty = Simulation::new(device, &spec, 1)
        .unwrap()
        .draw(&lens, &looks)
        .unwrap();
    assert!(empty.pixels.iter().all(|&p| p == BACKGROUND));
}

fn bad_frames_are_refused(device: &Device) {
    let (spec, looks) = three_kinds();
    let mut sim = Simulation::new(device, &spec, 1).unwrap();
    let lens = field_lens(spec.size, 400, 300);
    let err = sim.draw(&lens, &looks[..2]).unwrap_err().to_string();
    assert!(err.contains("2 looks for a world of 3 kinds"), "{err}");
    let wide = Lens { width: 0, ..lens };
    let err = sim.draw(&wide, &looks).unwrap_err().to_string();
    assert!(err.contains("0x300") && err.contains("1 to 16384"), "{err}");
    let flat = Lens { zoom: 0.0, ..lens };
    let err = sim.draw(&flat, &looks).unwrap_err().to_string();
    assert!(
        err.contains("zoom of 0") && err.contains("above 0"),
        "{err}"
    );
    let back = Lens { dt: -1.0, ..lens };
    let err = sim.draw(&back, &looks).unwrap_err().to_string();
    assert!(err.contains("-1 s") && err.contains("from 0"), "{err}");
}

fn paper() -> Scene {
    built_in("paper").unwrap().unwrap()
}

/// The frames of `paper` after `steps` autopilot steps through `camera`: a snapped one,
/// then one glided to 30 steps later.
fn paper_frames(device: &Device, steps: u32, camera: &Camera) -> [Frame; 2] {
    let mut game = Game::new(device, &paper(), 1).unwrap();
    for _ in 0..steps {
        game.submit(None).unwrap();
    }
    let snapped = game.draw(640, 360, camera).unwrap();
    for _ in 0..30 {
        game.submit(None).unwrap();
    }
    game.render(640, 360, camera, 1.0 / 60.0).unwrap();
    [snapped, game.pipeline().frame().unwrap()]
}

#[test]
fn frames_do_not_depend_on_the_schedule() {
    let shuffled = Device::cpu_scheduled(Some(2), Schedule::Shuffled { seed: 9 }, "tests").unwrap();
    let one = Device::cpu(Some(1), "tests").unwrap();
    for camera in [Camera::field(), Camera::default()] {
        let in_order = paper_frames(&one, 120, &camera);
        assert_eq!(
            paper_frames(&shuffled, 120, &camera),
            in_order,
            "{camera:?}"
        );
        assert_eq!(
            paper_frames(common::cpu(), 120, &camera),
            in_order,
            "{camera:?}"
        );
    }
}

#[test]
fn the_gpu_draws_the_same_frame_as_the_cpu() {
    let Some(gpu) = common::gpu() else { return };
    for camera in [Camera::field(), Camera::default()] {
        let cpu = paper_frames(common::cpu(), 300, &camera);
        let on_gpu = paper_frames(gpu, 300, &camera);
        println!(
            "paper frame after 300 steps, {:?}: cpu {:#018x}, gpu {:#018x}",
            camera.mode,
            cpu[0].hash(),
            on_gpu[0].hash()
        );
        assert_eq!(on_gpu, cpu);
    }
}

/// A GL context without a window: NVIDIA's EGL device with the GPU (so that interop works),
/// Mesa's software device without; `None`, said, where there is no EGL (Windows).
fn headless(device: &Device) -> Option<Headless> {
    if cfg!(not(unix)) {
        println!("skipped: headless GL is EGL's, which Windows lacks");
        return None;
    }
    Some(
        Headless::new(device.kind() == BackendKind::Cuda)
            .expect("an EGL device (see scripts/setup)"),
    )
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

/// The GL renderer's frame of `pipeline` through the camera of `lens`.
fn gl_frame(gl: &Headless, drawing: &mut Drawing, looks: &[Look], lens: &Lens) -> (Frame, bool) {
    let mut renderer = BodyRenderer::new(gl.facade(), drawing, looks).unwrap();
    if let Some(why) = renderer.fallback() {
        panic!("the GPU's vertices are uploaded: {why}");
    }
    let frame = gl.draw(&mut renderer, drawing, lens).unwrap();
    (frame, renderer.is_interop())
}

fn gl_draws_each_body_in_its_kinds_colour(device: &Device) {
    let Some(gl) = headless(device) else {
        return;
    };
    let (spec, looks) = three_kinds();
    let mut sim = Simulation::new(device, &spec, 1).unwrap();
    let bodies = place_three(&mut sim);
    let view = Framing::whole(spec.size, 400, 300, BACKGROUND);
    let lens = field_lens(spec.size, 400, 300);
    let (frame, interop) = gl_frame(&gl, &mut sim.drawing(), &looks, &lens);
    assert_eq!(interop, device.kind() == BackendKind::Cuda);
    check_three(&frame, &view, &looks, bodies);
    let kernel = sim.draw(&lens, &looks).unwrap();
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
    let Some(gl) = headless(device) else {
        return;
    };
    let scene = paper();
    let mut game = Game::new(device, &scene, 1).unwrap();
    for _ in 0..300 {
        game.submit(None).unwrap();
    }
    let looks = looks::looks(&scene);
    // The whole field (every kind a dot), and the ship followed at two zooms (silhouettes,
    // the halo, shots' streaks, the radar).
    let (wide, close) = (
        Camera::new(CameraMode::Follow, 1.0),
        Camera::new(CameraMode::Follow, 6.0),
    );
    for (camera, size) in [
        (Camera::field(), (640, 360)),
        (wide, (1280, 720)),
        (close, (640, 360)),
    ] {
        let kernel = game.draw(size.0, size.1, &camera).unwrap();
        let lens = game.lens(&camera, size.0, size.1, 0.0);
        let (frame, _) = gl_frame(&gl, &mut game.drawing(), &looks, &lens);
        let differ = differing(&frame, &kernel);
        println!(
            "paper after 300 steps, {camera:?}, GL on {}: {differ} of {} pixels differ from \
             the kernel renderer's (frame hash {:#018x})",
            gl.device(),
            frame.pixels.len(),
            frame.hash()
        );
        if camera.mode == CameraMode::Field {
            let state = game.snapshot().unwrap();
            for kind in state.live().map(|slot| state.bodies.kind[slot] as usize) {
                let look = &looks[kind];
                let drawn = [look.colour, look.nose, look.hurt];
                assert!(
                    frame.pixels.iter().any(|p| drawn.contains(p)),
                    "kind {kind} lives but is not drawn"
                );
            }
        }
        assert!(
            differ * 1000 <= frame.pixels.len(),
            "{differ} pixels differ"
        );
    }
}

#[test]
fn the_gpus_interop_frame_matches_the_cpus() {
    let Some(gpu) = common::gpu() else { return };
    let Some(gl) = headless(gpu) else {
        return;
    };
    let scene = paper();
    let mut game = Game::new(gpu, &scene, 1).unwrap();
    for _ in 0..300 {
        game.submit(None).unwrap();
    }
    let _ = game.snapshot().unwrap();
    let looks = looks::looks(&scene);
    let camera = Camera::default();
    let lens = game.lens(&camera, 640, 360, 0.0);
    let (on_gpu, interop) = gl_frame(&gl, &mut game.drawing(), &looks, &lens);
    assert!(interop);
    let [cpu, _] = paper_frames(common::cpu(), 300, &camera);
    println!(
        "paper after 300 steps: the GPU's interop frame ({}) and the CPU's kernel frame \
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
    let Some(gl) = headless(gpu) else {
        return;
    };
    let mut game = Game::new(gpu, &paper(), 1).unwrap();
    for _ in 0..300 {
        game.submit(None).unwrap();
    }
    let (width, height) = (640, 360);
    let camera = Camera::default();
    let mut image = DeviceImage::new(gl.facade(), gpu, width, height).unwrap();
    // SAFETY: the view goes only into the launches `render_into` queues; the mapped buffer
    // holds the frame's pixels; only these launches touch it.
    let texture =
        unsafe { image.set(|pixels| game.render_into(width, height, &camera, 0.0, pixels)) }
            .unwrap();
    let shown: RawImage2d<u8> = texture.read();
    let shown = Frame {
        width,
        height,
        pixels: bytemuck::cast_slice(&shown.data).to_vec(),
    };
    let drawn = game.draw(width, height, &camera).unwrap();
    println!(
        "kernel frame through a GL pixel buffer on {}: {} of {} pixels differ",
        gl.device(),
        differing(&shown, &drawn),
        drawn.pixels.len()
    );
    assert_eq!(shown.hash(), drawn.hash());
}

/// A follow camera's lens at `zoom` for a `size` frame of a `field` whose ship is slot 0.
fn follow_lens(field: Vec2, size: (u32, u32), zoom: f32, dt: f32) -> Lens {
    Camera::new(CameraMode::Follow, zoom).lens(field, size, 0, dt, BACKGROUND)
}

#[test]
fn the_camera_centres_the_ship_and_keeps_the_view_inside_the_field() {
    let field = Vec2::splat(4096.0);
    let lens = follow_lens(field, (1920, 1080), 2.0, 0.0);
    let mut state = CameraState::default();
    // Zoom 2 at 1,080 rows: 2 pixels per unit, so 960 × 540 units around the ship.
    let ship = Vec2::new(2000.0, 1500.0);
    let mid = camera::view(&lens, Some(ship), &mut state);
    assert_eq!(mid.scale, 2.0);
    assert_eq!(mid.origin, Vec2::new(2000.0 - 480.0, 1500.0 - 270.0));
    assert_eq!(mid.to_image(ship), Vec2::new(960.0, 540.0));
    assert_eq!(mid.to_world(Vec2::new(960.0, 540.0)), ship);
    // Near the corners the view stops at the field's edges.
    let low = camera::view(&lens, Some(Vec2::new(10.0, 30.0)), &mut state);
    assert_eq!(low.origin, Vec2::ZERO);
    let high = camera::view(&lens, Some(Vec2::new(4090.0, 4000.0)), &mut state);
    assert_eq!(high.origin, Vec2::new(4096.0 - 960.0, 4096.0 - 540.0));
    // A field lower than the view: centred along y, followed and clamped along x.
    let long = Vec2::new(4000.0, 100.0);
    let lens = follow_lens(long, (1920, 1080), 1.0, 0.0);
    let v = camera::view(&lens, Some(Vec2::new(3900.0, 90.0)), &mut state);
    assert_eq!(v.scale, 1.0);
    assert_eq!(v.origin, Vec2::new(4000.0 - 1920.0, 50.0 - 540.0));
    // The zoom is kept between the whole field and 8 times zoom 1.
    let whole = Framing::whole(field, 1920, 1080, BACKGROUND);
    assert_eq!(whole.scale, 1080.0 / 4096.0);
    assert_eq!(whole.origin.y, 0.0);
    assert_eq!(whole.origin.x + 960.0 / whole.scale, 2048.0);
    let far = follow_lens(field, (1920, 1080), 0.01, 0.0);
    assert_eq!(camera::view(&far, Some(ship), &mut state), whole);
    let near = follow_lens(field, (960, 540), 100.0, 0.0);
    assert_eq!(
        camera::view(&near, Some(ship), &mut state).scale,
        540.0 / 1080.0 * 8.0
    );
    // No ship, or the field mode: the whole field.
    assert_eq!(camera::view(&lens_of(field), None, &mut state), whole);
    let overview = Camera::field().lens(field, (1920, 1080), 0, 0.0, BACKGROUND);
    assert_eq!(camera::view(&overview, Some(ship), &mut state), whole);
    // The host's zoom steps stay in range, and Tab switches the mode.
    let mut cam = Camera::default();
    cam.zoom_by(1000.0);
    assert_eq!(cam.zoom, camera::MAX_ZOOM);
    cam.zoom_by(1e-9);
    assert_eq!(cam.zoom, camera::MIN_ZOOM);
    cam.toggle_overview();
    assert_eq!((cam.mode, cam.radar()), (CameraMode::Field, false));
    cam.toggle_overview();
    assert_eq!((cam.mode, cam.radar()), (CameraMode::Follow, true));
}

/// A follow lens for a 1920 × 1080 frame of `field`.
fn lens_of(field: Vec2) -> Lens {
    follow_lens(field, (1920, 1080), 2.0, 0.0)
}

#[test]
fn the_camera_glides_to_the_ship_and_snaps_at_frame_time_zero() {
    let field = Vec2::splat(4096.0);
    let (from, to) = (Vec2::new(1500.0, 1500.0), Vec2::new(2500.0, 1800.0));
    let dt = 1.0 / 60.0;
    let lens = follow_lens(field, (1920, 1080), 2.0, dt);
    let mut state = CameraState::default();
    // The first frame snaps, whatever its frame time.
    camera::view(&lens, Some(from), &mut state);
    assert_eq!((state.centre, state.scale), (from, 2.0));
    let start = (to - from).length();
    let mut gap = start;
    for n in 1..=120 {
        camera::view(&lens, Some(to), &mut state);
        let now = (to - state.centre).length();
        assert!(now <= gap, "frame {n}: the gap grew from {gap} to {now}");
        // An exponential approach: e^(−t/τ) of the way left after t seconds.
        let expected = start * (-(n as f32) * dt / 0.12).exp();
        assert!(
            (now - expected).abs() <= 1e-3 * start,
            "frame {n}: {now} units left, {expected} expected"
        );
        gap = now;
    }
    assert!(gap < 0.01, "{gap} units left after 2 s");
    // The zoom glides the same way.
    let closer = follow_lens(field, (1920, 1080), 4.0, dt);
    camera::view(&closer, Some(to), &mut state);
    let share = 1.0 - (-dt / 0.12).exp();
    assert!(
        (state.scale - (2.0 + 2.0 * share)).abs() < 1e-5,
        "{}",
        state.scale
    );
    // Frame time 0 snaps.
    let snap = follow_lens(field, (1920, 1080), 4.0, 0.0);
    camera::view(&snap, Some(from), &mut state);
    assert_eq!((state.centre, state.scale), (from, 4.0));
}

fn the_device_camera_is_the_hosts_bit_for_bit(device: &Device) {
    // `paper`'s frames work the camera out in every thread of their first launch; a world
    // of more slots than `FOLD_CAMERA_SLOTS` runs it as a launch of its own.
    let mut large = paper();
    large.world.kinds[2].capacity += FOLD_CAMERA_SLOTS;
    for scene in [paper(), large] {
        device_camera_is_the_hosts(device, &scene);
    }
}

/// The camera of 12 frames of `scene` (gliding, zoomed, snapped, overview) is the host's
/// own, bit for bit.
fn device_camera_is_the_hosts(device: &Device, scene: &Scene) {
    let mut game = Game::new(device, scene, 1).unwrap();
    let ship = game.pipeline().ship() as usize;
    let mut camera = Camera::default();
    let mut state = CameraState::default();
    for frame in 0..12 {
        for _ in 0..5 {
            game.submit(None).unwrap();
        }
        if frame == 4 {
            camera.zoom_by(3.0);
        }
        if frame == 8 {
            camera.toggle_overview();
        }
        let dt = if frame == 6 { 0.0 } else { 5.0 / 60.0 };
        game.render(1280, 720, &camera, dt).unwrap();
        let lens = game.lens(&camera, 1280, 720, dt);
        let snapshot = game.snapshot().unwrap();
        let pos = (snapshot.bodies.alive[ship] != 0).then(|| snapshot.bodies.pos[ship]);
        let host = camera::view(&lens, pos, &mut state);
        let shown = game.pipeline().shown().unwrap();
        assert_eq!(
            bytemuck::bytes_of(&shown.view),
            bytemuck::bytes_of(&host),
            "frame {frame}"
        );
    }
}

/// Each silhouette as a shape of its own in the body's frame (`u` along the heading, `v`
/// across it, in radii): the signed distance of `p` to its boundary, negative inside.
fn signed_distance(silhouette: u32, p: [f64; 2]) -> f64 {
    let polygon = |corners: &[[f64; 2]]| {
        let n = corners.len();
        let mut inside = false;
        let mut near = f64::INFINITY;
        for i in 0..n {
            let (a, b) = (corners[i], corners[(i + 1) % n]);
            // Crossing number along +u.
            if (a[1] > p[1]) != (b[1] > p[1]) {
                let u = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
                if p[0] < u {
                    inside = !inside;
                }
            }
            near = near.min(segment_distance(p, a, b));
        }
        if inside { -near } else { near }
    };
    let r = (p[0] * p[0] + p[1] * p[1]).sqrt();
    match silhouette {
        shapes::SQUARE => polygon(&[[0.7, 0.7], [-0.7, 0.7], [-0.7, -0.7], [0.7, -0.7]]),
        shapes::DIAMOND => polygon(&[[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]]),
        shapes::TRIANGLE => polygon(&[[1.0, 0.0], [-0.6, 0.8], [-0.6, -0.8]]),
        shapes::CHEVRON => polygon(&[[1.0, 0.0], [-0.8, 0.6], [-0.5, 0.0], [-0.8, -0.6]]),
        shapes::CROSS => polygon(&[
            [0.95, 0.3],
            [0.3, 0.3],
            [0.3, 0.95],
            [-0.3, 0.95],
            [-0.3, 0.3],
            [-0.95, 0.3],
            [-0.95, -0.3],
            [-0.3, -0.3],
            [-0.3, -0.95],
            [0.3, -0.95],
            [0.3, -0.3],
            [0.95, -0.3],
        ]),
        shapes::HEXAGON => {
            let corners: Vec<[f64; 2]> = (0..6)
                .map(|k| {
                    let a = k as f64 * std::f64::consts::PI / 3.0;
                    [a.cos(), a.sin()]
                })
                .collect();
            polygon(&corners)
        }
        shapes::BOWTIE => {
            // Two triangles meeting at the centre: the nearer boundary, inside either.
            let right = polygon(&[[0.0, 0.0], [0.75, -0.6], [0.75, 0.6]]);
            let left = polygon(&[[0.0, 0.0], [-0.75, 0.6], [-0.75, -0.6]]);
            right.min(left)
        }
        shapes::RING => (r - 1.0).max(0.55 - r),
        shapes::STREAK => segment_distance(p, [0.0, 0.0], [-3.0, 0.0]) - 1.0,
        _ => r - 1.0,
    }
}

/// Distance from `p` to the segment `a`–`b`.
fn segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (ab, ap) = ([b[0] - a[0], b[1] - a[1]], [p[0] - a[0], p[1] - a[1]]);
    let t = ((ap[0] * ab[0] + ap[1] * ab[1]) / (ab[0] * ab[0] + ab[1] * ab[1])).clamp(0.0, 1.0);
    let (dx, dy) = (ap[0] - t * ab[0], ap[1] - t * ab[1]);
    (dx * dx + dy * dy).sqrt()
}

fn silhouettes_cover_the_pixels_of_their_shapes(device: &Device) {
    let Some(gl) = headless(device) else {
        return;
    };
    let size = Vec2::splat(240.0);
    let colour = rgb(200, 100, 50);
    let centre = Vec2::new(120.3, 119.6);
    // Radius 20 pixels at one pixel per unit; then 2.5, below the silhouettes' threshold.
    for radius in [20.0f32, 2.5] {
        let spec = world(
            size,
            Boundary::Clamp,
            vec![kind("k", circle(radius), 1, &[])],
        );
        let mut sim = Simulation::new(device, &spec, 1).unwrap();
        let lens = field_lens(size, 240, 240);
        for silhouette in 0..shapes::RECT {
            let looks = [Look {
                silhouette,
                ..look(colour, 100)
            }];
            let mut renderer = BodyRenderer::new(gl.facade(), &sim, &looks).unwrap();
            for heading in [0.0f32, 0.5, 2.0, 3.9] {
                let dir = Vec2::new(heading.cos(), heading.sin());
                sim.place(&[(0, centre, dir)]).unwrap();
                let frame = sim.draw(&lens, &looks).unwrap();
                // The GL renderer's shader mirrors the inside tests: at most an edge pixel
                // or two rounds the other way.
                let on_gl = gl.draw(&mut renderer, &mut sim.drawing(), &lens).unwrap();
                let differ = differing(&on_gl, &frame);
                assert!(
                    differ <= 2,
                    "{silhouette} at {heading}: GL differs in {differ} pixels"
                );
                let shape = if radius < shapes::SHAPE_FROM_PX {
                    DISC
                } else {
                    silhouette
                };
                let dir = sim.snapshot().unwrap().bodies.dir[0].as_dvec2();
                let (mut drawn, mut expected, mut edge) = (0, 0, 1);
                for y in 0..240 {
                    for x in 0..240 {
                        let got = frame.pixel(x, y);
                        assert!(got == colour || got == BACKGROUND, "({x}, {y}) is {got:#x}");
                        let world = [x as f64 + 0.5, 240.0 - y as f64 - 0.5];
                        let d = [
                            (world[0] - f64::from(centre.x)) / f64::from(radius),
                            (world[1] - f64::from(centre.y)) / f64::from(radius),
                        ];
                        let p = [d[0] * dir.x + d[1] * dir.y, d[1] * dir.x - d[0] * dir.y];
                        let distance = signed_distance(shape, p);
                        drawn += usize::from(got == colour);
                        expected += usize::from(distance <= 0.0);
                        // Pixels within a ten-thousandth of a radius of the edge may go
                        // either way (f32 against f64); the pixel under the centre is
                        // always drawn.
                        let under = (x, y) == (120, 120);
                        if distance < -1e-4 || under {
                            assert_eq!(got, colour, "{shape} at {heading}: ({x}, {y}) inside");
                        } else if distance > 1e-4 {
                            assert_eq!(got, BACKGROUND, "{shape} at {heading}: ({x}, {y}) outside");
                        } else {
                            edge += 1;
                        }
                    }
                }
                // The count, as a summary: off by at most the pixels too close to call.
                assert!(
                    drawn.abs_diff(expected) <= edge,
                    "{shape}: {drawn} drawn, {expected} expected"
                );
            }
        }
    }
}

/// Big discs drawn row by row (more than `render::LARGE_PIXELS` pixels each) are the pixels a
/// plain host reference computes: a pixel shows the top (layer, then kind) of the discs
/// whose radius (at most `MAX_RADIUS_PX`) reaches its centre, or that lie over it.
fn big_discs_are_the_pixels_of_a_host_reference(device: &Device) {
    let size = Vec2::new(320.0, 200.0);
    let spec = world(
        size,
        Boundary::Clamp,
        vec![
            kind("low", circle(30.0), 3, &[]),
            kind("high", circle(21.5), 2, &[]),
            // Wider than any sprite may be drawn: capped at `MAX_RADIUS_PX`.
            kind("huge", circle(70.0), 1, &[]),
            kind("dot", circle(1.2), 2, &[]),
        ],
    );
    let looks = [
        look(rgb(200, 30, 30), 2),
        look(rgb(30, 200, 30), 7),
        look(rgb(30, 30, 200), 4),
        look(rgb(200, 200, 30), 9),
    ];
    let mut sim = Simulation::new(device, &spec, 1).unwrap();
    let ranges = sim.layout().ranges.clone();
    let bodies = [
        (ranges[0].start, Vec2::new(100.3, 90.7)),
        (ranges[0].start + 1, Vec2::new(130.0, 110.2)),
        // Clipped by the frame's corner.
        (ranges[0].start + 2, Vec2::new(4.0, 196.5)),
        (ranges[1].start, Vec2::new(118.6, 100.1)),
        (ranges[1].start + 1, Vec2::new(305.2, 12.9)),
        (ranges[2].start, Vec2::new(210.4, 120.6)),
        (ranges[3].start, Vec2::new(125.0, 100.0)),
        (ranges[3].start + 1, Vec2::new(240.0, 40.0)),
    ];
    let placed: Vec<_> = bodies.iter().map(|&(s, p)| (s, p, Vec2::X)).collect();
    sim.place(&placed).unwrap();
    let (width, height) = (320, 200);
    let lens = field_lens(size, width, height);
    let frame = sim.draw(&lens, &looks).unwrap();
    let view = sim.shown().unwrap().view;
    assert_eq!(view.scale, 1.0, "one pixel per unit");
    let radii = [30.0f32, 21.5, 48.0, 1.2];
    let kind_of = |slot: u32| ranges.iter().rposition(|r| r.start <= slot).unwrap();
    for y in 0..height {
        for x in 0..width {
            let mut top: Option<(u32, usize)> = None;
            for &(slot, pos) in &bodies {
                let k = kind_of(slot);
                // Image position: x from the left, y down from the top.
                let c = Vec2::new(
                    pos.x - view.origin.x,
                    height as f32 - (pos.y - view.origin.y),
                );
                let (dx, dy) = (x as f32 + 0.5 - c.x, y as f32 + 0.5 - c.y);
                let under = (c.x as u32, c.y as u32) == (x, y);
                if under || dx * dx + dy * dy <= radii[k] * radii[k] {
                    top = top.max(Some((looks[k].layer, k)));
                }
            }
            let expected = top.map_or(BACKGROUND, |(_, k)| looks[k].colour);
            assert_eq!(frame.pixel(x, y), expected, "pixel ({x}, {y})");
        }
    }
}

#[test]
fn frames_of_large_sprites_do_not_depend_on_the_schedule() {
    let shuffled = Device::cpu_scheduled(Some(2), Schedule::Shuffled { seed: 3 }, "tests").unwrap();
    let one = Device::cpu(Some(1), "tests").unwrap();
    // Close enough that most bodies on the screen are drawn row by row.
    let camera = Camera::new(CameraMode::Follow, 8.0);
    assert_eq!(
        paper_frames(&shuffled, 120, &camera),
        paper_frames(&one, 120, &camera)
    );
}

/// How many of `frame`'s pixels have one of `colours`, outside the radar's box.
fn count_outside_radar(frame: &Frame, colours: &[u32], field: Vec2) -> usize {
    let radar = radar_box(frame.width, frame.height, field);
    let mut n = 0;
    for y in 0..frame.height {
        for x in 0..frame.width {
            n += usize::from(!radar.contains(x, y) && colours.contains(&frame.pixel(x, y)));
        }
    }
    n
}

#[test]
fn a_followed_1080p_frame_of_paper_shows_a_large_ship_and_a_full_picture() {
    let scene = paper();
    let mut game = Game::new(common::cpu(), &scene, 1).unwrap();
    for _ in 0..STEPS_FOR_COVERAGE {
        game.submit(None).unwrap();
    }
    let frame = game.draw(1920, 1080, &Camera::default()).unwrap();
    let looks = looks::looks(&scene);
    let ship = &looks[scene.world.kind_index(&scene.game.ship.kind).unwrap()];
    let ship_pixels = count_outside_radar(
        &frame,
        &[ship.colour, ship.nose, ship.hurt],
        scene.world.size,
    );
    let drawn = frame.pixels.iter().filter(|&&p| p != BACKGROUND).count();
    println!(
        "paper at 1080p after {STEPS_FOR_COVERAGE} steps: the ship covers {ship_pixels} pixels, \
         {drawn} of {} pixels are drawn",
        frame.pixels.len()
    );
    assert!(ship_pixels >= 150, "the ship covers {ship_pixels} pixels");
    // At least 5% of the frame (5.8% measured): the bodies cover 3.8% (the autopilot
    // keeps its surroundings clear of enemies, and the silhouettes, at their bodies' true
    // sizes, cover about 60% of the discs they replaced), the radar 2.2% of it, the
    // backdrop's lines (96 pixels apart) about 2%, and the explosions' particles the rest.
    assert!(
        drawn * 1000 >= 50 * frame.pixels.len(),
        "{drawn} pixels drawn"
    );
}

/// Steps of `paper` before its followed frame is checked for coverage: 20 s of game
/// time, every wave of the first 16 s spawned.
const STEPS_FOR_COVERAGE: u32 = 1200;

fn the_radar_marks_the_ship_and_outlines_the_view(device: &Device) {
    let scene = paper();
    let mut game = Game::new(device, &scene, 1).unwrap();
    for _ in 0..120 {
        game.submit(None).unwrap();
    }
    let frame = game.draw(1920, 1080, &Camera::default()).unwrap();
    let looks = looks::looks(&scene);
    let ship_look = &looks[scene.world.kind_index(&scene.game.ship.kind).unwrap()];
    // 20% of 1,080 rows is 216 pixels inside a 1-pixel frame, 8 pixels from the top right.
    let (left, top, side) = (1920 - 8 - 218, 8, 218);
    assert_eq!(
        game.pipeline().shown().unwrap().radar,
        radar_box(1920, 1080, scene.world.size)
    );
    for i in 0..side {
        for (x, y) in [
            (left + i, top),
            (left + i, top + side - 1),
            (left, top + i),
            (left + side - 1, top + i),
        ] {
            assert_eq!(
                frame.pixel(x, y),
                radar::FRAME,
                "({x}, {y}) is the radar's frame"
            );
        }
    }
    assert_ne!(frame.pixel(left - 1, top + 5), radar::FRAME);
    // The ship's cross: its radar pixel is its position's share of 216.
    let snapshot = game.snapshot().unwrap();
    let pos = snapshot.bodies.pos[game.pipeline().ship() as usize];
    let sx = (pos.x / 4096.0 * 216.0).floor() as u32;
    let sy = 215 - (pos.y / 4096.0 * 216.0).floor() as u32;
    let (cx, cy) = (left + 1 + sx, top + 1 + sy);
    for (x, y) in [
        (cx, cy),
        (cx - 2, cy),
        (cx + 2, cy),
        (cx, cy - 2),
        (cx, cy + 2),
    ] {
        assert_eq!(
            frame.pixel(x, y),
            ship_look.colour,
            "({x}, {y}) marks the ship"
        );
    }
    // The view's outline: at zoom 1.5, 1,280 × 720 units, 67.5 × 38.0 radar pixels, around
    // the ship.
    let outline: Vec<(u32, u32)> = (top..top + side)
        .flat_map(|y| (left..left + side).map(move |x| (x, y)))
        .filter(|&(x, y)| frame.pixel(x, y) == radar::OUTLINE)
        .collect();
    let (x0, x1) = (
        outline.iter().map(|p| p.0).min().unwrap(),
        outline.iter().map(|p| p.0).max().unwrap(),
    );
    let (y0, y1) = (
        outline.iter().map(|p| p.1).min().unwrap(),
        outline.iter().map(|p| p.1).max().unwrap(),
    );
    assert!((67..=68).contains(&(x1 - x0)), "outline {x0}..{x1}");
    assert!((37..=38).contains(&(y1 - y0)), "outline {y0}..{y1}");
    assert!(((x0 + x1) / 2).abs_diff(cx) <= 1 && ((y0 + y1) / 2).abs_diff(cy) <= 1);
    assert_eq!(
        outline.len() as u32,
        2 * (x1 - x0 + y1 - y0),
        "a closed rectangle's edge"
    );
    // Enemies: pixels of the radar in neither the frame's, the outline's, the ship's nor
    // the empty colour.
    let enemies = (top + 1..top + side - 1)
        .flat_map(|y| (left + 1..left + side - 1).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            let c = frame.pixel(x, y);
            ![radar::OUTLINE, radar::EMPTY_COLOUR, ship_look.colour].contains(&c)
        })
        .count();
    assert!(enemies >= 100, "{enemies} radar pixels show enemies");
}

fn drawing_leaves_the_game_state_alone(device: &Device) {
    let scene = paper();
    let (mut drawn, mut plain) = (
        Game::new(device, &scene, 1).unwrap(),
        Game::new(device, &scene, 1).unwrap(),
    );
    let looks = looks::looks(&scene);
    let mut vertices = device
        .alloc_zeroed(drawn.pipeline().vertex_count() as usize)
        .unwrap();
    for i in 0..90 {
        drawn.submit(None).unwrap();
        plain.submit(None).unwrap();
        if i % 30 == 29 {
            drawn.draw(320, 180, &Camera::default()).unwrap();
            drawn
                .render(640, 360, &Camera::new(CameraMode::Follow, 8.0), 0.016)
                .unwrap();
            drawn.draw(200, 100, &Camera::field()).unwrap();
            let lens = drawn.lens(&Camera::default(), 800, 600, 0.03);
            drawn
                .drawing()
                .vertices_into(&lens, &looks, &mut vertices)
                .unwrap();
        }
    }
    assert_eq!(drawn.state_hash().unwrap(), plain.state_hash().unwrap());
}

/// A close follow camera: particles 2 pixels in radius in a 640 × 360 frame.
fn close_camera() -> Camera {
    Camera::new(CameraMode::Follow, 4.0)
}

/// The fade level of a particle with `life` steps left of `lifetime`: sixteenths of its
/// lifetime gone, at most 15.
fn expected_level(life: u32, lifetime: u32) -> u32 {
    ((lifetime - life) * 16 / lifetime).min(15)
}

/// The colours of particles of `looks` once they have faded (level 1 on: level 0 is the
/// kind's own colour, which its bodies have too).
fn particle_colours(looks: &[Look]) -> Vec<u32> {
    looks
        .iter()
        .flat_map(|l| (1..16).map(|level| fade(l.colour, BACKGROUND, level)))
        .collect()
}

/// `game` after `steps` autopilot steps of the crash scene, with a frame through
/// [`close_camera`].
fn crash_frame(device: &Device, steps: u32) -> (Game<'_>, Frame) {
    let mut game = Game::new(device, &crashing(), 3).unwrap();
    for _ in 0..steps {
        game.submit(None).unwrap();
    }
    let frame = game.draw(640, 360, &close_camera()).unwrap();
    (game, frame)
}

fn particles_are_drawn_in_their_kinds_colour_faded_by_age(device: &Device) {
    let (mut game, frame) = crash_frame(device, 45);
    let scene = crashing();
    let looks = looks::looks(&scene);
    let shown = game.pipeline().shown().unwrap();
    let view = shown.view;
    let particles = game.pipeline().particles().unwrap().unwrap();
    let bodies = game.snapshot().unwrap();
    let lifetime = particles.burst.lifetime;
    // 1.5 units at 4/3 pixels per unit.
    let radius = 2.0;
    let centres: Vec<(usize, Vec2)> = (0..particles.particles.life.len())
        .filter(|&p| particles.particles.life[p] > 0)
        .map(|p| (p, view.to_image(particles.particles.pos[p])))
        .collect();
    // (life, level, brightness) of each particle checked.
    let mut checked = Vec::new();
    for &(p, c) in &centres {
        let inside = c.x >= 4.0
            && c.y >= 4.0
            && c.x < view.width as f32 - 4.0
            && c.y < view.height as f32 - 4.0;
        let (x, y) = (c.x as u32, c.y as u32);
        // Alone: no other particle's disc and no body near it, off the radar.
        let alone = centres
            .iter()
            .all(|&(q, d)| q == p || (d - c).length() > 2.0 * radius + 2.0);
        let clear = bodies
            .live()
            .all(|b| (bodies.bodies.pos[b] - particles.particles.pos[p]).length() > 22.0);
        if !inside || !alone || !clear || shown.radar.contains(x, y) {
            continue;
        }
        let level = expected_level(particles.particles.life[p], lifetime);
        let expected = fade(
            looks[particles.particles.kind[p] as usize].colour,
            BACKGROUND,
            level,
        );
        assert_eq!(
            frame.pixel(x, y),
            expected,
            "particle {p} (life {}) at {c}",
            particles.particles.life[p]
        );
        // A disc: the pixels beside the one under its centre are within 2 pixels of it.
        assert_eq!(frame.pixel(x + 1, y), expected, "particle {p}: its disc");
        assert_eq!(frame.pixel(x, y + 1), expected, "particle {p}: its disc");
        let [r, g, b, _] = expected.to_le_bytes();
        checked.push((
            particles.particles.life[p],
            level,
            u32::from(r) + u32::from(g) + u32::from(b),
        ));
    }
    println!(
        "{} particles shown, {} checked alone",
        centres.len(),
        checked.len()
    );
    assert!(
        checked.len() >= 10,
        "only {} particles checked",
        checked.len()
    );
    // Older particles (less life left, a higher level) are darker: towards the background.
    let levels: std::collections::BTreeSet<u32> = checked.iter().map(|c| c.1).collect();
    assert!(levels.len() >= 3, "levels seen: {levels:?}");
    for a in &checked {
        for b in &checked {
            if a.1 > b.1 {
                assert!(a.0 < b.0 && a.2 < b.2, "{a:?} is older than {b:?}");
            }
        }
    }
}

#[test]
fn frames_with_particles_do_not_depend_on_the_schedule() {
    let one = Device::cpu(Some(1), "tests").unwrap();
    let (_, reference) = crash_frame(&one, 45);
    let colours = particle_colours(&looks::looks(&crashing()));
    let drawn = reference
        .pixels
        .iter()
        .filter(|p| colours.contains(p))
        .count();
    assert!(drawn >= 100, "{drawn} particle pixels");
    for threads in [2, 7] {
        let device = Device::cpu(Some(threads), "tests").unwrap();
        assert_eq!(crash_frame(&device, 45).1, reference, "{threads} threads");
    }
    for seed in [1, 2] {
        let device = Device::cpu_scheduled(Some(2), Schedule::Shuffled { seed }, "tests").unwrap();
        assert_eq!(crash_frame(&device, 45).1, reference, "shuffle seed {seed}");
    }
}

fn gl_draws_the_particles_as_the_kernel_does(device: &Device) {
    let Some(gl) = headless(device) else {
        return;
    };
    let (mut game, kernel) = crash_frame(device, 45);
    let looks = looks::looks(game.scene());
    let lens = game.lens(&close_camera(), 640, 360, 0.0);
    let (frame, _) = gl_frame(&gl, &mut game.drawing(), &looks, &lens);
    let colours = particle_colours(&looks);
    let count = |f: &Frame| f.pixels.iter().filter(|p| colours.contains(p)).count();
    let differ = differing(&frame, &kernel);
    println!(
        "crash after 45 steps, GL on {}: {differ} of {} pixels differ, {} and {} particle \
         pixels",
        gl.device(),
        frame.pixels.len(),
        count(&frame),
        count(&kernel)
    );
    assert!(count(&kernel) >= 100, "particles on screen");
    assert!(
        differ * 1000 <= frame.pixels.len(),
        "{differ} pixels differ"
    );
}

/// Launches of the particle-drawing kernels (kernel renderer, GL vertices) while `scene`
/// is drawn by both renderers on a fresh emulator, and the vertices the GL renderer needs.
fn particle_launches(scene: &Scene) -> (u64, u64, u32) {
    let mut device = Device::cpu(Some(2), "tests").unwrap();
    device.count_launches(true);
    let mut game = Game::new(&device, scene, 1).unwrap();
    for _ in 0..5 {
        game.submit(None).unwrap();
    }
    game.draw(320, 180, &Camera::default()).unwrap();
    let lens = game.lens(&Camera::default(), 320, 180, 0.0);
    let count = game.pipeline().vertex_count();
    let mut vertices = device.alloc_zeroed(count as usize).unwrap();
    let looks = looks::looks(scene);
    game.drawing()
        .vertices_into(&lens, &looks, &mut vertices)
        .unwrap();
    drop(game);
    let counts = device.launch_counts();
    let of = |name: &str| counts.get(name).copied().unwrap_or(0);
    (
        of(registry::SPLAT_PARTICLES.name),
        of(registry::WRITE_PARTICLE_VERTICES.name),
        count,
    )
}

#[test]
fn a_scene_without_explosions_launches_no_particle_drawing() {
    let scene = built_in("kamikaze").unwrap().unwrap();
    let (splat, vertices, with) = particle_launches(&scene);
    assert_eq!((splat, vertices), (1, 1), "one launch a frame with effects");
    let (splat, vertices, without) = particle_launches(&without_effects(&scene));
    assert_eq!((splat, vertices), (0, 0), "none without");
    // The bodies' vertices and the backdrop's; then the particles'.
    let game = Game::new(common::cpu(), &scene, 1).unwrap();
    let pipeline = game.pipeline();
    assert_eq!(without, pipeline.layout().slots + 1);
    let particles = pipeline.particles().unwrap().unwrap().particles.life.len() as u32;
    assert_eq!(with, without + particles);
}

/// The pixels (columns across, or rows down from the top) of a `size`-pixel image of a
/// `field`-long axis whose extent holds a multiple of the grid's spacing, seen from
/// `origin` at `scale` pixels per unit, worked out in f64; and those too close to a
/// pixel's edge to call.
fn multiples(origin: f32, scale: f32, size: u32, field: f32, down: bool) -> (Vec<u32>, Vec<u32>) {
    let (mut sure, mut close) = (Vec::new(), Vec::new());
    let spacing = f64::from(backdrop::SPACING);
    for k in 0..=(f64::from(field) / spacing) as u32 {
        let at = (f64::from(k) * spacing - f64::from(origin)) * f64::from(scale);
        if at < 0.0 || at >= f64::from(size) {
            continue;
        }
        let pixel = at.floor() as u32;
        let pixel = if down { size - 1 - pixel } else { pixel };
        // A whole number is exact in f32 too; a hair off one may round either way.
        let gap = (at - at.round()).abs();
        let edge = gap > 0.0 && gap < 1e-3;
        let into = if edge { &mut close } else { &mut sure };
        into.push(pixel);
    }
    (sure, close)
}

/// Checks that `frame`'s grid lines (a followed frame of `field` that `shown` describes)
/// lie exactly on the pixels that hold the world's multiples of the spacing.
fn check_lines(frame: &Frame, shown: &Shown, field: Vec2) {
    let (view, width, height) = (shown.view, frame.width, frame.height);
    assert_ne!(shown.backdrop, 0, "a followed frame has a backdrop");
    // 0.75 pixels per unit: lines 48 pixels apart.
    let (cols, cols_close) = multiples(view.origin.x, view.scale, width, field.x, false);
    let (rows, rows_close) = multiples(view.origin.y, view.scale, height, field.y, true);
    assert!(cols.len() >= 18 && rows.len() >= 10, "{cols:?} {rows:?}");
    for y in 0..height {
        for x in (0..width).filter(|&x| !shown.radar.contains(x, y)) {
            let got = frame.pixel(x, y);
            let on_col = cols.contains(&x) || cols_close.iter().any(|&c| c.abs_diff(x) <= 1);
            let on_row = rows.contains(&y) || rows_close.iter().any(|&r| r.abs_diff(y) <= 1);
            if got == backdrop::LINE {
                assert!(on_col || on_row, "({x}, {y}) is on no multiple");
            }
            // On a line, a pixel is the line's unless something is drawn over it.
            if cols.contains(&x) || rows.contains(&y) {
                assert_ne!(got, BACKGROUND, "({x}, {y}) is on a line");
            }
        }
    }
    for &x in &cols {
        let lit = (0..height)
            .filter(|&y| frame.pixel(x, y) == backdrop::LINE)
            .count();
        assert!(
            lit * 2 >= height as usize,
            "column {x}: {lit} pixels of line"
        );
    }
}

fn the_backdrop_grid_lies_on_the_worlds_multiples(device: &Device) {
    let Some(gl) = headless(device) else {
        return;
    };
    let scene = paper();
    let field = scene.world.size;
    let mut game = Game::new(device, &scene, 1).unwrap();
    // Long enough for the ship to have left the field's centre.
    for _ in 0..600 {
        game.submit(None).unwrap();
    }
    let (width, height) = (960, 540);
    let camera = Camera::default();
    // A view snapped to the ship, then one gliding after it (off whole units).
    let frame = game.draw(width, height, &camera).unwrap();
    check_lines(&frame, &game.pipeline().shown().unwrap(), field);
    let lens = game.lens(&camera, width, height, 0.0);
    for _ in 0..30 {
        game.submit(None).unwrap();
    }
    game.render(width, height, &camera, 1.0 / 60.0).unwrap();
    let glided = game.pipeline().shown().unwrap();
    assert_ne!(glided.view.origin.fract(), Vec2::ZERO);
    check_lines(&game.pipeline().frame().unwrap(), &glided, field);
    // The GL renderer draws the same lines, an edge pixel aside.
    let frame = game.draw(width, height, &camera).unwrap();
    let looks = looks::looks(&scene);
    let (on_gl, _) = gl_frame(&gl, &mut game.drawing(), &looks, &lens);
    let apart = frame
        .pixels
        .iter()
        .zip(&on_gl.pixels)
        .filter(|&(&a, &b)| (a == backdrop::LINE) != (b == backdrop::LINE))
        .count();
    println!(
        "paper's followed frame, GL on {}: {apart} of {} pixels differ in being a line, {} \
         in all",
        gl.device(),
        frame.pixels.len(),
        differing(&frame, &on_gl)
    );
    assert!(
        apart * 1000 <= frame.pixels.len(),
        "{apart} line pixels differ"
    );
    // The whole field has no backdrop: no line, no border.
    let whole = game.draw(width, height, &Camera::field()).unwrap();
    assert_eq!(game.pipeline().shown().unwrap().backdrop, 0);
    let marked = |f: &Frame| {
        f.pixels
            .iter()
            .filter(|p| [backdrop::LINE, backdrop::BORDER].contains(p))
            .count()
    };
    assert_eq!(marked(&whole), 0, "the field mode's frame");
    let lens = game.lens(&Camera::field(), width, height, 0.0);
    assert_eq!(
        marked(&gl_frame(&gl, &mut game.drawing(), &looks, &lens).0),
        0
    );
}

/// A frame drawn again with the same lens replays the frame's recorded launches (a CUDA
/// graph on the GPU, from the third frame on): every frame of a game drawn that way is the
/// frame a game that changes its lens in between (so that it never replays) draws, pixel
/// for pixel, the view followed and the whole field alike.
fn a_replayed_frame_is_the_frame_drawn_afresh(device: &Device) {
    let scene = paper();
    for camera in [Camera::default(), Camera::field()] {
        let (mut replayed, mut fresh) = (
            Game::new(device, &scene, 1).unwrap(),
            Game::new(device, &scene, 1).unwrap(),
        );
        for frame in 0..5 {
            for _ in 0..40 {
                replayed.submit(None).unwrap();
                fresh.submit(None).unwrap();
            }
            // The other size between frames: `fresh` never draws the same lens twice running.
            fresh.draw(64, 36, &camera).unwrap();
            let (a, b) = (
                replayed.draw(640, 360, &camera).unwrap(),
                fresh.draw(640, 360, &camera).unwrap(),
            );
            assert!(
                a == b,
                "{camera:?}, frame {frame}: {} pixels differ",
                differing(&a, &b)
            );
        }
    }
}

on_both_backends!(
    a_replayed_frame_is_the_frame_drawn_afresh,
    big_discs_are_the_pixels_of_a_host_reference,
    the_backdrop_grid_lies_on_the_worlds_multiples,
    particles_are_drawn_in_their_kinds_colour_faded_by_age,
    gl_draws_the_particles_as_the_kernel_does,
    a_frame_shows_each_body_in_its_kinds_colour,
    the_device_camera_is_the_hosts_bit_for_bit,
    silhouettes_cover_the_pixels_of_their_shapes,
    the_radar_marks_the_ship_and_outlines_the_view,
    drawing_leaves_the_game_state_alone,
    bad_frames_are_refused,
    gl_draws_each_body_in_its_kinds_colour,
    gl_draws_a_game_as_the_kernel_does,
);

#[test]
fn zooming_out_stops_at_the_whole_field_and_zooming_in_starts_at_once() {
    use gpuwars::camera::Camera;
    let field = Vec2::new(4096.0, 4096.0);
    let mut camera = Camera::default();
    for _ in 0..40 {
        camera.zoom_within(0.8, field, (1920, 1080));
    }
    // The whole field's height in 1,080 pixels: 1080 / 4096 pixels a unit, zoom 1 being one.
    let whole = 1080.0 / 4096.0;
    assert!((camera.zoom - whole).abs() < 1e-6, "{}", camera.zoom);
    camera.zoom_within(1.25, field, (1920, 1080));
    assert!((camera.zoom - whole * 1.25).abs() < 1e-6, "{}", camera.zoom);
}
