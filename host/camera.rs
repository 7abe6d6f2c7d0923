//! The camera as the host asks for it: follow the ship or show the whole field, and how
//! close. The device decides each frame's view (`gpuwars_kernels::render::camera`); the
//! host computes the very same view with the same functions ([`view`]) when it needs one,
//! e.g. to map the cursor to the field.

use glam::Vec2;
use gpuwars_kernels::render::Framing;
use gpuwars_kernels::render::camera::{self, CameraState, Lens};

/// What the camera shows.
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
pub enum CameraMode {
    /// Centred on the ship, zoomed in, with the radar in a corner.
    #[default]
    Follow,
    /// The whole field, without the radar.
    Field,
}

impl CameraMode {
    /// The name `--camera` takes.
    pub fn name(self) -> &'static str {
        match self {
            CameraMode::Follow => "follow",
            CameraMode::Field => "field",
        }
    }
}

/// The zoom of the default camera: 1.5 pixels per unit at 1080p, so that the `paper`
/// ship (radius 10) is a chevron 30 pixels across (about 200 pixels), clearly larger than
/// its largest enemy (radius 8), with 1,280 × 720 units of the field around it.
pub const DEFAULT_ZOOM: f32 = 1.5;
/// Smallest zoom kept; the device shows the whole field at any zoom below the one at
/// which it fits.
pub const MIN_ZOOM: f32 = 0.001;
/// Largest zoom.
pub const MAX_ZOOM: f32 = camera::MAX_ZOOM;

/// The camera: its mode and zoom (pixels per unit in follow mode, as a multiple of
/// `height / 1080`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// What it shows.
    pub mode: CameraMode,
    /// How close it follows, from [`MIN_ZOOM`] to [`MAX_ZOOM`].
    pub zoom: f32,
}

impl Default for Camera {
    fn default() -> Self {
        Camera::new(CameraMode::Follow, DEFAULT_ZOOM)
    }
}

impl Camera {
    /// A camera in `mode` at `zoom` (kept from [`MIN_ZOOM`] to [`MAX_ZOOM`]).
    pub fn new(mode: CameraMode, zoom: f32) -> Self {
        Camera {
            mode,
            zoom: zoom.clamp(MIN_ZOOM, MAX_ZOOM),
        }
    }

    /// The whole field (as the renderers drew before the camera).
    pub fn field() -> Self {
        Camera::new(CameraMode::Field, DEFAULT_ZOOM)
    }

    /// Zooms in by `factor` (out when below 1), kept from [`MIN_ZOOM`] to [`MAX_ZOOM`].
    pub fn zoom_by(&mut self, factor: f32) {
        self.zoom = (self.zoom * factor).clamp(MIN_ZOOM, MAX_ZOOM);
    }

    /// Zooms by `factor` as [`Camera::zoom_by`] does, but no farther out than the zoom at
    /// which a `field`-sized world fills a `width × height` frame: zooming back in from
    /// the whole field then starts at once.
    pub fn zoom_within(&mut self, factor: f32, field: Vec2, (width, height): (u32, u32)) {
        let unit = height.max(1) as f32 / camera::REFERENCE_HEIGHT;
        let whole = camera::fit_scale(field, width.max(1), height.max(1)) / unit;
        self.zoom_by(factor);
        self.zoom = self.zoom.max(whole.min(MAX_ZOOM));
    }

    /// Switches between following the ship and the whole field.
    pub fn toggle_overview(&mut self) {
        self.mode = match self.mode {
            CameraMode::Follow => CameraMode::Field,
            CameraMode::Field => CameraMode::Follow,
        };
    }

    /// Whether frames show the radar: in follow mode.
    pub fn radar(&self) -> bool {
        self.mode == CameraMode::Follow
    }

    /// What the device is asked for a `width × height` frame of a `field`-sized world whose
    /// ship is in slot `ship` (`render::NO_SHIP` for none), `dt` seconds after the previous
    /// frame (0 snaps the view to the ship), over `background`.
    pub fn lens(
        &self,
        field: Vec2,
        (width, height): (u32, u32),
        ship: u32,
        dt: f32,
        background: u32,
    ) -> Lens {
        Lens {
            field,
            zoom: self.zoom,
            dt,
            width,
            height,
            background,
            mode: match self.mode {
                CameraMode::Follow => camera::FOLLOW,
                CameraMode::Field => camera::FIELD,
            },
            radar: u32::from(self.radar()),
            ship,
        }
    }
}

/// The view the device shows for `lens` when the ship is at `ship` (`None`: no ship, or a
/// dead one), advancing `state` as the device advances its own: the host's copy of the
/// camera kernel's result, bit for bit.
pub fn view(lens: &Lens, ship: Option<Vec2>, state: &mut CameraState) -> Framing {
    let (next, view) = camera::advance(lens, ship, *state);
    *state = next;
    view
}
