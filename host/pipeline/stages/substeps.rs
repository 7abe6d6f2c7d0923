//! `substeps`: broad, narrow and integrate again for each further substep.

use super::{broad, integrate, narrow};
use crate::Op;
use crate::pipeline::world::World;

/// The physics of substeps 1 and on (substep 0 is the step's own stages).
pub(in crate::pipeline) fn ops(world: &World) -> Vec<Op> {
    (1..world.spec.physics.substeps)
        .flat_map(|k| {
            let mut ops = broad::ops(world, k);
            ops.extend(narrow::ops(world, k));
            ops.extend(integrate::ops(world, k, false));
            ops
        })
        .collect()
}
