//! The host half of the simulation core: world descriptions and their validation, slot
//! layout and grid sizing, the device buffers of a world, snapshots and the state hash. The
//! order of a step's launches is the pipeline's (`crate::pipeline`).

pub mod audit;
pub mod layout;
pub mod rng;
pub mod snapshot;
pub mod spec;
pub mod state;

pub use snapshot::Snapshot;
pub use spec::{
    Boundary, Field, Integrator, KindSpec, PairSweep, Physics, Shape, SpecError, Sweep, WorldSpec,
};
