//! One file per stage of the step, each making its ops for a world: the host halves of the
//! kernels in `gpuwars_kernels::sim` and `gpuwars_kernels::game`.

pub(super) mod births;
pub(super) mod broad;
pub(super) mod effects;
pub(super) mod free;
pub(super) mod integrate;
pub(super) mod master;
pub(super) mod narrow;
pub(super) mod pilot;
pub(super) mod renumber;
pub(super) mod substeps;
pub(super) mod tally;
pub(super) mod think;
