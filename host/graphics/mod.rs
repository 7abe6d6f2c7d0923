//! Drawing with OpenGL (glium): the GL renderer of the bodies ([`bodies`]), the display of
//! a frame the kernel renderer drew ([`picture`]), the HUD's text ([`hud`]), and a GL
//! context without a window for screenshots and tests ([`headless`]).
//!
//! Programs are made with `outputs_srgb`, so that GL writes the colours' bytes as given:
//! a GL frame can then be compared pixel for pixel with a kernel-drawn one.

pub mod bodies;
pub mod headless;
pub mod hud;
pub mod picture;

use std::fmt::Display;

use glium::Program;
use glium::backend::Facade;
use glium::program::ProgramCreationInput;

use crate::Error;

/// Which renderer draws the world.
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    clap::ValueEnum,
    serde::Serialize,
    serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum Renderer {
    /// A kernel draws an image that GL shows (one upload per frame): identical pixels on
    /// every backend.
    #[default]
    Kernel,
    /// GL draws the bodies from a vertex buffer that kernels write in place (CUDA–GL
    /// interop; uploaded from the CPU emulation).
    Interop,
}

impl Renderer {
    /// The name `--render` takes.
    pub fn name(self) -> &'static str {
        match self {
            Renderer::Kernel => "kernel",
            Renderer::Interop => "interop",
        }
    }
}

/// Turns a glium error into an [`Error::Graphics`] saying what was being done.
pub fn gl_error<E: Display>(during: &str) -> impl FnOnce(E) -> Error + '_ {
    move |e| Error::Graphics {
        during: during.to_string(),
        message: e.to_string(),
    }
}

/// A program from GLSL sources whose outputs are written as they are (no sRGB encoding).
fn program(facade: &impl Facade, vertex: &str, fragment: &str) -> Result<Program, Error> {
    Program::new(
        facade,
        ProgramCreationInput::SourceCode {
            vertex_shader: vertex,
            tessellation_control_shader: None,
            tessellation_evaluation_shader: None,
            geometry_shader: None,
            fragment_shader: fragment,
            transform_feedback_varyings: None,
            outputs_srgb: true,
            uses_point_size: true,
        },
    )
    .map_err(gl_error("compiling a shader"))
}

/// An RGBA8 colour packed little-endian as the floats GL clears with.
pub fn unpack(colour: u32) -> (f32, f32, f32, f32) {
    let [r, g, b, a] = colour.to_le_bytes().map(|c| f32::from(c) / 255.0);
    (r, g, b, a)
}
