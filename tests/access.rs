//! Work meets only memory of its own device, and ops beside each other only what neither
//! writes: a buffer, op, plan or ring of one device is refused on another with an error in
//! words, a plan refuses an op beside the others that meets what the ops it runs beside
//! write, and a race the declarations hide (written on purpose, against `Op::launch`'s
//! contract) changes the results of the CPU emulation's shuffled schedule.

mod common;

use common::{histogram, histogram_op};
use gpuwars::backend::{Binder, Launch, Schedule};
use gpuwars::kernels::access::Read;
use gpuwars::kernels::primitives::touch::TouchArgs;
use gpuwars::kernels::{DevSlice, registry};
use gpuwars::primitives::PrefixSum;
use gpuwars::{Buffer, Device, Error, Op};

/// A second CPU emulation: another device, with its own order.
fn other_cpu() -> Device {
    Device::cpu(Some(2), "tests: another device").unwrap()
}

/// `err` is the refusal of work of one device on another.
fn refused(err: Error) {
    assert!(matches!(err, Error::Invalid(_)), "{err}");
    assert!(err.to_string().contains("used on device #"), "{err}");
}

/// The program that raced before devices had identities: a prefix sum made with one
/// device's buffers, run on another, is refused when its plan is made, and so is every
/// host transfer of one device's buffer through another.
fn a_prefix_sum_of_one_device_is_refused_on_another(device: &Device) {
    let other = other_cpu();
    let data = device.upload(&[1u32; 64]).unwrap();
    let scan = PrefixSum::new(device, 64).unwrap();
    let ops = scan.ops(&data, &data, 64).unwrap();
    refused(
        other
            .plan(ops.clone(), false)
            .err()
            .expect("another device"),
    );
    refused(other.download(&data).expect_err("another device"));
    let mut mine = other.alloc_zeroed::<u32>(64).unwrap();
    refused(other.copy(&data, &mut mine).expect_err("another device"));
    refused(device.copy(&data, &mut mine).expect_err("another device"));
    refused(device.write(&mut mine, &[1]).expect_err("another device"));
    refused(device.zero(&mut mine).expect_err("another device"));
    // Its own device runs it.
    let plan = device.plan(ops, false).unwrap();
    device.run(&plan).unwrap();
    let expected: Vec<u32> = (0..64).collect();
    assert_eq!(device.download(&data).unwrap(), expected);
    refused(other.run(&plan).expect_err("another device"));
}

/// An op whose views are of two devices' buffers is refused, naming both.
fn an_op_of_two_devices_is_refused(device: &Device) {
    let other = other_cpu();
    let keys = device.upload(&[0u32; 32]).unwrap();
    let counts = other.alloc_zeroed::<u32>(1).unwrap();
    for on in [device, &other] {
        let err = on
            .plan(vec![histogram_op(&keys, &counts, 32, 1, 32)], false)
            .err()
            .expect("two devices");
        assert!(err.to_string().contains("one device's"), "{err}");
    }
}

/// A ring is its device's: made over another's buffers, or used on another, it refuses.
fn a_ring_is_its_devices(device: &Device) {
    let other = other_cpu();
    let inputs = device.alloc_shared::<u32>(2).unwrap();
    let outputs = device.alloc_shared::<u32>(2).unwrap();
    refused(other.ring(&inputs, &outputs).err().expect("another device"));
    let mut ring = device.ring(&inputs, &outputs).unwrap();
    refused(ring.send(&other, 7).expect_err("another device"));
    ring.send(device, 7).unwrap();
}

