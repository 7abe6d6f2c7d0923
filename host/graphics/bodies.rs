//! The GL renderer, the paper's way: every body one point sprite of one draw call, from a
//! vertex buffer a kernel writes (`gpuwars_kernels::render::write_vertices`). On the CUDA
//! backend that buffer is GL's own, registered with CUDA once and written in place each
//! frame, so the bodies never travel through the host; elsewhere the emulator writes the
//! same vertices into host memory and they are uploaded.
//!
//! The shaders follow the kernel renderer's rules (shape, nose, hurt shade, and the key that
//! decides which body is on top, kept in the depth buffer), so both draw the same picture;
//! where their arithmetic rounds differently an edge pixel may differ, and a body whose
//! centre is off the image is clipped whole.

use std::borrow::Cow;

use glium::backend::Facade;
use glium::index::{NoIndices, PrimitiveType};
use glium::texture::{
    ClientFormat, MipmapsOption, RawImage2d, UncompressedUintFormat, UnsignedTexture2d,
};
use glium::uniforms::{MagnifySamplerFilter, MinifySamplerFilter};
use glium::vertex::AttributeType;
use glium::{Depth, DepthTest, DrawParameters, Program, Rect, Surface, VertexBuffer, uniform};
use gpuwars_kernels::render::{BodyVertex, Look, MAX_RADIUS_PX, NOSE_FROM, View};
use gpuwars_kernels::sim::KindInfo;
use gpuwars_kernels::sim::kinds::SHAPE_RECT;

use super::{gl_error, program};
use crate::backend::GlBuffer;
use crate::game::{Game, looks};
use crate::pipeline::Pipeline;
use crate::sim::layout::kind_table;
use crate::{BackendKind, Buffer, Error};

/// The attributes of [`BodyVertex`], as the vertex shader names them.
const LAYOUT: glium::vertex::VertexFormat = &[
    (Cow::Borrowed("pos"), 0, -1, AttributeType::F32F32, false),
    (Cow::Borrowed("dir"), 8, -1, AttributeType::F32F32, false),
    (Cow::Borrowed("kind"), 16, -1, AttributeType::U32, false),
    (Cow::Borrowed("flags"), 20, -1, AttributeType::U32, false),
];
const _: () = assert!(size_of::<BodyVertex>() == 24);

/// Most kinds the shaders' key has room for (8 bits).
const MAX_KINDS: usize = 256;

const VERTEX_SHADER: &str = r#"
#version 330 core
in vec2 pos;
in vec2 dir;
in uint kind;
in uint flags;
// Per kind: (colour, nose, hurt, layer) in row 0; (rect?, radius, half.x, half.y) in row 1.
uniform usampler2D kinds;
uniform vec2 origin;
uniform float scale;
uniform float width;
uniform float height;
uniform float max_radius;
flat out vec2 centre;
flat out vec2 half_size;
flat out float reach;
flat out uint rect;
flat out vec2 facing;
flat out uint body_shade;
flat out uint body_kind;
flat out uvec4 look;

void main() {
    if ((flags & 1u) == 0u) {
        // A free slot: outside the clip volume, so nothing is drawn.
        gl_Position = vec4(2.0, 2.0, 2.0, 1.0);
        gl_PointSize = 1.0;
        return;
    }
    look = texelFetch(kinds, ivec2(int(kind), 0), 0);
    uvec4 shape = texelFetch(kinds, ivec2(int(kind), 1), 0);
    vec2 p = (pos - origin) * scale;
    // Image coordinates (y down), computed as the kernel renderer computes them.
    centre = vec2(p.x, height - p.y);
    reach = min(uintBitsToFloat(shape.y) * scale, max_radius);
    rect = shape.x;
    half_size = rect == 1u
        ? min(vec2(uintBitsToFloat(shape.z), uintBitsToFloat(shape.w)) * scale, vec2(max_radius))
        : vec2(reach);
    facing = vec2(dir.x, -dir.y);
    body_shade = (flags & 2u) != 0u ? 2u : 0u;
    body_kind = kind;
    // Large enough for every pixel the shape covers, and the one under the centre.
    gl_PointSize = 2.0 * ceil(max(half_size.x, half_size.y)) + 2.0;
    gl_Position = vec4(p.x / width * 2.0 - 1.0, p.y / height * 2.0 - 1.0, 0.0, 1.0);
}
"#;

