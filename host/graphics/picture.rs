//! Images shown pixel for pixel: the kernel renderer's frames (one texture upload per
//! displayed frame) and the HUD's text.

use std::borrow::Cow;

use glium::backend::Facade;
use glium::index::{NoIndices, PrimitiveType};
use glium::texture::{ClientFormat, MipmapsOption, RawImage2d, Texture2d, UncompressedFloatFormat};
use glium::uniforms::{MagnifySamplerFilter, MinifySamplerFilter};
use glium::vertex::EmptyVertexAttributes;
use glium::{Blend, DrawParameters, Program, Rect, Surface, uniform};

use super::{GlError, gl_error, program};
use crate::pipeline::Frame;

const VERTEX_SHADER: &str = r#"
#version 330 core
void main() {
    // A quad covering the viewport, as a strip of four corners.
    vec2 corner = vec2(float(gl_VertexID & 1), float(gl_VertexID >> 1));
    gl_Position = vec4(corner * 2.0 - 1.0, 0.0, 1.0);
}
"#;

const FRAGMENT_SHADER: &str = r#"
#version 330 core
uniform sampler2D image;
uniform ivec2 origin;
out vec4 colour;
void main() {
    // The image's row 0 is its top; GL counts rows from the bottom.
    ivec2 size = textureSize(image, 0);
    ivec2 p = ivec2(gl_FragCoord.xy) - origin;
    colour = texelFetch(image, ivec2(p.x, size.y - 1 - p.y), 0);
}
"#;

/// An RGBA8 image in a texture, shown pixel for pixel.
pub struct Picture {
    program: Program,
    texture: Option<Texture2d>,
}

impl Picture {
    /// A picture with no image yet.
    pub fn new(facade: &impl Facade) -> Result<Self, GlError> {
        Ok(Picture {
            program: program(facade, VERTEX_SHADER, FRAGMENT_SHADER)?,
            texture: None,
        })
    }

    /// Uploads `frame` as the image (reusing the texture when the size is the same).
    pub fn set(&mut self, facade: &impl Facade, frame: &Frame) -> Result<(), GlError> {
        let image = RawImage2d {
            data: Cow::Borrowed(bytemuck::cast_slice::<u32, u8>(&frame.pixels)),
            width: frame.width,
            height: frame.height,
            format: ClientFormat::U8U8U8U8,
        };
        match &self.texture {
            Some(t) if (t.width(), t.height()) == (frame.width, frame.height) => {
                let whole = Rect {
                    left: 0,
                    bottom: 0,
                    width: frame.width,
                    height: frame.height,
                };
                t.write(whole, image);
            }
            _ => {
                let texture = Texture2d::with_format(
                    facade,
                    image,
                    UncompressedFloatFormat::U8U8U8U8,
                    MipmapsOption::NoMipmap,
                )
                .map_err(gl_error("uploading an image"))?;
                self.texture = Some(texture);
            }
        }
        Ok(())
    }

    /// Draws the image with its top-left corner at `(left, top)` pixels from the target's
    /// top-left corner (the target is `target_height` pixels high), over what is there when
    /// `blend` (by the image's alpha) or replacing it.
    pub fn draw(
        &self,
        target: &mut impl Surface,
        (left, top): (u32, u32),
        target_height: u32,
        blend: bool,
    ) -> Result<(), GlError> {
        let Some(texture) = &self.texture else {
            return Ok(());
        };
        let (width, height) = (texture.width(), texture.height());
        let bottom = target_height.saturating_sub(top + height);
        let uniforms = uniform! {
            image: texture.sampled()
                .magnify_filter(MagnifySamplerFilter::Nearest)
                .minify_filter(MinifySamplerFilter::Nearest),
            origin: [left as i32, bottom as i32],
        };
        let params = DrawParameters {
            blend: if blend {
                Blend::alpha_blending()
            } else {
                Blend::default()
            },
            viewport: Some(Rect {
                left,
                bottom,
                width,
                height,
            }),
            ..DrawParameters::default()
        };
        target
            .draw(
                EmptyVertexAttributes { len: 4 },
                NoIndices(PrimitiveType::TriangleStrip),
                &self.program,
                &uniforms,
                &params,
            )
            .map_err(gl_error("drawing an image"))
    }
}
