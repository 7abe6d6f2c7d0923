//! A kernel that goes out of bounds is reported as the kernel fault it is, naming the kernel,
//! and the program carries on: under the emulator with the same device; on the GPU, where
//! the driver fails every later CUDA call of the faulting process, on the CPU emulation, while
//! a new process has the whole GPU again.
//!
//! On the GPU each fault happens in a child process (this executable, running the ignored
//! test `gpu::fault_in_this_process`), so that no other test of the run loses the GPU.

mod common;

use std::process::Command;

use gpuwars::backend::{Binder, Launch};
use gpuwars::kernels::primitives::scan::ReduceArgs;
use gpuwars::kernels::registry;
use gpuwars::{BackendKind, BackendRequest, Buffer, Device, Error, Op};

/// Keys of the histograms: each of 8 bins twice.
const KEYS: [u32; 16] = [0, 1, 2, 3, 4, 5, 6, 7, 7, 6, 5, 4, 3, 2, 1, 0];
const BINS: usize = 8;

/// The child process's variable naming the way it faults: `launch`, `ring` or `graph`.
const HOW: &str = "GPUWARS_TEST_FAULT";

/// A histogram of the first `n` keys on one block of 32 threads.
fn histogram(keys: &Buffer<u32>, counts: &Buffer<u32>, n: u32) -> Op {
    common::histogram_op(keys, counts, n, 1, 32)
}

/// A histogram whose `n` claims one key more than its view holds: thread 16 reads past the
/// end.
fn out_of_bounds(keys: &Buffer<u32>, counts: &Buffer<u32>) -> Op {
    histogram(keys, counts, KEYS.len() as u32 + 1)
}

/// A faulty histogram launched, then a wait: the emulator reports the fault from the launch,
/// the GPU from the wait.
fn fault_by_launch(device: &Device) -> Error {
    let keys = device.upload(&KEYS).unwrap();
    let counts = device.alloc_zeroed::<u32>(BINS).unwrap();
    device
        .launch(out_of_bounds(&keys, &counts))
        .and_then(|()| device.synchronize())
        .unwrap_err()
}

/// A faulty histogram launched between a ring's send and receive (as a game step is), then a
/// wait for the ring's oldest step.
fn fault_by_ring(device: &Device) -> Error {
    let keys = device.upload(&KEYS).unwrap();
    let counts = device.alloc_zeroed::<u32>(BINS).unwrap();
    let inputs = device.alloc_shared::<u32>(2).unwrap();
    let outputs = device.alloc_shared::<u32>(2).unwrap();
    let mut ring = device.ring(&inputs, &outputs).unwrap();
    ring.reserve(device).unwrap();
    ring.send(device, KEYS[0]).unwrap();
    device
        .launch(out_of_bounds(&keys, &counts))
        .and_then(|()| ring.receive(device))
        .and_then(|()| ring.oldest(device).map(drop))
        .unwrap_err()
}

/// A plan (a CUDA graph on the GPU) of a correct launch of another kernel, then the faulty
/// histogram, run, then a wait.
fn fault_by_plan(device: &Device) -> Error {
    let keys = device.upload(&KEYS).unwrap();
    let counts = device.alloc_zeroed::<u32>(BINS).unwrap();
    let sums = device.alloc_zeroed::<u32>(1).unwrap();
    // SAFETY: the views go into this op only.
    let mut b = unsafe { Binder::new() };
    let args = ReduceArgs {
        input: b.view(&keys),
        tile_sums: b.view(&sums),
        n: KEYS.len() as u32,
        reserved: 0,
    };
    let (kernel, grid, block) = (registry::SCAN_REDUCE, 1, 32);
    // SAFETY: two buffers of this binder, of the sizes the kernel asks for.
    let reduce = unsafe {
        Op::launch(
            Launch {
                kernel,
                grid,
                block,
                args,
            },
            b,
            0,
        )
    };
    let ops = vec![reduce, out_of_bounds(&keys, &counts)];
    let plan = device.plan(ops, true).unwrap();
    assert_eq!(plan.is_graph(), device.kind() == BackendKind::Cuda);
    device
        .run(&plan)
        .and_then(|()| device.synchronize())
        .unwrap_err()
}