/// One read-modify-write of each of `data`'s elements, beside the ops after it; `data`
/// viewed as written, or (`lie`) bound read only and its address then taken for a written
/// view, against `Op::launch`'s contract: the only way to a kernel that writes what its op
/// declares read only, since the kernel's types allow no write through a read-only view.
fn touch_beside(data: &Buffer<u32>, lie: bool) -> Op {
    // SAFETY: the view goes into this op only.
    let mut b = unsafe { Binder::new() };
    let view = match lie {
        true => {
            let read: DevSlice<u32, Read> = b.view(data);
            // SAFETY: the binder's view of `data`, which the op holds; written against the
            // declaration on purpose (see above), on the CPU only.
            unsafe { DevSlice::from_raw_parts(read.addr(), read.len()) }
        }
        false => b.view(data),
    };
    let args = TouchArgs { data: view };
    let launch = Launch {
        kernel: registry::TOUCH,
        grid: (data.len() as u32).div_ceil(64),
        block: 64,
        args,
    };
    // SAFETY: a buffer of the binder, a thread an element; with `lie` the kernel writes a
    // view declared read only: a race this test makes on purpose, on the CPU only.
    unsafe { Op::launch(launch, b, 0) }.beside()
}

/// A plan refuses an op beside the others that writes what an op it runs beside reads,
/// with an error that names both ops and the buffer, and takes it where the reader waits
/// for the branch (`after_branches`).
fn a_branch_that_writes_what_the_chain_reads_is_refused(device: &Device) {
    let keys = device.upload(&[1u32; 256]).unwrap().named("keys");
    let counts = device.alloc_zeroed::<u32>(4).unwrap();
    let racing = vec![
        touch_beside(&keys, false),
        histogram_op(&keys, &counts, 256, 2, 128),
    ];
    let err = device.plan(racing, false).err().expect("a race");
    let text = err.to_string();
    for word in ["`touch`", "`histogram`", "writes `keys`"] {
        assert!(text.contains(word), "{text}");
    }
    // The same ops, the histogram waiting for the branch: taken, and the keys touched first.
    let waiting = vec![
        touch_beside(&keys, false),
        histogram_op(&keys, &counts, 256, 2, 128).after_branches(),
    ];
    device.run(&device.plan(waiting, false).unwrap()).unwrap();
    assert_eq!(device.download(&counts).unwrap(), [0, 0, 256, 0]);
    // Beside an op that touches none of its buffers, an op runs beside: taken.
    let elsewhere = device.upload(&[3u32; 64]).unwrap();
    let apart = vec![
        touch_beside(&elsewhere, false),
        histogram_op(&keys, &counts, 256, 2, 128),
    ];
    device.plan(apart, false).unwrap();
}

/// A race the declarations hide: the touch writes the keys it says it only reads, beside a
/// histogram of them. The plan takes it (nothing declared meets), and the CPU emulation in
/// order gives the touched keys' histogram; its shuffled schedule, which starts each branch
/// where it forks (beside the histogram, on another thread) or where it joins (after it),
/// gives another for some seeds: the determinism tests, which compare the two schedules,
/// fail on CI rather than on a GPU. The emulator reads and writes device memory as relaxed
/// atomics, so the race is a wrong result, as on a GPU, not undefined behaviour of this test
/// (it runs under Miri's race detector in CI).
#[test]
fn a_hidden_race_changes_the_shuffled_schedules_results() {
    // Fewer under Miri, which runs them some thousand times slower.
    let n: u32 = if cfg!(miri) { 512 } else { 4096 };
    let run = |device: &Device| {
        let keys = device.upload(&vec![1u32; n as usize]).unwrap();
        let counts = device.alloc_zeroed::<u32>(4).unwrap();
        let plan = device
            .plan(
                vec![
                    touch_beside(&keys, true),
                    histogram_op(&keys, &counts, n, n / 128, 128),
                ],
                false,
            )
            .unwrap();
        device.run(&plan).unwrap();
        device.download(&counts).unwrap()
    };
    let in_order = run(&Device::cpu(Some(2), "tests").unwrap());
    assert_eq!(in_order, histogram(&vec![2; n as usize], 4));
    let shuffled: Vec<Vec<u32>> = (0..8)
        .map(|seed| {
            run(&Device::cpu_scheduled(Some(2), Schedule::Shuffled { seed }, "tests").unwrap())
        })
        .collect();
    assert!(
        shuffled.iter().any(|counts| *counts != in_order),
        "every shuffled schedule hid the race: {shuffled:?}"
    );
}

