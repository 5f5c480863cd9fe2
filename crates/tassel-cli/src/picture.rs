//! A software-drawn PNG of the demo: side views of the skeleton at several moments with
//! the chains highlighted and colliders outlined, and a strip of tip deviations over time.

use glam::Vec3;

/// An RGB canvas.
pub struct Canvas {
    w: usize,
    h: usize,
    px: Vec<u8>,
}

impl Canvas {
    pub fn new(w: usize, h: usize, bg: [u8; 3]) -> Self {
        let mut px = Vec::with_capacity(w * h * 3);
        for _ in 0..w * h {
            px.extend(bg);
        }
        Self { w, h, px }
    }

    pub fn dot(&mut self, x: f32, y: f32, r: f32, c: [u8; 3]) {
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

    pub fn line(&mut self, a: (f32, f32), b: (f32, f32), width: f32, c: [u8; 3]) {
        let len = ((b.0 - a.0).powi(2) + (b.1 - a.1).powi(2)).sqrt();
        let n = (len * 2.0).ceil().max(1.0) as usize;
        for k in 0..=n {
            let t = k as f32 / n as f32;
            self.dot(a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t, width * 0.5, c);
        }
    }

    pub fn circle(&mut self, x: f32, y: f32, r: f32, c: [u8; 3]) {
        let n = (r * 7.0).max(16.0) as usize;
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

    pub fn rect(&mut self, x0: usize, y0: usize, x1: usize, y1: usize, c: [u8; 3]) {
        for y in y0..y1.min(self.h) {
            for x in x0..x1.min(self.w) {
                let i = (y * self.w + x) * 3;
                self.px[i..i + 3].copy_from_slice(&c);
            }
        }
    }

    pub fn png(&self) -> Result<Vec<u8>, String> {
        let mut out = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut out, self.w as u32, self.h as u32);
            enc.set_color(png::ColorType::Rgb);
            enc.set_depth(png::BitDepth::Eight);
            let mut w = enc.write_header().map_err(|e| e.to_string())?;
            w.write_image_data(&self.px).map_err(|e| e.to_string())?;
        }
        Ok(out)
    }
}

/// What one panel shows: positions in the character's heading frame (x right = forward).
pub struct Panel {
    /// (parent, child, colour, width) segments in the side plane, metres.
    pub segments: Vec<(Vec3, Vec3, [u8; 3], f32)>,
    /// Collider outlines: centre and radius, metres.
    pub circles: Vec<(Vec3, f32)>,
}

/// One series of the bottom strip.
pub struct Series {
    pub color: [u8; 3],
    pub values: Vec<f32>,
}

pub fn draw(
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
