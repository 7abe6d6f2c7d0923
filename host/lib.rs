//! GpuWars host side: the backends that run the kernels (CUDA, or the CPU emulation of the
//! very same kernel source), the host halves of the parallel primitives, and the reports the
//! command line prints.
//!
//! The device code itself lives in the `gpuwars-kernels` crate, re-exported as [`kernels`].
#![warn(missing_docs)]

pub mod backend;
pub mod benchmark;
pub mod camera;
pub mod cli;
pub mod demo;
pub mod files;
pub mod game;
pub mod graphics;
pub mod info;
pub mod meter;
pub mod pipeline;
pub mod play;
pub mod primitives;
pub mod ptx;
pub mod sim;
pub mod sound;
mod terminal;

pub use backend::{BackendKind, BackendRequest, Buffer, Device, Element, Error, Op, Plan};
pub use gpuwars_kernels as kernels;