/// Plans that threads issue together on one device are ordered whole, their branches
/// included: one thread runs a plan whose first op touches every key beside the op after
/// it (a branch, joined at the plan's end), a second makes a histogram of the keys after
/// each of its own runs, and a third captures and runs a plan with a branch of its own
/// over other buffers. Every histogram must find all the keys at one value: a run of the
/// histogram between the toucher's fork and its join would find some keys touched and
/// others not.
fn plans_of_threads_are_ordered_whole(device: &Device) {
    let (n, rounds): (u32, u32) = if cfg!(miri) { (256, 3) } else { (1 << 16, 24) };
    let keys = device
        .upload(&vec![0u32; n as usize])
        .unwrap()
        .named("keys");
    let aside = device.upload(&vec![0u32; n as usize]).unwrap();
    let mut counts = device.alloc_zeroed::<u32>(64).unwrap();
    let (other, more) = (
        device.upload(&vec![0u32; n as usize]).unwrap(),
        device.upload(&vec![0u32; n as usize]).unwrap(),
    );
    std::thread::scope(|s| {
        s.spawn(|| {
            let toucher = device
                .plan(vec![touch_beside(&keys, false), touch(&aside)], false)
                .unwrap();
            for _ in 0..rounds {
                device.run(&toucher).unwrap();
            }
        });
        s.spawn(|| {
            for _ in 0..rounds {
                let captured = device
                    .plan(vec![touch_beside(&other, false), touch(&more)], true)
                    .unwrap();
                device.run(&captured).unwrap();
            }
        });
        let counter = device
            .plan(vec![histogram_op(&keys, &counts, n, n / 128, 128)], false)
            .unwrap();
        for _ in 0..rounds {
            device.zero(&mut counts).unwrap();
            device.run(&counter).unwrap();
            let found = device.download(&counts).unwrap();
            let values: Vec<usize> = (0..found.len()).filter(|&k| found[k] > 0).collect();
            assert!(
                values.len() == 1 && found[values[0]] == n,
                "the keys at several values at once: {found:?}"
            );
        }
    });
    device.synchronize().unwrap();
    assert_eq!(device.download(&keys).unwrap(), vec![rounds; n as usize]);
    assert_eq!(device.download(&other).unwrap(), vec![rounds; n as usize]);
}

/// [`plans_of_threads_are_ordered_whole`] on the CPU emulation's shuffled schedule, where
/// each branch runs on a thread of its own.
#[test]
fn plans_of_threads_are_ordered_whole_on_shuffled_branches() {
    for seed in 0..if cfg!(miri) { 1 } else { 4 } {
        let device = Device::cpu_scheduled(Some(2), Schedule::Shuffled { seed }, "tests").unwrap();
        plans_of_threads_are_ordered_whole(&device);
    }
}

/// One read-modify-write of each of `data`'s elements, in the chain.
fn touch(data: &Buffer<u32>) -> Op {
    // SAFETY: the view goes into this op only.
    let mut b = unsafe { Binder::new() };
    let args = TouchArgs { data: b.view(data) };
    let launch = Launch {
        kernel: registry::TOUCH,
        grid: (data.len() as u32).div_ceil(64),
        block: 64,
        args,
    };
    // SAFETY: a buffer of the binder, a thread an element.
    unsafe { Op::launch(launch, b, 0) }
}

