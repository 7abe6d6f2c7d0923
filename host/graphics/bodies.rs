//! The GL renderer, the paper's way: every body one point sprite of one draw call, from a
//! vertex buffer a kernel writes (`gpuwars_kernels::render::write_vertices`). On the CUDA
//! backend that buffer is GL's own, registered with CUDA once and written in place each
//! frame, so the bodies never travel through the host; elsewhere the emulator writes the
//! same vertices into host memory and they are uploaded.
//!
//! The kernel writes each vertex in image coordinates of the frame's view (the camera
//! kernel's, as the kernel renderer's), so the shaders only test pixels. They follow the
//! kernel renderer's rules (silhouettes, nose, hurt shade, the ship's halo, and the key
//! that decides which body is on top, kept in the depth buffer), so both draw the same
//! picture; where their arithmetic rounds differently an edge pixel may differ, and a body
//! whose centre is off the image is clipped whole. Explosions' particles are discs drawn
//! from vertices after the bodies' in the same buffer and the same draw call. The backdrop
//! (a followed frame's grid and the field's border) is a full-screen pass before them,
//! drawn from one more vertex of that buffer, which a kernel fills from the frame's view
//! (`gpuwars_kernels::render::backdrop_vertex`): the host neither computes the view nor
//! waits for it, and it costs no mapping of its own. The radar is the kernels' own image,
//! shown over the bodies.

use std::borrow::Cow;

use glium::backend::Facade;
use glium::index::{NoIndices, PrimitiveType};
use glium::texture::{
    ClientFormat, MipmapsOption, RawImage2d, UncompressedUintFormat, UnsignedTexture2d,
};
use glium::uniforms::{MagnifySamplerFilter, MinifySamplerFilter};
use glium::vertex::{AttributeType, EmptyVertexAttributes};
use glium::{Depth, DepthTest, DrawParameters, Program, Rect, Surface, VertexBuffer, uniform};
use gpuwars_kernels::render::camera::Lens;
use gpuwars_kernels::render::radar::{RadarBox, radar_box};
use gpuwars_kernels::render::{BodyVertex, Look, NOSE_FROM, backdrop};

use super::picture::{Blit, DeviceImage, Upload};
use super::{gl_error, program};
use crate::backend::DeviceId;
use crate::backend::GlBuffer;
use crate::game::{Game, looks};
use crate::pipeline::{Drawing, Frame, Pipeline};
use crate::{BackendKind, Buffer, Error};

/// The attributes of [`BodyVertex`], as the vertex shader names them.
const LAYOUT: glium::vertex::VertexFormat = &[
    (Cow::Borrowed("centre"), 0, -1, AttributeType::F32F32, false),
    (Cow::Borrowed("facing"), 8, -1, AttributeType::F32F32, false),
    (
        Cow::Borrowed("half_size"),
        16,
        -1,
        AttributeType::F32F32,
        false,
    ),
    (Cow::Borrowed("radius"), 24, -1, AttributeType::F32, false),
    (Cow::Borrowed("bound"), 28, -1, AttributeType::F32, false),
    (Cow::Borrowed("kind"), 32, -1, AttributeType::U32, false),
    (Cow::Borrowed("flags"), 36, -1, AttributeType::U32, false),
];
const _: () = assert!(size_of::<BodyVertex>() == 40);

/// Most kinds the shaders' key has room for (8 bits).
const MAX_KINDS: usize = 256;

const VERTEX_SHADER: &str = r#"
#version 330 core
in vec2 centre;
in vec2 facing;
in vec2 half_size;
in float radius;
in float bound;
in uint kind;
in uint flags;
// Per kind: (colour, nose, hurt, layer).
uniform usampler2D kinds;
uniform float width;
uniform float height;
flat out vec2 v_centre;
flat out vec2 v_facing;
flat out vec2 v_half;
flat out float v_radius;
flat out uint v_flags;
flat out uint v_kind;
flat out uvec4 look;

