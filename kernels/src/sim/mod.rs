//! The simulation core (paper sections 5 and 6): bodies as a structure of arrays, the
//! uniform-grid broad phase, the narrow phase with collision response, and the Euler
//! integrator. A step runs, in order:
//!
//! 1. [`broad::count_cells`]: the (cell, kind) bucket of every live body, counted with
//!    atomic adds;
//! 2. a prefix sum of the counts (`crate::primitives::scan`): where each bucket starts;
//! 3. [`broad::place_in_cells`] and [`broad::order_cells`]: every body in its bucket, each
//!    bucket in increasing slot order whatever order the threads ran in;
//! 4. every few steps in large worlds, [`renumber`]: each kind's bodies move to the slots of
//!    its range in the grid's order, so that neighbours in a warp are neighbours in the field;
//! 5. [`narrow::collide`]: each body tests the bodies of the kinds it collides with in its 3×3
//!    cell neighbourhood and sums its own response (position push, velocity kick, energy loss),
//!    alone or with a team of lanes ([`teams`]) that folds what it finds in the same order;
//! 6. [`integrate::integrate`]: explicit Euler and the world's boundary rule; bodies out of
//!    energy die;
//! 7. [`free_list::mark_free`], a prefix sum of the counts of each warp's tile,
//!    [`free_list::gather_free`]: the free slots of each kind's range, in slot order, for the
//!    master thread to hand out.
//!
//! Every kernel writes only its own slot's elements, and reads what others write only in a
//! later launch: no barriers, no float atomics, the same bits on every backend. The one
//! order that depends on scheduling (the arrival ranks of the bucket counts) is made
//! canonical by [`broad::order_cells`] before anything reads it.

pub mod bodies;
pub mod broad;
pub mod contact;
pub mod free_list;
pub mod integrate;
pub mod kinds;
pub mod narrow;
pub mod renumber;
pub mod scatter;
pub mod space;
pub mod teams;

pub use bodies::{Bodies, BodiesAccess, Contacts, ContactsAccess, Deaths, Touched};
pub use kinds::{KindInfo, KindTables, KindTablesAccess, SlotKind, SlotRange};
pub use space::Space;
