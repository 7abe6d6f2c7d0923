//! The persistent step (`Device::program`): a plan's launches run as stages of one
//! cooperative launch give the plan's results bit for bit — a multi-launch prefix sum
//! against the reference, every built-in game and worlds of other sizes against their plan
//! of launches (and, on the GPU, against the CPU's) — and what cannot be a stage is refused
//! in words.

mod common;

use common::game::{Enemy, hash_with, scene};
use common::{EDGE_SIZES, exclusive_scan, random_below, rng_for};

use gpuwars::backend::{Binder, Launch, Op};
use gpuwars::game::scene::built_in;
use gpuwars::game::{Options, Scene};
use gpuwars::kernels::primitives::histogram::HistogramArgs;
use gpuwars::kernels::primitives::touch::TouchArgs;
use gpuwars::kernels::registry;
use gpuwars::pipeline::Persistent;
use gpuwars::primitives::PrefixSum;
use gpuwars::{Device, Error};

/// One touch of every element of `data` (each thread adds one to its element).
fn touch(data: &gpuwars::Buffer<u32>, block: u32) -> Op {
    // SAFETY: the view goes into this op only.
    let mut b = unsafe { Binder::new() };
    let args = TouchArgs { data: b.view(data) };
    let launch = Launch {
        kernel: registry::TOUCH,
        grid: (data.len() as u32).div_ceil(block),
        block,
        args,
    };
    // SAFETY: one buffer, one element a thread.
    unsafe { Op::launch(launch, b, 0) }
}

/// A prefix sum's launches (two to four of them, each reading what the one before wrote) as
/// one persistent launch: the reference's sums at every edge size, so every barrier between
/// stages held.
fn prefix_sum_as_one_launch(device: &Device) {
    for &n in EDGE_SIZES.iter().filter(|&&n| n > 0) {
        let input = random_below(&mut rng_for("persistent prefix sum", n), n, 1 << 20);
        let data = device.upload(&input).unwrap();
        let out = device.alloc_zeroed::<u32>(n).unwrap();
        let scan = PrefixSum::new(device, n).unwrap();
        let ops = scan.ops(&data, &out, n as u32).unwrap();
        let program = device.program(&ops, 1).unwrap();
        device
            .run(&device.plan(vec![program], false).unwrap())
            .unwrap();
        assert_eq!(
            device.download(&out).unwrap(),
            exclusive_scan(&input),
            "n = {n}"
        );
    }
}

/// Several steps in one launch: a chain of three touches run five times touches every
/// element fifteen times, in blocks of one warp, of 128 and of 1,024 threads.
fn steps_in_one_launch(device: &Device) {
    for (n, block) in [(1, 32), (4_099, 128), (70_001, 1_024)] {
        let data = device.alloc_zeroed::<u32>(n).unwrap();
        let ops: Vec<Op> = (0..3).map(|_| touch(&data, block)).collect();
        let program = device.program(&ops, 5).unwrap();
        device.launch(program).unwrap();
        let touched = device.download(&data).unwrap();
        assert!(touched.iter().all(|&v| v == 15), "n = {n}, block = {block}");
    }
}

/// What cannot be a stage is refused in words, before anything runs.
fn refusals(device: &Device) {
    let data = device.alloc_zeroed::<u32>(64).unwrap();
    let refused = |ops: &[Op], steps: u32| match device.program(ops, steps) {
        Err(Error::Invalid(why)) => why,
        Err(other) => panic!("refused as {other:?}"),
        Ok(_) => panic!("a program of what cannot be one was made"),
    };
    let why = refused(&[touch(&data, 64)], 0);
    assert!(why.contains("0 steps"), "{why}");
    let why = refused(&[touch(&data, 48)], 1);
    assert!(why.contains("whole warps") && why.contains("48"), "{why}");
    let why = refused(&[], 1);
    assert!(why.contains("0 launches"), "{why}");
    // A kernel of no step's plan.
    let counts = device.alloc_zeroed::<u32>(64).unwrap();
    // SAFETY: the views go into this op only.
    let mut b = unsafe { Binder::new() };
    let args = HistogramArgs {
        keys: b.view(&data),
        counts: b.view(&counts),
        n: 64,
        reserved: 0,
    };
    let launch = Launch {
        kernel: registry::HISTOGRAM,
        grid: 1,
        block: 64,
        args,
    };
    // SAFETY: 64 keys in view; the keys and the counts are two buffers.
    let histogram = unsafe { Op::launch(launch, b, 0) };
    let why = refused(&[histogram], 1);
    assert!(
        why.contains("`histogram`") && why.contains("stage kernels"),
        "{why}"
    );
    assert_eq!(device.download(&data).unwrap(), vec![0; 64]);
}

/// A game of `scene` for `steps` autopilot steps, stepped persistently or not.
fn hash_of(device: &Device, scene: &Scene, steps: u32, persistent: Persistent) -> u64 {
    let options = Options {
        persistent,
        ..Options::default()
    };
    hash_with(device, scene, 1, steps, options)
}

/// Every built-in scene small enough for the tests (the million-enemy ones are the
/// benchmarks'), 40 steps (the renumbering steps 0, 16 and 32 among them): the persistent
/// step's hash is the plan's, and on the GPU the CPU's too.
fn built_in_games_alike(device: &Device) {
    for name in ["paper", "kamikaze", "group", "tricky", "arena"] {
        let scene = built_in(name).unwrap().unwrap();
        let plan = hash_of(device, &scene, 40, Persistent::Off);
        let persistent = hash_of(device, &scene, 40, Persistent::On);
        assert_eq!(persistent, plan, "{name}: persistent against the plan");
        if !std::ptr::eq(device, common::cpu()) {
            let cpu = hash_of(common::cpu(), &scene, 40, Persistent::Off);
            assert_eq!(
                persistent, cpu,
                "{name}: the GPU's persistent step against the CPU's"
            );
        }
    }
}

/// Worlds of sizes no built-in scene has (an odd count, one enemy, a crowd of kamikazes
/// on a torus): the persistent step's hash is the plan's.
fn other_sizes_alike(device: &Device) {
    for (count, machine, boundary) in [
        (1, "kamikaze", "wrap"),
        (777, "group", "clamp"),
        (3_001, "kamikaze", "wrap"),
    ] {
        let enemies = [Enemy {
            name: "texel",
            machine,
            count,
            energy: 2,
            vision: 120.0,
            speed: 60.0,
            extra: "",
        }];
        let scene = scene(1500.0, boundary, 200.0, &enemies);
        let plan = hash_of(device, &scene, 30, Persistent::Off);
        let persistent = hash_of(device, &scene, 30, Persistent::On);
        assert_eq!(persistent, plan, "{count} {machine} enemies, {boundary}");
    }
}

on_both_backends!(
    prefix_sum_as_one_launch,
    steps_in_one_launch,
    refusals,
    built_in_games_alike,
    other_sizes_alike,
);

/// The emulator runs a cooperative launch with one block a worker: with one worker, one
/// block walks every stage's threads alone, and the result is the same.
#[test]
fn one_worker_runs_the_whole_program() {
    let device = Device::cpu(Some(1), "tests").unwrap();
    steps_in_one_launch(&device);
    let scene = built_in("paper").unwrap().unwrap();
    assert_eq!(
        hash_of(&device, &scene, 20, Persistent::On),
        hash_of(common::cpu(), &scene, 20, Persistent::Off)
    );
}
