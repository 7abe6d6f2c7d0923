//! Data-parallel building blocks of the game loop: prefix sum, histogram and counting sort;
//! and the one-touch kernel the launch floor is measured with.
//!
//! All are barrier-free: each thread owns a contiguous tile of the input and walks it in order,
//! and the cooperation between tiles happens across launches. The host side (which launches
//! what, in which order, with which scratch buffers) lives in the host's `primitives` module.

pub mod histogram;
pub mod scan;
pub mod sort;
pub mod touch;
