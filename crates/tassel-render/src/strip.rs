//! The demo's picture: side views of the skeleton at several moments (chains highlighted,
//! colliders outlined) over a strip of tip deviations with phase bands.

use crate::canvas::{Canvas, Rgb};
use glam::Vec3;

/// What one panel shows: positions in the character's heading frame (x right = forward).
pub struct Panel {
    /// (parent, child, colour, width) segments in the side plane, metres.
    pub segments: Vec<(Vec3, Vec3, [u8; 3], f32)>,
    /// Collider outlines: centre and radius, metres.
    pub circles: Vec<(Vec3, f32)>,
}

/// One series of the bottom strip.
pub struct Series {
    /// Line colour.
    pub color: Rgb,
    /// One value per frame, metres.
    pub values: Vec<f32>,
}

/// Draws `panels` side by side (220 × 470 pixels each, 210 pixels per metre, the ground
/// line 30 pixels from the bottom) over a 200-pixel strip: `bands` (start time, colour)
/// behind `series` scaled to their largest value, across `duration` seconds.
pub fn draw_strip(
    panels: &[Panel],
    bands: &[(f32, [u8; 3])],
    series: &[Series],
    duration: f32,
) -> Canvas {
    let (pw, ph, strip) = (220usize, 470usize, 200usize);
    let w = pw * panels.len();
    let mut c = Canvas::new(w, ph + strip, [250, 250, 248]);
    let scale = 210.0;
    for (i, p) in panels.iter().enumerate() {
        let (ox, base) = ((i * pw) as f32 + pw as f32 * 0.5, ph as f32 - 30.0);
        c.rect(i * pw, ph - 30, (i + 1) * pw, ph - 29, [180, 180, 180]);
        if i > 0 {
            c.rect(i * pw, 0, i * pw + 1, ph, [220, 220, 220]);
        }
        let to = |v: Vec3| (ox + v.z * scale, base - v.y * scale);
        for &(centre, r) in &p.circles {
            let (x, y) = to(centre);
            c.circle(x, y, r * scale, [150, 200, 150]);
        }
        for &(a, b, col, width) in &p.segments {
            c.line(to(a), to(b), width, col);
        }
    }
    // Strip: phase bands, then deviation curves.
    let top = ph + 10;
    let height = (strip - 20) as f32;
    for (k, &(start, col)) in bands.iter().enumerate() {
        let end = bands.get(k + 1).map(|b| b.0).unwrap_or(duration);
        let x0 = (start / duration * w as f32) as usize;
        let x1 = (end / duration * w as f32) as usize;
        c.rect(x0, top, x1, top + height as usize, col);
    }
    let max = series
        .iter()
        .flat_map(|s| s.values.iter().cloned())
        .fold(1e-6f32, f32::max);
    for s in series {
        let n = s.values.len().max(2);
        for k in 1..s.values.len() {
            let x = |i: usize| i as f32 / (n - 1) as f32 * (w - 1) as f32;
            let y = |v: f32| top as f32 + height - v / max * height;
            c.line(
                (x(k - 1), y(s.values[k - 1])),
                (x(k), y(s.values[k])),
                1.6,
                s.color,
            );
        }
    }
    c
}
