//! Line charts: several series over a shared x axis, with ticks at 1-2-5 steps, labelled
//! axes, a title and a legend.

use crate::canvas::{Canvas, Rgb};

/// One line of a chart.
#[derive(Debug, Clone, PartialEq)]
pub struct ChartSeries {
    /// Legend text.
    pub name: String,
    /// Line colour.
    pub color: Rgb,
    /// (x, y) points in x order; non-finite points are skipped.
    pub points: Vec<(f32, f32)>,
}

/// A stretch of the x axis shaded behind the lines, with a label at its top.
#[derive(Debug, Clone, PartialEq)]
pub struct Band {
    /// Where it starts and ends on the x axis.
    pub range: (f32, f32),
    /// Its colour (light, behind the grid).
    pub color: Rgb,
    /// Written at the band's top left.
    pub label: String,
}

/// A chart to draw.
///
/// ```
/// use tassel_render::{Chart, ChartSeries, PALETTE};
///
/// let points = (0..=100).map(|i| i as f32 * 0.01).map(|t| (t, (6.28 * t).sin())).collect();
/// let chart = Chart {
///     title: "A SWING".into(),
///     x_label: "TIME (S)".into(),
///     y_label: "ANGLE (RAD)".into(),
///     series: vec![ChartSeries { name: "tip".into(), color: PALETTE[0], points }],
///     ..Chart::default()
/// };
/// let canvas = chart.draw(640, 360);
/// assert_eq!((canvas.width(), canvas.height()), (640, 360));
/// // The line is drawn in its colour.
/// let drawn = canvas.pixels().chunks(3).filter(|p| *p == PALETTE[0]).count();
/// assert!(drawn > 100, "{drawn} pixels of the line");
/// let png = canvas.png()?;
/// assert_eq!(&png[1..4], b"PNG");
/// # Ok::<(), tassel_render::RenderError>(())
/// ```
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Chart {
    /// Title over the plot.
    pub title: String,
    /// The x axis' label (with its unit).
    pub x_label: String,
    /// The y axis' label (with its unit).
    pub y_label: String,
    /// The lines.
    pub series: Vec<ChartSeries>,
    /// Shaded stretches of the x axis (e.g. the phases of a run), under everything else.
    pub bands: Vec<Band>,
}

/// Distinct line colours for up to eight series (then repeated).
pub const PALETTE: [Rgb; 8] = [
    [31, 119, 180],
    [230, 85, 13],
    [44, 160, 44],
    [214, 39, 40],
    [148, 103, 189],
    [140, 86, 75],
    [227, 119, 194],
    [100, 100, 100],
];

const BG: Rgb = [255, 255, 255];
const AXIS: Rgb = [60, 60, 60];
const GRID: Rgb = [228, 228, 228];

/// Tick positions covering `[lo, hi]`: the smallest step of 1, 2 or 5 × 10ⁿ that gives
/// at most 7 intervals.
pub fn ticks(lo: f32, hi: f32) -> Vec<f32> {
    if !(lo.is_finite() && hi.is_finite()) || hi <= lo {
        return vec![lo];
    }
    let raw = (hi - lo) / 6.0;
    let mag = 10f32.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| (hi - lo) / s <= 7.0)
        .unwrap_or(10.0 * mag);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last)
        .map(|k| (k as f64 * step as f64) as f32)
        .collect()
}

fn tick_text(v: f32, step: f32) -> String {
    let decimals = if step >= 1.0 {
        0
    } else {
        (-step.log10().floor()) as usize
    };
    let s = format!("{v:.decimals$}");
    if s.starts_with('-') && s[1..].chars().all(|c| c == '0' || c == '.') {
        s[1..].to_string()
    } else {
        s
    }
}

