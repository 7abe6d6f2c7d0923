//! GpuWars device code: every kernel of the game loop, in one source for two targets.
//!
//! This crate is compiled twice. For `nvptx64-nvidia-cuda` it becomes the PTX module that the
//! host embeds and hands to the CUDA driver; natively it is an ordinary library whose kernel
//! bodies the host's CPU emulator calls thread by thread. Nothing here knows about the host.
//!
//! The execution model ([`exec`]) is deliberately small: a kernel body is a plain function of
//! the calling thread's coordinates and a `#[repr(C)]` argument struct, and kernels never wait
//! for each other's threads (no barriers, no shared memory). A phase boundary is a new launch,
//! so the emulator's semantics are exactly the GPU's; or, in the persistent step
//! ([`persistent`]), a barrier across a grid whose blocks all stay resident, which both
//! targets honour. The lanes of one warp may exchange
//! values through [`warp`]'s collectives, which give the same bits on both targets.
#![cfg_attr(not(test), no_std)]
#![cfg_attr(
    target_arch = "nvptx64",
    feature(abi_ptx, stdarch_nvptx, asm_experimental_arch)
)]
#![warn(missing_docs)]

pub mod access;
pub mod data;
pub mod elementary;
pub mod exec;
pub mod game;
pub mod math;
pub mod persistent;
pub mod primitives;
pub mod registry;
pub mod render;
pub mod rng;
pub mod sim;
pub mod warp;

pub use exec::{DevSlice, Kernel, KernelArgs, KernelInfo, Thread, asked};

/// What the exported macros name, through `$crate`, so that a crate using them need not
/// depend on these crates itself under these names.
#[doc(hidden)]
pub mod __private {
    pub use bytemuck;
}

/// On the GPU a panic (only reachable through a failed bounds check) traps the kernel; the host
/// sees the launch fail.
#[cfg(target_arch = "nvptx64")]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    // SAFETY: `trap` aborts the kernel; it has no preconditions.
    unsafe { core::arch::nvptx::trap() }
}
