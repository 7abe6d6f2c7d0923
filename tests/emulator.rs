//! The execution model: launch validation on both backends, faults as errors, and results
//! that do not depend on the emulator's thread count.

mod common;

use common::{histogram_op as histogram, random_below, rng_for};
use gpuwars::primitives::{CountingSort, PrefixSum};
use gpuwars::{Device, Error, Op};

fn launches_outside_the_block_limits_are_refused(device: &Device) {
    let keys = device.upload(&[0u32]).unwrap();
    let counts = device.alloc_zeroed::<u32>(1).unwrap();
    for block in [0, 1025] {
        let err = device
            .launch(histogram(&keys, &counts, 1, 1, block))
            .unwrap_err();
        assert!(matches!(err, Error::Invalid(_)), "{err}");
        assert!(err.to_string().contains("1..=1024"), "{err}");
    }
    // A grid of zero blocks runs nothing.
    device.launch(histogram(&keys, &counts, 1, 0, 32)).unwrap();
    assert_eq!(device.download(&counts).unwrap(), [0]);
}

fn every_thread_of_the_grid_runs_once(device: &Device) {
    // Keys 0..n, one per thread, with a grid that overshoots n: each bin counts exactly one.
    let n = 1000;
    let keys = device.upload(&(0..n).collect::<Vec<u32>>()).unwrap();
    let mut counts = device.alloc_zeroed::<u32>(n as usize).unwrap();
    device.zero(&mut counts).unwrap();
    device.launch(histogram(&keys, &counts, n, 9, 128)).unwrap();
    device.synchronize().unwrap();
    assert_eq!(device.download(&counts).unwrap(), vec![1; n as usize]);
}

/// A plan holds the buffers its ops view: dropping every handle the code that made it had
/// frees nothing, so the plan still reads its keys, even after new buffers were allocated
/// (which, had the keys been freed, would likely take their memory on the CPU).
fn a_plan_keeps_its_buffers_alive(device: &Device) {
    let n = 4096;
    let keys: Vec<u32> = (0..n).map(|i| i % 8).collect();
    let counts = device.alloc_zeroed::<u32>(8).unwrap();
    let plan = {
        let keys = device.upload(&keys).unwrap();
        let plan = device
            .plan(vec![histogram(&keys, &counts, n, n / 128, 128)], true)
            .unwrap();
        drop(keys);
        plan
    };
    let reused: Vec<_> = (0..8)
        .map(|_| device.upload(&vec![9u32; n as usize]).unwrap())
        .collect();
    device.run(&plan).unwrap();
    device.synchronize().unwrap();
    assert_eq!(device.download(&counts).unwrap(), [n / 8; 8]);
    // The counts' last handle goes too: the plan still runs on memory it holds (which
    // memcheck checks on the GPU).
    drop(counts);
    drop(reused);
    device.run(&plan).unwrap();
    device.synchronize().unwrap();
}

/// Shared memory (page-locked host memory mapped into the GPU on the GPU): kernels read and
/// write it where it is, and the host writes, reads and zeroes it; a ring takes only
/// buffers of it of one length.
fn shared_memory_is_reached_by_kernels_and_the_host(device: &Device) {
    let mut rng = rng_for("shared_memory", 0);
    let n = 3000;
    let data = random_below(&mut rng, n, 16);
    let mut keys = device.alloc_shared::<u32>(n).unwrap();
    device.write(&mut keys, &data).unwrap();
    let mut counts = device.alloc_shared::<u32>(16).unwrap();
    let plan = device
        .plan(vec![histogram(&keys, &counts, n as u32, 24, 128)], true)
        .unwrap();
    for _ in 0..2 {
        device.run(&plan).unwrap();
    }
    let expected: Vec<u32> = (0..16)
        .map(|k| 2 * data.iter().filter(|&&v| v == k).count() as u32)
        .collect();
    assert_eq!(device.download(&counts).unwrap(), expected);
    assert_eq!(device.download(&keys).unwrap(), data);
    device.zero(&mut counts).unwrap();
    assert_eq!(device.download(&counts).unwrap(), [0; 16]);
    // A device copy involves no shared memory on the GPU (a clear error), any on the CPU.
    let mut plain = device.alloc_zeroed::<u32>(n).unwrap();
    match (device.kind(), device.copy(&keys, &mut plain)) {
        (gpuwars::BackendKind::Cuda, Err(e)) => assert!(e.to_string().contains("shared"), "{e}"),
        (gpuwars::BackendKind::Cpu, Ok(())) => assert_eq!(device.download(&plain).unwrap(), data),
        (kind, result) => panic!("{kind:?}: {result:?}"),
    }
    // A ring's two buffers hold one slot per step in flight each.
    let outputs = device.alloc_shared::<u32>(3).unwrap();
    let err = device.ring(&keys, &outputs).err().expect("lengths differ");
    assert!(err.to_string().contains("as many of each"), "{err}");
    let none = device.alloc_shared::<u32>(0).unwrap();
    assert!(device.ring(&none, &none).is_err());
    if device.kind() == gpuwars::BackendKind::Cuda {
        let plain = device.alloc_zeroed::<u32>(3).unwrap();
        let err = device.ring(&plain, &outputs).err().expect("device memory");
        assert!(err.to_string().contains("shared memory"), "{err}");
    }
}