void main() {
    if ((flags & 1u) == 0u) {
        // A free slot: outside the clip volume, so nothing is drawn.
        gl_Position = vec4(2.0, 2.0, 2.0, 1.0);
        gl_PointSize = 1.0;
        return;
    }
    look = texelFetch(kinds, ivec2(int(kind), 0), 0);
    // The kernel wrote the image position and sizes in the frame's view: nothing to scale.
    v_centre = centre;
    v_facing = facing;
    v_half = half_size;
    v_radius = radius;
    v_flags = flags;
    v_kind = kind;
    // Large enough for every pixel the shape covers, and the one under the centre.
    gl_PointSize = 2.0 * ceil(bound) + 2.0;
    gl_Position = vec4(centre.x / width * 2.0 - 1.0, 1.0 - centre.y / height * 2.0, 0.0, 1.0);
}
"#;

/// GLSL: an RGBA8 colour packed little-endian as the floats GL writes.
const RGBA: &str = "vec4 rgba(uint c) {
    return vec4(float(c & 255u), float((c >> 8) & 255u), float((c >> 16) & 255u),
        float(c >> 24)) / 255.0;
}";

/// The fragment shader: `gpuwars_kernels::render::shade_at` and `shapes::inside`, line for
/// line, with the kernels' constants filled in.
fn fragment_shader() -> String {
    use gpuwars_kernels::render::shapes::*;
    use gpuwars_kernels::render::{
        HALO_FADE, HALO_FROM, HALO_LAYER, HALO_TO, PARTICLE_LAYER, VERTEX_LEVEL_SHIFT,
        VERTEX_PARTICLE,
    };
    format!(
        r#"
#version 330 core
uniform float height;
uniform float nose_from;
uniform uint background;
flat in vec2 v_centre;
flat in vec2 v_facing;
flat in vec2 v_half;
flat in float v_radius;
flat in uint v_flags;
flat in uint v_kind;
flat in uvec4 look;
out vec4 colour;

{RGBA}

// The offset d in the body's frame: u along the heading, v across it.
vec2 local(vec2 d, vec2 h) {{
    return vec2(d.x * h.x + d.y * h.y, d.y * h.x - d.x * h.y);
}}

bool inside(uint s, vec2 p, float r) {{
    float u = p.x;
    float v = abs(p.y);
    if (s == {SQUARE}u) return abs(u) <= 0.7 * r && v <= 0.7 * r;
    if (s == {DIAMOND}u) return abs(u) + v <= r;
    if (s == {TRIANGLE}u) return u >= -0.6 * r && v <= (r - u) * 0.5;
    if (s == {RING}u) {{
        float d2 = u * u + v * v;
        return d2 <= r * r && d2 >= {RING_HOLE:?} * {RING_HOLE:?} * r * r;
    }}
    if (s == {CHEVRON}u) return 3.0 * v <= r - u && u >= -0.5 * r - 0.5 * v;
    if (s == {CROSS}u) {{
        float a = abs(u);
        return (a <= 0.3 * r && v <= 0.95 * r) || (v <= 0.3 * r && a <= 0.95 * r);
    }}
    if (s == {HEXAGON}u) return v <= {HALF_SQRT3:?} * r && abs(u) + v * {INV_SQRT3:?} <= r;
    if (s == {BOWTIE}u) return abs(u) <= 0.75 * r && v <= abs(u) * 0.8;
    if (s == {STREAK}u) {{
        float along = max(min(u, 0.0), -{STREAK_LENGTH:?} * r);
        float du = u - along;
        return du * du + v * v <= r * r;
    }}
    return u * u + v * v <= r * r;
}}

// Colour c moved level sixteenths of the way to b, in integer steps.
uint fade(uint c, uint b, int level) {{
    uint result = 0u;
    for (int i = 0; i < 32; i += 8) {{
        int x = int((c >> uint(i)) & 255u);
        int y = int((b >> uint(i)) & 255u);
        result |= uint(x + (y - x) * level / 16) << uint(i);
    }}
    return result;
}}

void main() {{
    // This pixel as the kernel renderer numbers it (row 0 at the top).
    vec2 pixel = vec2(floor(gl_FragCoord.x), height - 1.0 - floor(gl_FragCoord.y));
    vec2 d = pixel + 0.5 - v_centre;
    // A body smaller than a pixel still shows in the pixel under its centre.
    bool under = v_centre.x >= 0.0 && v_centre.y >= 0.0 && floor(v_centre) == pixel;
    uint key;
    if ((v_flags & {VERTEX_PARTICLE}u) != 0u) {{
        // A particle: a disc in the lowest layer, its kind's colour faded by its level.
        if (!(under || dot(d, d) <= v_radius * v_radius)) discard;
        uint level = v_flags >> {VERTEX_LEVEL_SHIFT};
        key = (uint({PARTICLE_LAYER}) << 13) | (v_kind << 5) | 16u | level;
        gl_FragDepth = float(key) / 16777216.0;
        colour = rgba(fade(look.x, background, int(level)));
        return;
    }}
    uint s = (v_flags >> 8) & 255u;
    float r = v_radius;
    bool within = s == {RECT}u
        ? abs(d.x) <= v_half.x && abs(d.y) <= v_half.y
        : (s == {DISC}u ? dot(d, d) <= r * r : inside(s, local(d, v_facing), r));
    uint body_shade = (v_flags & 2u) != 0u ? 2u : 0u;
    uint shade = 0u;
    if (within) {{
        shade = dot(d, v_facing) > nose_from * r ? 1u : body_shade;
    }} else {{
        float from = {HALO_FROM:?} * r;
        float to = {HALO_TO:?} * r;
        float d2 = dot(d, d);
        if ((v_flags & 4u) != 0u && d2 >= from * from && d2 <= to * to) {{
            shade = 3u;
        }} else if (under) {{
            shade = body_shade;
        }} else {{
            discard;
        }}
    }}
    uint layer = shade == 3u ? {HALO_LAYER}u : look.w;
    // The kernel renderer's key order: layer, then kind, then shade (a particle's: its
    // level), with a drawn bit; the highest is on top.
    key = (layer << 13) | (v_kind << 5) | 16u | shade;
    gl_FragDepth = float(key) / 16777216.0;
    uint c = shade == 1u ? look.y
        : (shade == 2u ? look.z : (shade == 3u ? fade(look.x, background, {HALO_FADE}) : look.x));
    colour = rgba(c);
}}
"#
    )
}

