//! Skeleton pictures: each moment seen from the side (looking along −X: Z to the right, Y
//! up) and from the front (looking along −Z: X to the right, Y up), simulated bones in
//! orange, other bones grey, colliders green. A contact sheet puts several moments in one
//! image; animation frames show one moment each, for a GIF.

use crate::canvas::{Canvas, Rgb};
use crate::figure::{Figure, Outline};
use glam::Vec3;

const BG: Rgb = [250, 250, 248];
const FRAME: Rgb = [215, 215, 210];
const BONE: Rgb = [90, 90, 96];
const SIMULATED: Rgb = [235, 110, 30];
const COLLIDER: Rgb = [60, 160, 80];
const LIMIT: Rgb = [200, 160, 20];
const INK: Rgb = [40, 40, 40];

/// A direction the skeleton is seen from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum View {
    /// From +X: the picture's right is +Z, up is +Y.
    Side,
    /// From +Z: the picture's right is +X, up is +Y.
    Front,
}

impl View {
    /// The point on the picture plane (right, up), world units.
    pub fn project(self, p: Vec3) -> (f32, f32) {
        match self {
            View::Side => (p.z, p.y),
            View::Front => (p.x, p.y),
        }
    }

    fn label(self) -> &'static str {
        match self {
            View::Side => "SIDE",
            View::Front => "FRONT",
        }
    }
}

/// The world-to-pixel map of one view, the same for every moment so motion shows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Framing {
    lo: (f32, f32),
    hi: (f32, f32),
}

impl Framing {
    /// Bounds of every bone and collider of `figures` in `view` (a unit box if empty).
    pub fn fit(figures: &[Figure], view: View) -> Framing {
        let mut lo = (f32::MAX, f32::MAX);
        let mut hi = (f32::MIN, f32::MIN);
        let mut add = |p: Vec3, r: f32| {
            if !p.is_finite() {
                return;
            }
            let (x, y) = view.project(p);
            lo = (lo.0.min(x - r), lo.1.min(y - r));
            hi = (hi.0.max(x + r), hi.1.max(y + r));
        };
        for f in figures {
            for b in &f.bones {
                add(b.from, 0.0);
                add(b.to, 0.0);
            }
            for c in &f.colliders {
                for (p, r) in c.extent() {
                    add(p, r);
                }
            }
        }
        if lo.0 > hi.0 {
            return Framing {
                lo: (-0.5, -0.5),
                hi: (0.5, 0.5),
            };
        }
        Framing { lo, hi }
    }

    /// Scale and offset placing the bounds centred in a `w × h` box with a margin.
    fn map(&self, x: f32, y: f32, w: f32, h: f32) -> impl Fn((f32, f32)) -> (f32, f32) {
        let span = (
            (self.hi.0 - self.lo.0).max(1e-6),
            (self.hi.1 - self.lo.1).max(1e-6),
        );
        let s = (0.88 * w / span.0).min(0.88 * h / span.1);
        let c = (0.5 * (self.lo.0 + self.hi.0), 0.5 * (self.lo.1 + self.hi.1));
        let (ox, oy) = (x + 0.5 * w, y + 0.5 * h);
        move |(px, py)| (ox + (px - c.0) * s, oy - (py - c.1) * s)
    }

    fn scale(&self, w: f32, h: f32) -> f32 {
        let span = (
            (self.hi.0 - self.lo.0).max(1e-6),
            (self.hi.1 - self.lo.1).max(1e-6),
        );
        (0.88 * w / span.0).min(0.88 * h / span.1)
    }
}

