//! Time per frame of the kernel renderer at 1920 × 1080: `paper` full (8,190 enemies) and
//! `scale-1m` (1,048,576), on the backend `GPUWARS_BACKEND` names (default: auto): the frame
//! left on the device (`render`: two launches, then a synchronise), and read back to the
//! host (`draw`: 8 MB of pixels more).
//!
//! ```text
//! cargo bench --bench render
//! ```

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use gpuwars::game::Game;
use gpuwars::game::scene::built_in;

mod common;
use common::device;

fn frame(c: &mut Criterion) {
    let device = device();
    let mut group = c.benchmark_group("kernel_frame_1080p");
    group.sample_size(10);
    for (scene, steps) in [("paper", 900), ("scale-1m", 2)] {
        let scene = built_in(scene).unwrap().unwrap();
        let mut game = Game::new(&device, &scene, 1).unwrap();
        for _ in 0..steps {
            game.submit(None).unwrap();
        }
        let alive = game.draw(16, 16).map(|_| game.status().enemies_alive);
        group.throughput(Throughput::Elements(u64::from(alive.unwrap())));
        group.bench_function(format!("{}/{}/render", device.kind(), scene.name), |b| {
            b.iter(|| {
                game.render(1920, 1080).unwrap();
                device.synchronize().unwrap();
            })
        });
        group.bench_function(format!("{}/{}/draw", device.kind(), scene.name), |b| {
            b.iter(|| game.draw(1920, 1080).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, frame);
criterion_main!(benches);