/// The backdrop pass's vertex shader: a quad over the viewport, drawn once (one instance)
/// with the backdrop's vertex as its attributes; off the clip volume when the frame has no
/// backdrop.
const BACKDROP_VERTEX_SHADER: &str = r#"
#version 330 core
in vec2 centre;
in vec2 facing;
in float radius;
in uint flags;
flat out vec2 origin;
flat out vec2 field;
flat out float scale;

void main() {
    origin = centre;
    field = facing;
    scale = radius;
    vec2 corner = vec2(float(gl_VertexID & 1), float(gl_VertexID >> 1));
    gl_Position = (flags & BACKDROP_FLAG) != 0u
        ? vec4(corner * 2.0 - 1.0, 0.0, 1.0)
        : vec4(2.0, 2.0, 2.0, 1.0);
}
"#;

/// The backdrop pass's fragment shader: `gpuwars_kernels::render::backdrop::on_grid`, line
/// for line, with the kernels' constants filled in.
fn backdrop_fragment_shader() -> String {
    use backdrop::{BORDER, LINE, MIN_GAP_PX, SPACING};
    format!(
        r#"
#version 330 core
flat in vec2 origin;
flat in vec2 field;
flat in float scale;
out vec4 colour;

{RGBA}

// Along one axis: 0 outside the field, 1 inside on no line, 2 on a line, 3 the border.
int mark(float origin, float scale, float field, bool lines, float p) {{
    float centre = p + 0.5;
    float low = (0.0 - origin) * scale;
    float high = (field - origin) * scale;
    if (centre < low || centre >= high) return 0;
    if (centre - 1.0 < low || centre + 1.0 >= high) return 3;
    float k = floor((origin + centre / scale) / {SPACING:?} + 0.5);
    if (lines && floor((k * {SPACING:?} - origin) * scale) == p) return 2;
    return 1;
}}

void main() {{
    bool lines = {SPACING:?} * scale >= {MIN_GAP_PX:?};
    // Rows count from the bottom, as the world's y runs (and GL's).
    int across = mark(origin.x, scale, field.x, lines, floor(gl_FragCoord.x));
    int up = mark(origin.y, scale, field.y, lines, floor(gl_FragCoord.y));
    if (across == 0 || up == 0) discard;
    if (across == 3 || up == 3) {{
        colour = rgba({BORDER}u);
    }} else if (across == 2 || up == 2) {{
        colour = rgba({LINE}u);
    }} else {{
        discard;
    }}
}}
"#
    )
}

