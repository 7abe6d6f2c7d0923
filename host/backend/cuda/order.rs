//! The device's order: the lock whoever queues work on the GPU holds, and the side streams
//! that only its holder forks onto.

use std::sync::{Arc, Mutex, MutexGuard};

use cudarc::driver::CudaStream;

/// Streams for the branches of a plan (see `Gpu::beside`): the autopilot's, the
/// explosions', the tally's and a frame's drawn beside the step.
pub(super) const BRANCHES: usize = 4;

/// A device's order, shared by the GPU and the GL buffers registered with it (see
/// `Gpu::in_order`).
#[derive(Clone)]
pub(in crate::backend) struct Order(Arc<Mutex<Sides>>);

impl Order {
    /// The order of a device whose side streams are `sides`.
    pub(super) fn new(sides: Sides) -> Order {
        Order(Arc::new(Mutex::new(sides)))
    }

    /// Holds the order for as long as the guard lives; the side streams come with it. The
    /// lock's poison is ignored: the streams it guards are never changed, so a holder that
    /// panicked left nothing half written.
    pub(in crate::backend) fn hold(&self) -> MutexGuard<'_, Sides> {
        self.0.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// The side streams of a device, which only the holder of its order forks onto.
pub(in crate::backend) struct Sides(pub(super) Vec<Arc<CudaStream>>);