/// An op run beside the others ([`gpuwars::Op::beside`]: a branch of the graph, or a side
/// stream) runs once a run and is joined at the plan's end: a histogram of 2 million keys
/// in blocks of one warp beside one of a thousand, run as a graph and one by one, is done
/// by the time the host reads it (the read waits for the device's stream only).
fn an_op_beside_the_others_is_joined_at_the_plans_end(device: &Device) {
    let mut rng = rng_for("beside", 0);
    let (slow_n, fast_n) = (1 << 21, 1000);
    let slow_keys = random_below(&mut rng, slow_n, 8);
    let fast_keys = random_below(&mut rng, fast_n, 8);
    let count = |keys: &[u32], times: u32| -> Vec<u32> {
        (0..8)
            .map(|k| times * keys.iter().filter(|&&v| v == k).count() as u32)
            .collect()
    };
    for graph in [true, false] {
        let slow = device.upload(&slow_keys).unwrap();
        let fast = device.upload(&fast_keys).unwrap();
        let slow_counts = device.alloc_zeroed::<u32>(8).unwrap();
        let fast_counts = device.alloc_zeroed::<u32>(8).unwrap();
        // Far longer than the fast launch after it.
        let beside = histogram(&slow, &slow_counts, slow_n as u32, slow_n as u32 / 32, 32);
        // The ops after it touch other buffers (making the plan checks it).
        let ops = vec![
            beside.beside(),
            histogram(&fast, &fast_counts, fast_n as u32, 8, 128),
        ];
        let plan = device.plan(ops, graph).unwrap();
        assert_eq!(plan.launches(), 2);
        for _ in 0..3 {
            device.run(&plan).unwrap();
        }
        assert_eq!(device.download(&slow_counts).unwrap(), count(&slow_keys, 3));
        assert_eq!(device.download(&fast_counts).unwrap(), count(&fast_keys, 3));
    }
}

/// An op made [`gpuwars::Op::after_branches`] runs once the ops beside the others before it
/// are done: the prefix sums of a slow histogram's counts, run beside the fast one and
/// read by the op after the branches, are those of the finished counts on every run.
fn an_op_after_the_branches_sees_what_they_wrote(device: &Device) {
    let mut rng = rng_for("after_branches", 0);
    let slow_n = 1 << 21;
    let slow_keys = random_below(&mut rng, slow_n, 8);
    let counts: Vec<u32> = (0..8)
        .map(|k| slow_keys.iter().filter(|&&v| v == k).count() as u32)
        .collect();
    for graph in [true, false] {
        let slow = device.upload(&slow_keys).unwrap();
        let slow_counts = device.alloc_zeroed::<u32>(8).unwrap();
        let sums = device.alloc_zeroed::<u32>(8).unwrap();
        let fast = device.upload(&[1u32; 1000]).unwrap();
        let fast_counts = device.alloc_zeroed::<u32>(8).unwrap();
        let scan = PrefixSum::new(device, 8).unwrap();
        let beside = histogram(&slow, &slow_counts, slow_n as u32, slow_n as u32 / 32, 32);
        // The op after it touches other buffers, up to the scan after the branches.
        let mut ops = vec![
            beside.beside(),
            histogram(&fast, &fast_counts, 1000, 8, 128),
        ];
        let scanned = scan.ops(&slow_counts, &sums, 8).unwrap();
        ops.extend(scanned.into_iter().map(Op::after_branches));
        let plan = device.plan(ops, graph).unwrap();
        for run in 1..=3 {
            device.run(&plan).unwrap();
            let done: Vec<u32> = counts.iter().map(|c| run * c).collect();
            assert_eq!(
                device.download(&sums).unwrap(),
                common::exclusive_scan(&done),
                "run {run}, graph {graph}"
            );
        }
    }
}

on_both_backends!(
    launches_outside_the_block_limits_are_refused,
    an_op_beside_the_others_is_joined_at_the_plans_end,
    an_op_after_the_branches_sees_what_they_wrote,
    every_thread_of_the_grid_runs_once,
    a_plan_keeps_its_buffers_alive,
    shared_memory_is_reached_by_kernels_and_the_host,
);

/// An out-of-bounds index is an error, not a crash of the host. (CPU only here: on the GPU the
/// same fault traps, and the driver fails every later CUDA call of the process, so
/// `tests/gpu_fault.rs` checks it in child processes.)
#[test]
fn an_out_of_bounds_kernel_is_an_error() {
    let device = common::cpu();
    let keys = device.upload(&[0u32; 4]).unwrap();
    let counts = device.alloc_zeroed::<u32>(1).unwrap();
    // `n` claims more keys than the view holds.
    let err = device
        .launch(histogram(&keys, &counts, 5, 1, 8))
        .unwrap_err();
    match err {
        Error::KernelFault { kernel, message } => {
            assert_eq!(kernel, "histogram");
            assert!(message.contains("index 4 out of bounds"), "{message}");
        }
        other => panic!("expected a kernel fault, got {other}"),
    }
}

#[test]
fn sort_is_identical_for_any_thread_count() {
    let n = 200_003;
    let keys = random_below(&mut rng_for("threads", n), n, 64);
    let run = |threads| {
        let device = Device::cpu(Some(threads), "test").unwrap();
        let mut sort = CountingSort::new(&device, n).unwrap();
        let src = device.upload(&keys).unwrap();
        let mut k = device.alloc_zeroed(n).unwrap();
        let mut i = device.alloc_zeroed(n).unwrap();
        sort.run(&device, &src, n, 64, &mut k, &mut i).unwrap();
        (device.download(&k).unwrap(), device.download(&i).unwrap())
    };
    let one = run(1);
    assert_eq!(one, run(2));
    assert_eq!(one, run(7));
}