/// How the vertices reach GL.
enum Feed {
    /// Kernels write GL's buffer in place (CUDA backend, NVIDIA GL).
    Interop(GlBuffer),
    /// Kernels write this device buffer, and its contents are uploaded.
    Upload(Buffer<BodyVertex>),
}

/// Draws a pipeline's bodies with GL: one point sprite per slot; then the radar, drawn
/// by a kernel, as an image over them.
pub struct BodyRenderer {
    program: Program,
    backdrop: Program,
    vertices: VertexBuffer<BodyVertex>,
    /// Index of the backdrop's vertex (after the bodies').
    backdrop_at: usize,
    kinds: UnsignedTexture2d,
    looks: Vec<Look>,
    feed: Feed,
    /// Why the vertices are uploaded on a GPU backend, if they are.
    fallback: Option<String>,
    /// The radar of the last update, and where it goes.
    radar: Option<RadarBox>,
    /// On the CUDA backend, the radar written by a kernel into a GL pixel buffer: `Err`
    /// once that failed (GL not on the NVIDIA driver), and the radar is read back.
    radar_device: Result<Option<DeviceImage>, ()>,
    radar_upload: Upload,
    blit: Blit,
    /// The device of the pipeline it was made for, whose memory its buffers are.
    device: DeviceId,
}