const FRAGMENT_SHADER: &str = r#"
#version 330 core
uniform float height;
uniform float nose_from;
flat in vec2 centre;
flat in vec2 half_size;
flat in float reach;
flat in uint rect;
flat in vec2 facing;
flat in uint body_shade;
flat in uint body_kind;
flat in uvec4 look;
out vec4 colour;

vec4 rgba(uint c) {
    return vec4(float(c & 255u), float((c >> 8) & 255u), float((c >> 16) & 255u),
        float(c >> 24)) / 255.0;
}

void main() {
    // This pixel as the kernel renderer numbers it (row 0 at the top).
    vec2 pixel = vec2(floor(gl_FragCoord.x), height - 1.0 - floor(gl_FragCoord.y));
    vec2 d = pixel + 0.5 - centre;
    bool inside = rect == 1u
        ? abs(d.x) <= half_size.x && abs(d.y) <= half_size.y
        : dot(d, d) <= reach * reach;
    // A body smaller than a pixel still shows in the pixel under its centre.
    bool under = centre.x >= 0.0 && centre.y >= 0.0 && floor(centre) == pixel;
    if (!inside && !under) {
        discard;
    }
    uint shade = dot(d, facing) > nose_from * reach ? 1u : body_shade;
    // The kernel renderer's key order: layer, then kind, then shade; the highest is on top.
    uint key = (look.w << 10) | (body_kind << 2) | shade;
    gl_FragDepth = float(key) / 16777216.0;
    colour = rgba(shade == 1u ? look.y : (shade == 2u ? look.z : look.x));
}
"#;

/// How the vertices reach GL.
enum Feed {
    /// Kernels write GL's buffer in place (CUDA backend, NVIDIA GL).
    Interop(GlBuffer),
    /// Kernels write this device buffer, and its contents are uploaded.
    Upload(Buffer<BodyVertex>),
}

/// Draws a pipeline's bodies with GL: one point sprite per slot.
pub struct BodyRenderer {
    program: Program,
    vertices: VertexBuffer<BodyVertex>,
    kinds: UnsignedTexture2d,
    feed: Feed,
    /// Why the vertices are uploaded on a GPU backend, if they are.
    fallback: Option<String>,
}

impl BodyRenderer {
    /// A renderer of `pipeline`'s bodies, whose kinds are `kinds` (their shapes) and look as
    /// `looks` say. On the CUDA backend the vertex buffer is registered with CUDA; if GL is
    /// not the NVIDIA driver's, the vertices are uploaded instead, and
    /// [`BodyRenderer::fallback`] says why.
    pub fn new(
        facade: &impl Facade,
        pipeline: &Pipeline,
        kinds: &[KindInfo],
        looks: &[Look],
    ) -> Result<Self, Error> {
        if kinds.len() != looks.len() || kinds.len() > MAX_KINDS {
            return Err(Error::Graphics {
                during: "setting up the body renderer".into(),
                message: format!(
                    "{} kinds and {} looks (allowed: as many looks as kinds, at most {MAX_KINDS})",
                    kinds.len(),
                    looks.len()
                ),
            });
        }
        let count = pipeline.vertex_count() as usize;
        // SAFETY: `LAYOUT` describes `BodyVertex` (checked size, offsets from its fields).
        let vertices = unsafe {
            VertexBuffer::new_raw_dynamic(
                facade,
                &vec![BodyVertex::default(); count],
                LAYOUT,
                size_of::<BodyVertex>(),
            )
        }
        .map_err(gl_error("making the vertex buffer"))?;
        let device = pipeline.device();
        let (feed, fallback) = match device.kind() {
            BackendKind::Cuda => {
                use glium::GlObject;
                match device.register_gl_buffer(vertices.get_id()) {
                    Ok(buffer) => (Feed::Interop(buffer), None),
                    Err(e) => (
                        Feed::Upload(device.alloc_zeroed(count)?),
                        Some(format!("CUDA–GL interop is not available ({e})")),
                    ),
                }
            }
            BackendKind::Cpu => (Feed::Upload(device.alloc_zeroed(count)?), None),
        };
        Ok(BodyRenderer {
            program: program(facade, VERTEX_SHADER, FRAGMENT_SHADER)?,
            vertices,
            kinds: kind_texture(facade, kinds, looks)?,
            feed,
            fallback,
        })
    }

