//! Software pictures for Tassel (no GPU): an RGB [`Canvas`] with a 5×7 font, PNG and GIF
//! output, skeleton views ([`Figure`] from a [`tassel::CharacterSim`], side and front
//! [`contact_sheet`]s and [`animation_frames`]), line [`Chart`]s, and the demo's
//! [`draw_strip`] (titled side views of the character in its level over a chart).

mod canvas;
mod chart;
mod error;
mod figure;
mod font;
mod gif;
mod sheet;
mod strip;

pub use canvas::{Canvas, Rgb};
pub use chart::{ticks, Band, Chart, ChartSeries, PALETTE};
pub use error::RenderError;
pub use figure::{outline, Bone, Figure, LimitOutline, Outline};
pub use gif::encode_gif;
pub use sheet::{
    animation_frames, contact_sheet, draw_view, Framing, View, BONE_COLOR, COLLIDER_COLOR,
    LIMIT_COLOR, SIMULATED_COLOR,
};
pub use strip::{
    draw_strip, side_outlines, Panel, CHART_HEIGHT, MAX_SCALE, PANEL_WIDTH, TITLE_HEIGHT,
};
