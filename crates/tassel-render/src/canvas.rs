//! An RGB canvas with the few primitives the pictures need: filled discs, thick lines,
//! circle outlines, rectangles and 5×7 text; PNG output.

use crate::error::RenderError;
use crate::font::{glyph, GLYPH};

/// An RGB colour.
pub type Rgb = [u8; 3];

/// An RGB image, row-major, top row first.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Canvas {
    w: usize,
    h: usize,
    px: Vec<u8>,
}

impl Canvas {
    /// A `w × h` canvas filled with `bg`.
    pub fn new(w: usize, h: usize, bg: Rgb) -> Self {
        let mut px = Vec::with_capacity(w * h * 3);
        for _ in 0..w * h {
            px.extend(bg);
        }
        Self { w, h, px }
    }

    /// Width in pixels.
    pub fn width(&self) -> usize {
        self.w
    }

    /// Height in pixels.
    pub fn height(&self) -> usize {
        self.h
    }

    /// The RGB bytes, row-major.
    pub fn pixels(&self) -> &[u8] {
        &self.px
    }

    /// The colour at (`x`, `y`).
    pub fn get(&self, x: usize, y: usize) -> Rgb {
        let i = (y * self.w + x) * 3;
        [self.px[i], self.px[i + 1], self.px[i + 2]]
    }

    /// Sets one pixel (ignored outside the canvas).
    pub fn set(&mut self, x: i64, y: i64, c: Rgb) {
        if x >= 0 && y >= 0 && (x as usize) < self.w && (y as usize) < self.h {
            let i = (y as usize * self.w + x as usize) * 3;
            self.px[i..i + 3].copy_from_slice(&c);
        }
    }

    /// A filled disc of radius `r` at (`x`, `y`).
    pub fn dot(&mut self, x: f32, y: f32, r: f32, c: Rgb) {
        if !(x.is_finite() && y.is_finite() && r.is_finite()) {
            return;
        }
        let (x0, x1) = ((x - r).floor() as i64, (x + r).ceil() as i64);
        let (y0, y1) = ((y - r).floor() as i64, (y + r).ceil() as i64);
        for yy in y0.max(0)..=y1.min(self.h as i64 - 1) {
            for xx in x0.max(0)..=x1.min(self.w as i64 - 1) {
                let (dx, dy) = (xx as f32 - x, yy as f32 - y);
                if dx * dx + dy * dy <= r * r {
                    let i = (yy as usize * self.w + xx as usize) * 3;
                    self.px[i..i + 3].copy_from_slice(&c);
                }
            }
        }
    }

    /// A line `width` pixels wide from `a` to `b` (round ends).
    pub fn line(&mut self, a: (f32, f32), b: (f32, f32), width: f32, c: Rgb) {
        let len = ((b.0 - a.0).powi(2) + (b.1 - a.1).powi(2)).sqrt();
        if !len.is_finite() {
            return;
        }
        // Clip absurdly long lines (a point far off the view) to a sane number of dots.
        let n = (len * 2.0).ceil().clamp(1.0, 20_000.0) as usize;
        for k in 0..=n {
            let t = k as f32 / n as f32;
            self.dot(a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t, width * 0.5, c);
        }
    }

    /// A circle outline of radius `r` at (`x`, `y`).
    pub fn circle(&mut self, x: f32, y: f32, r: f32, c: Rgb) {
        let n = (r * 7.0).clamp(16.0, 2000.0) as usize;
        for k in 0..n {
            let (a0, a1) = (
                k as f32 / n as f32 * std::f32::consts::TAU,
                (k + 1) as f32 / n as f32 * std::f32::consts::TAU,
            );
            self.line(
                (x + r * a0.cos(), y + r * a0.sin()),
                (x + r * a1.cos(), y + r * a1.sin()),
                1.2,
                c,
            );
        }
    }

    /// A filled polygon (any simple polygon, vertices in order; even–odd rule, pixel
    /// centres inside are set).
    pub fn polygon(&mut self, points: &[(f32, f32)], c: Rgb) {
        if points.len() < 3 || points.iter().any(|p| !(p.0.is_finite() && p.1.is_finite())) {
            return;
        }
        let (lo, hi) = points.iter().fold((f32::MAX, f32::MIN), |(lo, hi), p| {
            (lo.min(p.1), hi.max(p.1))
        });
        let y0 = (lo.floor() as i64).max(0);
        let y1 = (hi.ceil() as i64).min(self.h as i64 - 1);
        let mut xs: Vec<f32> = Vec::new();
        for y in y0..=y1 {
            let yc = y as f32 + 0.5;
            xs.clear();
            for k in 0..points.len() {
                let (a, b) = (points[k], points[(k + 1) % points.len()]);
                if (a.1 <= yc) != (b.1 <= yc) {
                    xs.push(a.0 + (yc - a.1) / (b.1 - a.1) * (b.0 - a.0));
                }
            }
            xs.sort_by(f32::total_cmp);
            for pair in xs.chunks_exact(2) {
                let x0 = ((pair[0] - 0.5).ceil() as i64).max(0);
                let x1 = ((pair[1] - 0.5).floor() as i64).min(self.w as i64 - 1);
                for x in x0..=x1 {
                    let i = (y as usize * self.w + x as usize) * 3;
                    self.px[i..i + 3].copy_from_slice(&c);
                }
            }
        }
    }

