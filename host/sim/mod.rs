//! The host half of the simulation core: world descriptions, slot layout, the device
//! buffers of a world and the order in which a step's kernels run.

pub mod layout;
pub mod rng;
pub mod snapshot;
pub mod spec;
pub mod world;

pub use snapshot::Snapshot;
pub use spec::{Boundary, KindSpec, Shape, SpecError, WorldSpec};
pub use world::Simulation;