impl BodyRenderer {
    /// A renderer of `pipeline`'s bodies, each kind looking as `looks` says. On the CUDA
    /// backend the vertex buffer is registered with CUDA; if GL is not the NVIDIA driver's,
    /// the vertices are uploaded instead, and [`BodyRenderer::fallback`] says why.
    pub fn new(facade: &impl Facade, pipeline: &Pipeline, looks: &[Look]) -> Result<Self, Error> {
        if looks.len() > MAX_KINDS {
            return Err(Error::Graphics {
                during: "setting up the body renderer".into(),
                message: format!("{} looks (allowed at most {MAX_KINDS})", looks.len()),
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
            program: program(facade, VERTEX_SHADER, &fragment_shader())?,
            backdrop: program(
                facade,
                &BACKDROP_VERTEX_SHADER.replace(
                    "BACKDROP_FLAG",
                    &format!("{}u", gpuwars_kernels::render::VERTEX_BACKDROP),
                ),
                &backdrop_fragment_shader(),
            )?,
            vertices,
            backdrop_at: pipeline.layout().slots as usize,
            kinds: kind_texture(facade, looks)?,
            looks: looks.to_vec(),
            feed,
            fallback,
            radar: None,
            radar_device: if device.kind() == BackendKind::Cuda {
                Ok(None)
            } else {
                Err(())
            },
            radar_upload: Upload::default(),
            blit: Blit::new(facade)?,
            device: device.id(),
        })
    }

    /// A renderer of `game`'s bodies, in its scene's looks (see [`BodyRenderer::new`]).
    pub fn for_game(facade: &impl Facade, game: &Game) -> Result<Self, Error> {
        BodyRenderer::new(facade, game.pipeline(), &looks::looks(game.scene()))
    }

    /// Whether kernels write GL's vertex buffer in place (CUDA–GL interop).
    pub fn is_interop(&self) -> bool {
        matches!(self.feed, Feed::Interop(_))
    }

    /// Why a GPU backend's vertices are uploaded rather than written in place, if they are.
    pub fn fallback(&self) -> Option<&str> {
        self.fallback.as_deref()
    }

    /// Points the camera of `lens` and writes every body's vertex in its view after the
    /// steps queued on the pipeline of `drawing` (one of the device this renderer was made
    /// for: another's is refused), and takes the radar's image.
    pub fn update(
        &mut self,
        facade: &impl Facade,
        drawing: &mut Drawing,
        lens: &Lens,
    ) -> Result<(), Error> {
        self.device.check(drawing.device().id(), "a renderer")?;
        let looks = &self.looks;
        match &mut self.feed {
            Feed::Interop(buffer) => {
                // SAFETY: the view goes only into the launches `write_vertices` queues; the
                // mapped buffer holds one vertex per slot (made so above) and only these
                // launches touch it until the unmap.
                unsafe {
                    buffer.with_mapped(|vertices| drawing.write_vertices(lens, looks, vertices))
                }?;
            }
            Feed::Upload(buffer) => {
                drawing.vertices_into(lens, looks, buffer)?;
                let vertices = drawing.device().download(buffer)?;
                self.vertices.write(&vertices);
            }
        }
        self.radar = (lens.radar != 0)
            .then(|| radar_box(lens.width, lens.height, lens.field))
            .filter(|radar| radar.width != 0);
        if let Some(radar) = self.radar {
            self.show_radar(facade, drawing, radar)?;
        }
        Ok(())
    }

    /// Takes the radar's image of the last vertices written: on the GPU into a GL pixel
    /// buffer, without leaving it, where CUDA–GL interop works; else read back and
    /// uploaded (a few thousand pixels).
    fn show_radar(
        &mut self,
        facade: &impl Facade,
        pipeline: &Pipeline,
        radar: RadarBox,
    ) -> Result<(), Error> {
        let size = (radar.width, radar.height);
        if let Ok(image) = &mut self.radar_device
            && image.as_ref().is_none_or(|i| i.size() != size)
        {
            match DeviceImage::new(facade, pipeline.device(), size.0, size.1) {
                Ok(made) => *image = Some(made),
                Err(_) => self.radar_device = Err(()),
            }
        }
        if let Ok(Some(image)) = &mut self.radar_device {
            // SAFETY: the view goes only into the launch `radar_into` queues; the mapped
            // buffer holds the radar's box and only this launch touches it until the unmap.
            unsafe { image.set(|pixels| pipeline.radar_into(pixels)) }?;
            return Ok(());
        }
        let image = Frame {
            width: radar.width,
            height: radar.height,
            pixels: pipeline.radar_image(radar)?,
        };
        self.radar_upload.set(facade, &image)
    }

    /// Draws the backdrop, then the bodies and particles as the last
    /// [`BodyRenderer::update`] placed them, and its radar, onto `target`, whose size must
    /// be `lens`'s (the lens of that update). The caller clears colour to the background
    /// and depth to 0 first.
    pub fn draw(&self, target: &mut impl Surface, lens: &Lens) -> Result<(), Error> {
        let viewport = Some(Rect {
            left: 0,
            bottom: 0,
            width: lens.width,
            height: lens.height,
        });
        let at = self.backdrop_at;
        let vertex = self
            .vertices
            .slice(at..at + 1)
            .expect("the buffer holds the backdrop's vertex");
        let instance = vertex.per_instance().map_err(|_| Error::Graphics {
            during: "drawing the backdrop".into(),
            message: "GL has no instanced drawing (OpenGL 3.3 has)".into(),
        })?;
        let backdrop = DrawParameters {
            viewport,
            ..DrawParameters::default()
        };
        target
            .draw(
                (EmptyVertexAttributes { len: 4 }, instance),
                NoIndices(PrimitiveType::TriangleStrip),
                &self.backdrop,
                &uniform! {},
                &backdrop,
            )
            .map_err(gl_error("drawing the backdrop"))?;
        let uniforms = uniform! {
            kinds: self.kinds.sampled()
                .magnify_filter(MagnifySamplerFilter::Nearest)
                .minify_filter(MinifySamplerFilter::Nearest),
            width: lens.width as f32,
            height: lens.height as f32,
            nose_from: NOSE_FROM,
            background: lens.background,
        };
        let params = DrawParameters {
            depth: Depth {
                test: DepthTest::IfMore,
                write: true,
                ..Depth::default()
            },
            viewport,
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
            .map_err(gl_error("drawing the bodies"))?;
        let texture = match &self.radar_device {
            Ok(Some(image)) => Some(image.texture()),
            _ => self.radar_upload.texture(),
        };
        if let (Some(radar), Some(texture)) = (self.radar, texture) {
            let at = (radar.left, radar.top);
            self.blit
                .draw(target, texture, true, at, lens.height, false)?;
        }
        Ok(())
    }
}

/// The per-kind table the shaders read: colours and layer.
fn kind_texture(facade: &impl Facade, looks: &[Look]) -> Result<UnsignedTexture2d, Error> {
    let texels: Vec<u32> = looks
        .iter()
        .flat_map(|l| [l.colour, l.nose, l.hurt, l.layer.min(255)])
        .collect();
    let image = RawImage2d {
        data: Cow::Owned(texels),
        width: looks.len() as u32,
        height: 1,
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