/// A ring owns the host's side of its buffers: while one thread sends and receives through
/// it, another's writes into them are refused (its writes into other shared memory, and
/// its reads of the ring's, are taken, in the device's order); a second ring over either
/// is refused; once the ring is gone, they are the host's again.
fn a_rings_buffers_are_written_through_it_only(device: &Device) {
    let steps: u32 = if cfg!(miri) { 8 } else { 200 };
    let mut inputs = device.alloc_shared::<u32>(4).unwrap().named("inputs");
    let outputs = device.alloc_shared::<u32>(4).unwrap();
    let mut other = device.alloc_shared::<u32>(4).unwrap();
    let mut ring = device.ring(&inputs, &outputs).unwrap();
    let err = device.ring(&other, &inputs).err().expect("a second ring");
    assert!(
        err.to_string().contains("`inputs` is another ring's"),
        "{err}"
    );
    // The refused ring left `other` the host's.
    device.write(&mut other, &[1]).unwrap();
    std::thread::scope(|s| {
        s.spawn(|| {
            for step in 0..steps {
                ring.reserve(device).unwrap();
                ring.send(device, step).unwrap();
                ring.receive(device).unwrap();
            }
            while ring.oldest(device).unwrap().is_some() {}
        });
        for step in 0..steps {
            let err = device
                .write(&mut inputs, &[step])
                .expect_err("a ring's buffer");
            assert!(err.to_string().contains("belongs to a ring"), "{err}");
            device.write(&mut other, &[step]).unwrap();
            assert_eq!(device.download(&outputs).unwrap(), [0; 4]);
        }
    });
    // Each slot holds the last step sent through it.
    let last: Vec<u32> = (0..4)
        .map(|k| (0..steps).filter(|s| s % 4 == k).max().unwrap_or(0))
        .collect();
    assert_eq!(device.download(&inputs).unwrap(), last);
    drop(ring);
    device.write(&mut inputs, &[7]).unwrap();
}

/// A chain runs its ops in order as one op; beside the ops to the plan's end, it is checked
/// against every op after it (those after the branches join too), which do not wait for it.
fn a_chain_beside_to_the_end_is_checked_to_the_end(device: &Device) {
    let keys = device.upload(&[1u32; 256]).unwrap().named("keys");
    let counts = device.alloc_zeroed::<u32>(4).unwrap();
    let other = device.upload(&[5u32; 64]).unwrap();
    let histogram = || histogram_op(&keys, &counts, 256, 2, 128).after_branches();
    // Two touches of `other` beside the histogram: taken, each touch run once.
    let chain = Op::chain(vec![touch(&other), touch(&other)]).unwrap();
    let apart = vec![chain.beside_to_the_end(), histogram()];
    device.run(&device.plan(apart, false).unwrap()).unwrap();
    assert_eq!(device.download(&other).unwrap(), vec![7; 64]);
    assert_eq!(device.download(&counts).unwrap(), [0, 256, 0, 0]);
    // A chain that writes the keys the histogram reads after the join: refused to the end,
    // and taken where the branch joins there.
    let chain = || Op::chain(vec![touch(&other), touch(&keys)]).unwrap();
    let racing = vec![chain().beside_to_the_end(), histogram()];
    let text = device
        .plan(racing, false)
        .err()
        .expect("a race")
        .to_string();
    for word in ["`touch`", "`histogram`", "writes `keys`"] {
        assert!(text.contains(word), "{text}");
    }
    device
        .plan(vec![chain().beside(), histogram()], false)
        .unwrap();
    // No chain of none, nor of an op beside.
    assert!(Op::chain(Vec::new()).is_err());
    assert!(Op::chain(vec![touch_beside(&other, false)]).is_err());
}

on_both_backends!(
    a_chain_beside_to_the_end_is_checked_to_the_end,
    plans_of_threads_are_ordered_whole,
    a_rings_buffers_are_written_through_it_only,
    a_prefix_sum_of_one_device_is_refused_on_another,
    an_op_of_two_devices_is_refused,
    a_ring_is_its_devices,
    a_branch_that_writes_what_the_chain_reads_is_refused,
);

/// The shuffled schedule's branches run on a pool of one worker too (a worker waiting for
/// a branch would otherwise hold back the only thread its launches need).
#[test]
fn branches_run_on_an_emulator_of_one_worker() {
    for seed in 0..4 {
        let device = Device::cpu_scheduled(Some(1), Schedule::Shuffled { seed }, "tests").unwrap();
        let keys = device.upload(&[1u32; 256]).unwrap();
        let elsewhere = device.upload(&[3u32; 64]).unwrap();
        let counts = device.alloc_zeroed::<u32>(4).unwrap();
        let ops = vec![
            touch_beside(&elsewhere, false),
            histogram_op(&keys, &counts, 256, 2, 128),
        ];
        device.run(&device.plan(ops, false).unwrap()).unwrap();
        assert_eq!(device.download(&counts).unwrap(), [0, 256, 0, 0]);
        assert_eq!(device.download(&elsewhere).unwrap(), vec![4; 64]);
    }
}