/// Checks that `err` is a fault of `kernel` that says what the backend can say: the index
/// under the emulator; on the GPU, that the GPU is lost to the process and how to carry on.
fn check_fault(err: &Error, kernel: &str, backend: BackendKind) {
    let Error::KernelFault {
        kernel: named,
        message,
    } = err
    else {
        panic!("expected a fault of kernel `{kernel}`, got: {err}");
    };
    assert_eq!(named, kernel, "{err}");
    assert!(
        err.to_string()
            .starts_with(&format!("kernel `{kernel}` failed: ")),
        "{err}"
    );
    match backend {
        BackendKind::Cpu => assert!(
            message.contains("device index 16 out of bounds for a buffer of 16 elements"),
            "{message}"
        ),
        BackendKind::Cuda => {
            for words in [
                "The GPU is lost to this process",
                "--backend cpu",
                "run the program again",
            ] {
                assert!(message.contains(words), "no {words:?} in: {message}");
            }
        }
    }
}

/// A correct histogram on `device` gives the right counts.
fn check_histogram(device: &Device) {
    let keys = device.upload(&KEYS).unwrap();
    let counts = device.alloc_zeroed::<u32>(BINS).unwrap();
    device
        .launch(histogram(&keys, &counts, KEYS.len() as u32))
        .unwrap();
    device.synchronize().unwrap();
    assert_eq!(device.download(&counts).unwrap(), [2; BINS]);
}

mod cpu {
    use super::*;

    /// The emulator loses nothing to a fault: the same device carries on.
    #[test]
    fn a_fault_names_the_kernel_and_the_program_carries_on() {
        let device = common::cpu();
        for fault in [fault_by_launch, fault_by_ring, fault_by_plan] {
            check_fault(&fault(device), "histogram", BackendKind::Cpu);
            check_histogram(device);
        }
    }
}

mod gpu {
    use super::*;

    /// Each way of faulting, in a child process that checks the fault and carries on on the
    /// CPU emulation; then this process, which has not faulted, has the whole GPU.
    #[test]
    fn a_fault_names_the_kernel_and_the_program_carries_on() {
        let Some(device) = common::gpu() else { return };
        for how in ["launch", "ring", "graph"] {
            let child = Command::new(std::env::current_exe().unwrap())
                .args(["gpu::fault_in_this_process", "--exact", "--ignored"])
                .args(["--nocapture", "--test-threads=1"])
                .env(HOW, how)
                .output()
                .unwrap();
            let stdout = String::from_utf8_lossy(&child.stdout);
            let stderr = String::from_utf8_lossy(&child.stderr);
            eprintln!("fault by {how}, in a child process:\n{stdout}{stderr}");
            assert!(child.status.success(), "the child failed: {}", child.status);
            assert!(stdout.contains("1 passed"), "the child ran no test");
        }
        check_histogram(device);
    }

    /// The fault itself, in a process of its own (`HOW` says which).
    #[test]
    #[ignore = "run in a child process by the test above"]
    fn fault_in_this_process() {
        let device = match Device::cuda("tests") {
            Err(Error::CudaUnavailable(why)) => {
                eprintln!("skipped: no GPU ({why})");
                return;
            }
            opened => opened.unwrap(),
        };
        let how = std::env::var(HOW).unwrap_or_else(|_| "launch".into());
        let (err, kernel) = match how.as_str() {
            "launch" => (fault_by_launch(&device), "histogram"),
            "ring" => (fault_by_ring(&device), "histogram"),
            // A graph's kernels run unseen by the host: the fault names both.
            "graph" => (fault_by_plan(&device), "scan_reduce or histogram"),
            other => panic!("{HOW}={other}: expected launch, ring or graph"),
        };
        eprintln!("the fault as reported: {err}");
        check_fault(&err, kernel, BackendKind::Cuda);

        // Every later call fails the same way, naming the same kernels.
        check_fault(
            &device.synchronize().unwrap_err(),
            kernel,
            BackendKind::Cuda,
        );
        check_fault(
            &device.upload(&KEYS).err().unwrap(),
            kernel,
            BackendKind::Cuda,
        );
        // So does opening the GPU afresh, even with the faulted device gone.
        drop(device);
        let Err(err) = Device::cuda("tests") else {
            panic!("the GPU opened again in the process that faulted");
        };
        check_fault(&err, "unknown", BackendKind::Cuda);

        // The program carries on on the CPU emulation, which `auto` falls back to.
        let device = Device::select(BackendRequest::Auto, None).unwrap();
        assert_eq!(device.kind(), BackendKind::Cpu);
        check_histogram(&device);
    }
}