    /// Copies `other` with its top-left corner at (`x`, `y`) (clipped to this canvas).
    pub fn blit(&mut self, other: &Canvas, x: usize, y: usize) {
        for row in 0..other.h.min(self.h.saturating_sub(y)) {
            let n = other.w.min(self.w.saturating_sub(x));
            let src = row * other.w * 3;
            let dst = ((y + row) * self.w + x) * 3;
            self.px[dst..dst + n * 3].copy_from_slice(&other.px[src..src + n * 3]);
        }
    }

    /// A filled rectangle `[x0, x1) × [y0, y1)`.
    pub fn rect(&mut self, x0: usize, y0: usize, x1: usize, y1: usize, c: Rgb) {
        for y in y0..y1.min(self.h) {
            for x in x0..x1.min(self.w) {
                let i = (y * self.w + x) * 3;
                self.px[i..i + 3].copy_from_slice(&c);
            }
        }
    }

    /// Text with its top-left corner at (`x`, `y`), each font pixel `scale` pixels.
    pub fn text(&mut self, x: i64, y: i64, s: &str, scale: usize, c: Rgb) {
        let advance = (GLYPH.0 + 1) * scale;
        for_each_font_pixel(s, scale, |k, col, row| {
            self.set(x + (k * advance + col) as i64, y + row as i64, c)
        });
    }

    /// Width of `s` drawn by [`Canvas::text`] at `scale`.
    pub fn text_width(s: &str, scale: usize) -> usize {
        let n = s.chars().count();
        if n == 0 {
            0
        } else {
            (n * (GLYPH.0 + 1) - 1) * scale
        }
    }

    /// Text drawn bottom to top, rotated a quarter turn counter-clockwise (a y-axis label),
    /// its bottom-left corner at (`x`, `y`).
    pub fn text_up(&mut self, x: i64, y: i64, s: &str, scale: usize, c: Rgb) {
        let advance = (GLYPH.0 + 1) * scale;
        for_each_font_pixel(s, scale, |k, col, row| {
            self.set(x + row as i64, y - (k * advance + col) as i64, c)
        });
    }

    /// The canvas as PNG bytes.
    pub fn png(&self) -> Result<Vec<u8>, RenderError> {
        let bad = |e: png::EncodingError| RenderError::Png(e.to_string());
        let mut out = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut out, self.w as u32, self.h as u32);
            enc.set_color(png::ColorType::Rgb);
            enc.set_depth(png::BitDepth::Eight);
            let mut w = enc.write_header().map_err(bad)?;
            w.write_image_data(&self.px).map_err(bad)?;
        }
        Ok(out)
    }
}

/// Calls `f(character index, column, row)` for every lit pixel of `s` at `scale` (column
/// and row in pixels within the character's cell).
fn for_each_font_pixel(s: &str, scale: usize, mut f: impl FnMut(usize, usize, usize)) {
    for (k, ch) in s.chars().enumerate() {
        let Some(rows) = glyph(ch) else { continue };
        for (row, bits) in rows.iter().enumerate() {
            for col in 0..GLYPH.0 {
                if bits & (1 << (GLYPH.0 - 1 - col)) != 0 {
                    for dy in 0..scale {
                        for dx in 0..scale {
                            f(k, col * scale + dx, row * scale + dy);
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_sets_the_glyph_pixels() {
        let mut c = Canvas::new(20, 10, [0, 0, 0]);
        c.text(1, 1, "1", 1, [255, 255, 255]);
        // '1' is 00100 / 01100 / ...: its top row lights only column 2.
        assert_eq!(c.get(3, 1), [255, 255, 255]);
        assert_eq!(c.get(1, 1), [0, 0, 0]);
        // Bottom row 01110: columns 1..=3.
        assert_eq!(c.get(2, 7), [255, 255, 255]);
        assert_eq!(c.get(4, 7), [255, 255, 255]);
        assert_eq!(c.get(5, 7), [0, 0, 0]);
        assert_eq!(Canvas::text_width("12", 2), 22);
    }

    #[test]
    fn polygons_fill_their_inside_only() {
        let mut c = Canvas::new(10, 10, [0, 0, 0]);
        // A right triangle with legs along the top and left edges, 8 pixels long.
        c.polygon(&[(1.0, 1.0), (9.0, 1.0), (1.0, 9.0)], [5, 5, 5]);
        assert_eq!(c.get(2, 2), [5, 5, 5]);
        assert_eq!(c.get(1, 7), [5, 5, 5]);
        // Below the hypotenuse x + y = 10 (pixel centre 8.5 + 8.5 > 10).
        assert_eq!(c.get(8, 8), [0, 0, 0]);
        assert_eq!(c.get(0, 0), [0, 0, 0]);
        let mut big = Canvas::new(4, 3, [1, 1, 1]);
        big.blit(&c, 1, 1);
        assert_eq!(big.get(0, 0), [1, 1, 1]);
        assert_eq!(big.get(2, 2), c.get(1, 1));
    }

    #[test]
    fn lines_and_discs_stay_inside() {
        let mut c = Canvas::new(8, 8, [0, 0, 0]);
        c.line((-100.0, 4.0), (100.0, 4.0), 1.0, [9, 9, 9]);
        c.dot(f32::NAN, 1.0, 3.0, [1, 1, 1]);
        assert_eq!(c.get(0, 4), [9, 9, 9]);
        assert_eq!(c.get(7, 4), [9, 9, 9]);
        assert_eq!(c.get(0, 0), [0, 0, 0]);
    }
}
