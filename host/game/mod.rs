//! The game on the host side: scenes (TOML), the per-step driver that launches the game's
//! kernels in order, replays, and high scores.

pub mod accuracy;
pub mod engine;
pub mod highscore;
pub mod looks;
pub mod replay;
pub mod scene;
pub mod spec;

pub use engine::{Game, Options};
pub use spec::Scene;