    /// A renderer of `game`'s bodies, in its scene's looks (see [`BodyRenderer::new`]).
    pub fn for_game(facade: &impl Facade, game: &Game) -> Result<Self, Error> {
        let scene = game.scene();
        let kinds = kind_table(&scene.world);
        BodyRenderer::new(facade, game.pipeline(), &kinds, &looks::looks(scene))
    }

    /// Whether kernels write GL's vertex buffer in place (CUDA–GL interop).
    pub fn is_interop(&self) -> bool {
        matches!(self.feed, Feed::Interop(_))
    }

    /// Why a GPU backend's vertices are uploaded rather than written in place, if they are.
    pub fn fallback(&self) -> Option<&str> {
        self.fallback.as_deref()
    }

    /// Writes every body's vertex after the steps queued on `pipeline` (the pipeline this
    /// renderer was made for).
    pub fn update(&mut self, pipeline: &Pipeline) -> Result<(), Error> {
        match &mut self.feed {
            Feed::Interop(buffer) => {
                // SAFETY: the mapped buffer holds one vertex per slot (made so above) and
                // only this launch touches it until the unmap.
                buffer.with_mapped(|vertices| unsafe { pipeline.write_vertices(vertices) })?;
            }
            Feed::Upload(buffer) => {
                pipeline.vertices_into(buffer)?;
                let vertices = pipeline.device().download(buffer)?;
                self.vertices.write(&vertices);
            }
        }
        Ok(())
    }

    /// Draws the bodies as `view` shows the world onto `target`, whose size must be the
    /// view's. The caller clears colour to the background and depth to 0 first.
    pub fn draw(&self, target: &mut impl Surface, view: &View) -> Result<(), Error> {
        let uniforms = uniform! {
            kinds: self.kinds.sampled()
                .magnify_filter(MagnifySamplerFilter::Nearest)
                .minify_filter(MinifySamplerFilter::Nearest),
            origin: view.origin.to_array(),
            scale: view.scale,
            width: view.width as f32,
            height: view.height as f32,
            max_radius: MAX_RADIUS_PX,
            nose_from: NOSE_FROM,
        };
        let params = DrawParameters {
            depth: Depth {
                test: DepthTest::IfMore,
                write: true,
                ..Depth::default()
            },
            viewport: Some(Rect {
                left: 0,
                bottom: 0,
                width: view.width,
                height: view.height,
            }),
            ..DrawParameters::default()
        };
        target
            .draw(
                &self.vertices,
                NoIndices(PrimitiveType::Points),
                &self.program,
                &uniforms,
                &params,
            )
            .map_err(gl_error("drawing the bodies"))
    }
}

/// The per-kind table the shaders read: colours and layer, then shape and sizes.
fn kind_texture(
    facade: &impl Facade,
    kinds: &[KindInfo],
    looks: &[Look],
) -> Result<UnsignedTexture2d, Error> {
    let mut texels: Vec<u32> = looks
        .iter()
        .flat_map(|l| [l.colour, l.nose, l.hurt, l.layer.min(255)])
        .collect();
    texels.extend(kinds.iter().flat_map(|k| {
        [
            u32::from(k.shape == SHAPE_RECT),
            k.radius.to_bits(),
            k.half.x.to_bits(),
            k.half.y.to_bits(),
        ]
    }));
    let image = RawImage2d {
        data: Cow::Owned(texels),
        width: kinds.len() as u32,
        height: 2,
        format: ClientFormat::U32U32U32U32,
    };
    UnsignedTexture2d::with_format(
        facade,
        image,
        UncompressedUintFormat::U32U32U32U32,
        MipmapsOption::NoMipmap,
    )
    .map_err(gl_error("making the kind table"))
}