/// Draws `figure` seen from `view` into the box (`x`, `y`, `w`, `h`) of `canvas`.
pub fn draw_view(
    canvas: &mut Canvas,
    figure: &Figure,
    view: View,
    framing: &Framing,
    (x, y, w, h): (f32, f32, f32, f32),
) {
    let to = framing.map(x, y, w, h);
    let s = framing.scale(w, h);
    let pt = |p: Vec3| to(view.project(p));
    for l in &figure.limits {
        // The boundary, and a few lines from the joint to it.
        for w in l.rim.windows(2) {
            canvas.line(pt(w[0]), pt(w[1]), 1.0, LIMIT);
        }
        for p in l.rim.iter().step_by(6) {
            canvas.line(pt(l.joint), pt(*p), 1.0, LIMIT);
        }
    }
    for c in &figure.colliders {
        match *c {
            Outline::Sphere { center, radius } => {
                let (cx, cy) = pt(center);
                canvas.circle(cx, cy, radius * s, COLLIDER);
            }
            Outline::Capsule { a, b, radius } => {
                capsule(canvas, pt(a), pt(b), radius * s, radius * s);
            }
            Outline::TaperedCapsule {
                a,
                b,
                radius_a,
                radius_b,
            } => {
                capsule(canvas, pt(a), pt(b), radius_a * s, radius_b * s);
            }
            Outline::Box { corners } => {
                for i in 0..8usize {
                    for bit in [1usize, 2, 4] {
                        if i & bit == 0 {
                            canvas.line(pt(corners[i]), pt(corners[i | bit]), 1.2, COLLIDER);
                        }
                    }
                }
            }
            Outline::Plane { point, normal } => {
                // The plane's trace: the direction in the picture plane normal to the
                // projected normal, a third of the picture long, with a tick toward the
                // kept side.
                let (nx, ny) = view.project(normal);
                let len = (nx * nx + ny * ny).sqrt();
                let (cx, cy) = pt(point);
                let half = 0.3 * w.min(h);
                if len > 1e-3 {
                    let (tx, ty) = (-ny / len, nx / len);
                    canvas.line(
                        (cx - tx * half, cy + ty * half),
                        (cx + tx * half, cy - ty * half),
                        1.5,
                        COLLIDER,
                    );
                    canvas.line(
                        (cx, cy),
                        (cx + nx / len * 10.0, cy - ny / len * 10.0),
                        1.5,
                        COLLIDER,
                    );
                } else {
                    canvas.rect(
                        (x + 4.0) as usize,
                        (y + 4.0) as usize,
                        (x + w - 4.0) as usize,
                        (y + 5.0) as usize,
                        COLLIDER,
                    );
                }
            }
        }
    }
    for pass in [false, true] {
        for b in figure.bones.iter().filter(|b| b.simulated == pass) {
            let (col, width) = if b.simulated {
                (SIMULATED, 3.0)
            } else {
                (BONE, 2.0)
            };
            let (a, e) = (pt(b.from), pt(b.to));
            canvas.line(a, e, width, col);
            canvas.dot(e.0, e.1, width * 0.9, col);
        }
    }
}

/// A capsule's outline between the projected ends `pa` and `pb`: each end's circle (radii
/// `ra`, `rb` in pixels) and the two lines touching both (straight across for equal radii;
/// for a taper, the lines through the circles' points normal to the axis, which is what
/// the rule's radius does along it).
fn capsule(canvas: &mut Canvas, pa: (f32, f32), pb: (f32, f32), ra: f32, rb: f32) {
    canvas.circle(pa.0, pa.1, ra, COLLIDER);
    canvas.circle(pb.0, pb.1, rb, COLLIDER);
    let d = (pb.0 - pa.0, pb.1 - pa.1);
    let len = (d.0 * d.0 + d.1 * d.1).sqrt();
    if len > 1e-3 {
        let n = (-d.1 / len, d.0 / len);
        for k in [-1.0, 1.0] {
            canvas.line(
                (pa.0 + k * n.0 * ra, pa.1 + k * n.1 * ra),
                (pb.0 + k * n.0 * rb, pb.1 + k * n.1 * rb),
                1.2,
                COLLIDER,
            );
        }
    }
}

fn time_label(t: f32) -> String {
    format!("T = {t:.2} S")
}

