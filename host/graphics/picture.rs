//! Images shown pixel for pixel: the kernel renderer's frames (one texture upload per
//! displayed frame) and the HUD's text.

use std::borrow::Cow;

use glium::backend::Facade;
use glium::buffer::{BufferMode, BufferType};
use glium::index::{NoIndices, PrimitiveType};
use glium::texture::{ClientFormat, MipmapsOption, RawImage2d, Texture2d, UncompressedFloatFormat};
use glium::uniforms::{MagnifySamplerFilter, MinifySamplerFilter};
use glium::vertex::EmptyVertexAttributes;
use glium::{Blend, DrawParameters, GlObject, Program, Rect, Surface, uniform};
use gpuwars_kernels::DevSlice;

use super::{gl_error, program};
use crate::backend::GlBuffer;
use crate::pipeline::Frame;
use crate::{Device, Error};

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
uniform bool top_down;
out vec4 colour;
void main() {
    ivec2 size = textureSize(image, 0);
    ivec2 p = ivec2(gl_FragCoord.xy) - origin;
    // GL counts rows from the bottom; an uploaded image's row 0 is its top.
    colour = texelFetch(image, ivec2(p.x, top_down ? size.y - 1 - p.y : p.y), 0);
}
"#;

/// An image that kernels write into a GL pixel buffer registered with CUDA, then copied
/// into a texture by GL: the kernel renderer's frames shown without leaving the GPU.
pub struct DeviceImage {
    /// Registered with CUDA: dropped before the GL buffer.
    registered: GlBuffer,
    pixels: glium::buffer::Buffer<[(u8, u8, u8, u8)]>,
    texture: Texture2d,
}

impl DeviceImage {
    /// A `width × height` image in `device`'s reach (the CUDA backend, with GL on the
    /// NVIDIA driver).
    pub fn new(
        facade: &impl Facade,
        device: &Device,
        width: u32,
        height: u32,
    ) -> Result<Self, Error> {
        let count = width as usize * height as usize;
        let pixels = glium::buffer::Buffer::empty_array(
            facade,
            BufferType::PixelUnpackBuffer,
            count,
            BufferMode::Dynamic,
        )
        .map_err(gl_error("making a pixel buffer"))?;
        let registered = device.register_gl_buffer(pixels.get_id())?;
        let texture = Texture2d::empty_with_format(
            facade,
            UncompressedFloatFormat::U8U8U8U8,
            MipmapsOption::NoMipmap,
            width,
            height,
        )
        .map_err(gl_error("making a texture"))?;
        Ok(DeviceImage {
            registered,
            pixels,
            texture,
        })
    }

    /// The image's width and height.
    pub fn size(&self) -> (u32, u32) {
        (self.texture.width(), self.texture.height())
    }

    /// The texture, as the last [`DeviceImage::set`] left it.
    pub fn texture(&self) -> &Texture2d {
        &self.texture
    }

    /// Lets `write` fill the pixel buffer (row 0 the image's top) with launches on the
    /// device, then copies it into the texture on the GPU.
    ///
    /// # Safety
    /// As for [`GlBuffer::with_mapped`](crate::backend::GlBuffer::with_mapped).
    pub unsafe fn set(
        &mut self,
        write: impl FnOnce(DevSlice<u32>) -> Result<(), Error>,
    ) -> Result<&Texture2d, Error> {
        // SAFETY: forwarded.
        unsafe { self.registered.with_mapped(write) }?;
        let (width, height) = self.size();
        self.texture.main_level().raw_upload_from_pixel_buffer(
            self.pixels.as_slice(),
            0..width,
            0..height,
            0..1,
        );
        Ok(&self.texture)
    }
}

/// Draws textures pixel for pixel.
pub struct Blit {
    program: Program,
}

/// An RGBA8 image uploaded into a texture, which is kept for the next image of its size.
#[derive(Default)]
pub struct Upload {
    texture: Option<Texture2d>,
}

impl Upload {
    /// The texture of the last image set, if any.
    pub fn texture(&self) -> Option<&Texture2d> {
        self.texture.as_ref()
    }

    /// Uploads `frame` as the image.
    pub fn set(&mut self, facade: &impl Facade, frame: &Frame) -> Result<(), Error> {
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
}

impl Blit {
    /// The program that draws them.
    pub fn new(facade: &impl Facade) -> Result<Self, Error> {
        Ok(Blit {
            program: program(facade, VERTEX_SHADER, FRAGMENT_SHADER)?,
        })
    }

    /// Draws `texture` (row 0 its top if `top_down`, as uploaded frames have it; its bottom
    /// otherwise, as GL draws) with its top-left corner at `(left, top)` pixels from
    /// the target's top-left corner (the target is `target_height` pixels high), over what
    /// is there when `blend` (by the image's alpha) or replacing it.
    pub fn draw(
        &self,
        target: &mut impl Surface,
        texture: &Texture2d,
        top_down: bool,
        (left, top): (u32, u32),
        target_height: u32,
        blend: bool,
    ) -> Result<(), Error> {
        let (width, height) = (texture.width(), texture.height());
        let bottom = target_height.saturating_sub(top + height);
        let uniforms = uniform! {
            image: texture.sampled()
                .magnify_filter(MagnifySamplerFilter::Nearest)
                .minify_filter(MinifySamplerFilter::Nearest),
            origin: [left as i32, bottom as i32],
            top_down: top_down,
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
