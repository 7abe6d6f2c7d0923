//! Time per frame at 1920 × 1080: `paper` full (8,190 enemies), `scale-1m` (1,048,576) and,
//! for the kernel renderer, `scale-16m` (16,760,000),
//! on the backend `GPUWARS_BACKEND` names (default: auto).
//!
//! - `kernel_frame_1080p`: the kernel renderer's frame of the whole field left on the
//!   device (`render`: the camera, radar, splat and resolve launches, then a synchronise),
//!   read back to the host (`draw`: 8 MB of pixels more), and the ship followed at the
//!   default zoom with the radar, gliding 1/60 s per frame (`follow`); `paper` also
//!   without its explosions (`paper-no-effects`).
//! - `displayed_frame_1080p`: a whole displayed frame with GL (no window: an EGL device),
//!   `glFinish` included, for each renderer: `kernel` (render, read back, one texture
//!   upload, one textured draw; `kernel-pbo` on the GPU: drawn into a GL pixel buffer
//!   registered with CUDA, copied into the texture by GL) and `interop` (the vertex kernel into GL's mapped vertex
//!   buffer, or the emulator's vertices uploaded, then one point draw); alone, and after
//!   one simulation step (`step+…`: the GPU then switches from CUDA to GL each frame).
//!
//! ```text
//! cargo bench --bench render
//! ```

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glium::Surface;
use gpuwars::BackendKind;
use gpuwars::camera::Camera;
use gpuwars::game::scene::built_in;
use gpuwars::game::{Game, looks};
use gpuwars::graphics::bodies::BodyRenderer;
use gpuwars::graphics::headless::{Headless, Target};
use gpuwars::graphics::picture::{Blit, DeviceImage, Upload};
use gpuwars::graphics::unpack;

mod common;
use common::device;

fn frame(c: &mut Criterion) {
    let device = device();
    let mut group = c.benchmark_group("kernel_frame_1080p");
    group.sample_size(10);
    // `paper` without its explosions too: what the camera, silhouettes, radar and backdrop
    // cost by themselves, the particles' cost being the difference.
    let scenes = [
        ("paper", 900, true),
        ("paper", 900, false),
        ("scale-1m", 2, true),
        ("scale-16m", 2, true),
    ];
    for (scene, steps, effects) in scenes {
        let mut scene = built_in(scene).unwrap().unwrap();
        if !effects {
            scene.game.effects = None;
            scene.name += "-no-effects";
        }
        let mut game = Game::new(&device, &scene, 1).unwrap();
        for _ in 0..steps {
            game.submit(None).unwrap();
        }
        let field = Camera::field();
        let alive = game
            .draw(16, 16, &field)
            .map(|_| game.status().enemies_alive);
        group.throughput(Throughput::Elements(u64::from(alive.unwrap())));
        group.bench_function(format!("{}/{}/render", device.kind(), scene.name), |b| {
            b.iter(|| {
                game.render(1920, 1080, &field, 0.0).unwrap();
                device.synchronize().unwrap();
            })
        });
        group.bench_function(format!("{}/{}/draw", device.kind(), scene.name), |b| {
            b.iter(|| game.draw(1920, 1080, &field).unwrap())
        });
        let follow = Camera::default();
        group.bench_function(format!("{}/{}/follow", device.kind(), scene.name), |b| {
            b.iter(|| {
                game.render(1920, 1080, &follow, 1.0 / 60.0).unwrap();
                device.synchronize().unwrap();
            })
        });
    }
    group.finish();
}

fn displayed(c: &mut Criterion) {
    let device = device();
    let gl = Headless::new(device.kind() == BackendKind::Cuda).expect("an EGL device");
    let facade = gl.facade();
    let (width, height) = (1920, 1080);
    let target = Target::new(facade, width, height).unwrap();
    let blit = Blit::new(facade).unwrap();
    let mut group = c.benchmark_group("displayed_frame_1080p");
    group.sample_size(10);
    for (name, steps) in [("paper", 900), ("scale-1m", 2)] {
        let scene = built_in(name).unwrap().unwrap();
        let mut game = Game::new(&device, &scene, 1).unwrap();
        for _ in 0..steps {
            game.submit(None).unwrap();
        }
        let camera = Camera::field();
        let alive = game
            .draw(16, 16, &camera)
            .map(|_| game.status().enemies_alive);
        group.throughput(Throughput::Elements(u64::from(alive.unwrap())));
        let lens = game.lens(&camera, width, height, 0.0);
        let mut bodies = BodyRenderer::new(facade, game.pipeline(), &looks::looks(&scene)).unwrap();
        let feed = if bodies.is_interop() {
            "interop"
        } else {
            "upload"
        };
        let mut upload = Upload::default();
        let mut kernel_frame = |game: &mut Game| {
            let frame = game.draw(width, height, &camera).unwrap();
            upload.set(facade, &frame).unwrap();
            let mut surface = target.surface(facade).unwrap();
            let texture = upload.texture().unwrap();
            blit.draw(&mut surface, texture, true, (0, 0), height, false)
                .unwrap();
            facade.finish();
        };
        let label = |what: &str| format!("{}/{name}/{what}", device.kind());
        group.bench_function(label("kernel"), |b| b.iter(|| kernel_frame(&mut game)));
        if let Ok(mut image) = DeviceImage::new(facade, &device, width, height) {
            // The frame never leaves the GPU: drawn into a GL pixel buffer mapped for CUDA.
            let mut pbo_frame = |game: &mut Game| {
                // SAFETY: the view goes only into the launches `render_into` queues; the
                // mapped buffer holds the frame; only these launches touch it.
                let texture = unsafe {
                    image.set(|pixels| game.render_into(width, height, &camera, 0.0, pixels))
                }
                .unwrap();
                let mut surface = target.surface(facade).unwrap();
                blit.draw(&mut surface, texture, true, (0, 0), height, false)
                    .unwrap();
                facade.finish();
            };
            group.bench_function(label("kernel-pbo"), |b| b.iter(|| pbo_frame(&mut game)));
            group.bench_function(label("step+kernel-pbo"), |b| {
                b.iter(|| {
                    game.submit(None).unwrap();
                    pbo_frame(&mut game)
                })
            });
        }
        group.bench_function(label("step+kernel"), |b| {
            b.iter(|| {
                game.submit(None).unwrap();
                kernel_frame(&mut game)
            })
        });
        let mut gl_frame = |game: &mut Game| {
            let mut surface = target.surface(facade).unwrap();
            surface.clear_color_and_depth(unpack(lens.background), 0.0);
            bodies.update(facade, &mut game.drawing(), &lens).unwrap();
            bodies.draw(&mut surface, &lens).unwrap();
            facade.finish();
        };
        group.bench_function(label(feed), |b| b.iter(|| gl_frame(&mut game)));
        group.bench_function(label(&format!("step+{feed}")), |b| {
            b.iter(|| {
                game.submit(None).unwrap();
                gl_frame(&mut game)
            })
        });
    }
    group.finish();
}

criterion_group!(benches, frame, displayed);
criterion_main!(benches);