impl Chart {
    /// Draws the chart on a `w × h` canvas (at least 200 × 150).
    pub fn draw(&self, w: usize, h: usize) -> Canvas {
        let (w, h) = (w.max(200), h.max(150));
        let mut c = Canvas::new(w, h, BG);
        let (left, right, top, bottom) = (78usize, 20usize, 40usize, 52usize);
        let (pw, ph) = (w - left - right, h - top - bottom);
        c.text(left as i64, 12, &self.title, 2, AXIS);
        let pts = || {
            self.series
                .iter()
                .flat_map(|s| s.points.iter())
                .filter(|(x, y)| x.is_finite() && y.is_finite())
        };
        let (mut x0, mut x1, mut y0, mut y1) = (f32::MAX, f32::MIN, f32::MAX, f32::MIN);
        for &(x, y) in pts() {
            x0 = x0.min(x);
            x1 = x1.max(x);
            y0 = y0.min(y);
            y1 = y1.max(y);
        }
        if x0 > x1 {
            (x0, x1, y0, y1) = (0.0, 1.0, 0.0, 1.0);
        }
        if x1 - x0 < 1e-9 {
            x1 = x0 + 1.0;
        }
        // Include zero when the data is all on one side (displacements start there).
        if y0 > 0.0 {
            y0 = 0.0;
        }
        if y1 < 0.0 {
            y1 = 0.0;
        }
        if y1 - y0 < 1e-9 {
            y1 = y0 + 1.0;
        }
        let pad = 0.05 * (y1 - y0);
        y1 += pad;
        if y0 < 0.0 {
            y0 -= pad;
        }
        let px = |x: f32| left as f32 + (x - x0) / (x1 - x0) * pw as f32;
        let py = |y: f32| (top + ph) as f32 - (y - y0) / (y1 - y0) * ph as f32;
        // Bands, then grid and ticks.
        for b in &self.bands {
            let (a, z) = (b.range.0.max(x0), b.range.1.min(x1));
            if z > a {
                let (xa, xz) = (px(a).round() as usize, px(z).round() as usize);
                c.rect(xa, top, xz, top + ph, b.color);
                c.text(xa as i64 + 3, top as i64 + 3, &b.label, 1, [110, 110, 110]);
            }
        }
        let xt = ticks(x0, x1);
        let yt = ticks(y0, y1);
        let xstep = if xt.len() > 1 { xt[1] - xt[0] } else { 1.0 };
        let ystep = if yt.len() > 1 { yt[1] - yt[0] } else { 1.0 };
        for &t in &xt {
            let x = px(t).round() as usize;
            c.rect(x, top, x + 1, top + ph, GRID);
            c.rect(x, top + ph, x + 1, top + ph + 5, AXIS);
            let s = tick_text(t, xstep);
            c.text(
                x as i64 - Canvas::text_width(&s, 1) as i64 / 2,
                (top + ph + 9) as i64,
                &s,
                1,
                AXIS,
            );
        }
        for &t in &yt {
            let y = py(t).round() as usize;
            c.rect(left, y, left + pw, y + 1, GRID);
            c.rect(left - 5, y, left, y + 1, AXIS);
            let s = tick_text(t, ystep);
            c.text(
                (left - 8 - Canvas::text_width(&s, 1)) as i64,
                y as i64 - 3,
                &s,
                1,
                AXIS,
            );
        }
        // Axes.
        c.rect(left, top, left + 1, top + ph + 1, AXIS);
        c.rect(left, top + ph, left + pw, top + ph + 1, AXIS);
        if y0 < 0.0 && y1 > 0.0 {
            let y = py(0.0).round() as usize;
            c.rect(left, y, left + pw, y + 1, [150, 150, 150]);
        }
        // Axis labels.
        let xl = Canvas::text_width(&self.x_label, 1);
        c.text(
            (left + pw / 2) as i64 - xl as i64 / 2,
            (h - 16) as i64,
            &self.x_label,
            1,
            AXIS,
        );
        let yl = Canvas::text_width(&self.y_label, 1) as i64;
        c.text_up(10, (top + ph / 2) as i64 + yl / 2, &self.y_label, 1, AXIS);
        // Lines.
        for s in &self.series {
            let mut prev: Option<(f32, f32)> = None;
            for &(x, y) in &s.points {
                if !(x.is_finite() && y.is_finite()) {
                    prev = None;
                    continue;
                }
                let p = (px(x), py(y));
                if let Some(q) = prev {
                    c.line(q, p, 1.8, s.color);
                }
                prev = Some(p);
            }
        }
        // Legend, top right inside the plot.
        let lw = self
            .series
            .iter()
            .map(|s| Canvas::text_width(&s.name, 1))
            .max()
            .unwrap_or(0)
            + 40;
        let lh = 14 * self.series.len() + 8;
        if !self.series.is_empty() {
            let (lx, ly) = (left + pw - lw - 8, top + 8);
            c.rect(lx, ly, lx + lw, ly + lh, [248, 248, 248]);
            c.rect(lx, ly, lx + lw, ly + 1, GRID);
            c.rect(lx, ly + lh, lx + lw, ly + lh + 1, GRID);
            for (k, s) in self.series.iter().enumerate() {
                let y = ly + 8 + 14 * k;
                c.rect(lx + 6, y + 2, lx + 26, y + 5, s.color);
                c.text((lx + 32) as i64, y as i64, &s.name, 1, AXIS);
            }
        }
        c
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_round_and_cover() {
        assert_eq!(ticks(0.0, 1.0), vec![0.0, 0.2, 0.4, 0.6, 0.8, 1.0]);
        assert_eq!(ticks(0.0, 10.0), vec![0.0, 2.0, 4.0, 6.0, 8.0, 10.0]);
        let t = ticks(-0.013, 0.042);
        assert!(t.len() >= 4 && t.len() <= 12, "{t:?}");
        assert!(
            t.windows(2).all(|w| (w[1] - w[0] - 0.01).abs() < 1e-6),
            "{t:?}"
        );
        assert_eq!(tick_text(0.1 + 0.2, 0.1), "0.3");
        assert_eq!(tick_text(-0.0, 0.1), "0.0");
    }

    #[test]
    fn series_are_drawn_in_their_colour_where_their_points_are() {
        let chart = Chart {
            title: "T".into(),
            x_label: "TIME (S)".into(),
            y_label: "M".into(),
            series: vec![ChartSeries {
                name: "A".into(),
                color: [200, 0, 0],
                points: vec![(0.0, 0.5), (1.0, 0.5)],
            }],
            bands: vec![],
        };
        let c = chart.draw(400, 300);
        // y range [0, 0.5 + 5 %]: 0.5 sits at 1/1.05 of the plot height above the axis.
        let (top, ph) = (40.0f32, 300.0f32 - 40.0 - 52.0);
        let y = (top + ph - 0.5 / 0.525 * ph).round() as usize;
        let x = 78 + (400 - 78 - 20) / 2;
        let hit = (y - 2..=y + 2).any(|yy| c.get(x, yy) == [200, 0, 0]);
        assert!(hit, "no red near ({x}, {y})");
    }
}
