//! Mersenne Twister family.
//!
//! - [`Mt19937`]: the reference generator of Matsumoto & Nishimura (1998),
//!   seeded like `mt19937ar.c`. The host draws the slots' seeds from it, and
//!   the host's dcmt parameter search (`gpuwars::sim::rng::dcmt`) uses it
//!   internally.
//! - [`Mt607`]: the small 19-word generator that runs one per GPU thread, as
//!   in V. Podlozhnyuk's "Parallel Mersenne Twister" (NVIDIA, 2007).
//! - [`RngStreams`]: one MT607 per body slot in device memory, drawn by kernels.

pub mod mt19937;
pub mod mt607;
pub mod streams;

pub use mt607::{Mt607, Mt607Params};
pub use mt19937::Mt19937;
pub use streams::{Drawing, RngStreams, RngStreamsAccess, SlotRng};
