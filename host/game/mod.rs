//! The game on the host side: scenes (TOML), the per-step driver that launches the game's
//! kernels in order, and replays.

pub mod scene;
pub mod spec;
pub mod demo;
pub mod engine;

pub use engine::Game;
pub use spec::Scene;
pub mod replay;
