//! Whether a world's step runs as one persistent launch ([`Device::program`]) or as its
//! plan of launches, and why.

use crate::Device;
use crate::backend::BackendKind;

/// How a world's step is launched: as one persistent launch that runs its stages with a
/// barrier across the GPU between them, or as its plan of launches (a CUDA graph).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Persistent {
    /// The plan of launches, which is the faster wherever it has been measured (see
    /// [`Persistent::choose`]).
    #[default]
    Auto,
    /// Always persistent (the CPU emulation too: its threads wait at the same barriers).
    On,
    /// Always the plan of launches.
    Off,
}

impl Persistent {
    /// Whether a world steps persistently on `device`, and why, in words.
    pub fn choose(self, device: &Device) -> (bool, &'static str) {
        match (self, device.kind()) {
            (Persistent::On, _) => (true, "asked for (--persistent on)"),
            (Persistent::Off, _) => (false, "asked for (--persistent off)"),
            (Persistent::Auto, BackendKind::Cpu) => (
                false,
                "the CPU emulation: its launches start from inside its thread pool, and its \
                 blocks split each stage statically (paper 1,010 → 735 steps/s persistent)",
            ),
            (Persistent::Auto, BackendKind::Cuda) => (
                false,
                "a barrier across the GPU costs about 2 µs, twice a graph's launch boundary \
                 (H100, the launch floor: 11 stages 23.1 µs persistent, 12.5 as a graph)",
            ),
        }
    }
}