/// Several moments in one image: one column per figure, the side view above the front
/// view, the time over each column and `title` on top.
pub fn contact_sheet(figures: &[Figure], title: &str) -> Canvas {
    let (cw, vh, head) = (200usize, 240usize, 44usize);
    let cols = figures.len().max(1);
    let mut c = Canvas::new(cw * cols, head + 2 * vh, BG);
    c.text(8, 8, title, 2, INK);
    let side = Framing::fit(figures, View::Side);
    let front = Framing::fit(figures, View::Front);
    for (i, f) in figures.iter().enumerate() {
        let x = (i * cw) as f32;
        if i > 0 {
            c.rect(i * cw, head, i * cw + 1, head + 2 * vh, FRAME);
        }
        c.text(
            (i * cw + 6) as i64,
            (head - 12) as i64,
            &time_label(f.time),
            1,
            INK,
        );
        for (k, (view, framing)) in [(View::Side, &side), (View::Front, &front)]
            .iter()
            .enumerate()
        {
            let y = head + k * vh;
            c.rect(i * cw, y, (i + 1) * cw, y + 1, FRAME);
            if i == 0 {
                c.text(4, (y + 4) as i64, view.label(), 1, INK);
            }
            draw_view(
                &mut c,
                f,
                *view,
                framing,
                (x, y as f32 + 10.0, cw as f32, vh as f32 - 10.0),
            );
        }
    }
    c
}

/// One image per figure: side and front views next to each other, the time and `title`
/// on top, all framed alike.
pub fn animation_frames(figures: &[Figure], title: &str) -> Vec<Canvas> {
    let (vw, vh, head) = (280usize, 300usize, 28usize);
    let side = Framing::fit(figures, View::Side);
    let front = Framing::fit(figures, View::Front);
    figures
        .iter()
        .map(|f| {
            let mut c = Canvas::new(2 * vw, head + vh, BG);
            c.text(8, 8, title, 1, INK);
            let label = time_label(f.time);
            c.text(
                (2 * vw - Canvas::text_width(&label, 1) - 8) as i64,
                8,
                &label,
                1,
                INK,
            );
            c.rect(vw, head, vw + 1, head + vh, FRAME);
            c.rect(0, head, 2 * vw, head + 1, FRAME);
            for (k, (view, framing)) in [(View::Side, &side), (View::Front, &front)]
                .iter()
                .enumerate()
            {
                c.text((k * vw + 6) as i64, (head + 6) as i64, view.label(), 1, INK);
                draw_view(
                    &mut c,
                    f,
                    *view,
                    framing,
                    (
                        (k * vw) as f32,
                        head as f32 + 10.0,
                        vw as f32,
                        vh as f32 - 10.0,
                    ),
                );
            }
            c
        })
        .collect()
}

/// The colour simulated bones are drawn in (for tests and legends).
pub const SIMULATED_COLOR: Rgb = SIMULATED;
/// The colour of other bones.
pub const BONE_COLOR: Rgb = BONE;
/// The colour of colliders.
pub const COLLIDER_COLOR: Rgb = COLLIDER;
/// The colour of VRM swing limits.
pub const LIMIT_COLOR: Rgb = LIMIT;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::figure::Bone;

    #[test]
    fn a_bone_lands_where_the_framing_says() {
        // A 1 m vertical bone framed in a 100 × 100 box: 88 px per metre (the 6 % margin
        // on the tighter side), centred: from (50, 94) up to (50, 6).
        let fig = Figure {
            bones: vec![Bone {
                from: Vec3::ZERO,
                to: Vec3::Y,
                simulated: true,
            }],
            colliders: vec![Outline::Sphere {
                center: Vec3::new(0.0, 0.5, 0.0),
                radius: 0.25,
            }],
            limits: vec![],
            time: 0.0,
        };
        let framing = Framing::fit(std::slice::from_ref(&fig), View::Front);
        let mut c = Canvas::new(100, 100, BG);
        draw_view(
            &mut c,
            &fig,
            View::Front,
            &framing,
            (0.0, 0.0, 100.0, 100.0),
        );
        for y in [10, 50, 90] {
            assert_eq!(c.get(50, y), SIMULATED, "y {y}");
        }
        assert_eq!(c.get(50, 1), BG);
        assert_eq!(c.get(50, 99), BG);
        // The collider: a circle of 0.25 m = 22 px around (50, 50).
        assert_eq!(c.get(72, 50), COLLIDER);
        assert_eq!(c.get(28, 50), COLLIDER);
        assert_eq!(c.get(61, 50), BG);
        // Side view of the same figure: the bone is still vertical through the centre.
        let side = Framing::fit(std::slice::from_ref(&fig), View::Side);
        let mut s = Canvas::new(100, 100, BG);
        draw_view(&mut s, &fig, View::Side, &side, (0.0, 0.0, 100.0, 100.0));
        assert_eq!(s.get(50, 50), SIMULATED);
    }
}
