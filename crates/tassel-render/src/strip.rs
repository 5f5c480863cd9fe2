//! The demo's picture: titled side views of the character in its level at several
//! moments (chains highlighted, colliders outlined, the level's nearby colliders drawn
//! cut-away behind it) over a chart of what the chains did.

use crate::canvas::{Canvas, Rgb};
use crate::chart::Chart;
use glam::Vec3;
use tassel::controller::{LevelCollider, LevelShape};

/// Width of one panel, pixels.
pub const PANEL_WIDTH: usize = 240;
/// Height of a panel's title (two lines of 2× text), pixels.
pub const TITLE_HEIGHT: usize = 44;
/// Height of the chart under the panels, pixels.
pub const CHART_HEIGHT: usize = 300;
/// The most pixels per metre of the side views (fewer if the content needs it to fit).
pub const MAX_SCALE: f32 = 110.0;

/// What one panel shows, in world space seen from the side: world z to the right,
/// world y up (the view looks along +x).
#[derive(Debug, Clone, Default)]
pub struct Panel {
    /// Title lines (e.g. the time and the phase), drawn at the top.
    pub title: Vec<String>,
    /// The world z the view is centred on, metres.
    pub centre_z: f32,
    /// (parent, child, colour, width in pixels) segments, metres.
    pub segments: Vec<(Vec3, Vec3, Rgb, f32)>,
    /// Collider outlines: centre and radius, metres.
    pub circles: Vec<(Vec3, f32)>,
    /// Level silhouettes: outline points (metres, any order: their convex hull in the
    /// side view is filled) and fill colour, drawn first.
    pub level: Vec<(Vec<Vec3>, Rgb)>,
}

/// The side-view silhouettes of a level collider (world space, scale 1): one outline for
/// a convex shape, one per triangle for a triangle mesh.
pub fn side_outlines(c: &LevelCollider) -> Vec<Vec<Vec3>> {
    let place = |p: Vec3| c.position + c.rotation * p;
    // A circle in the side (z–y) plane, for round shapes (their silhouette from any side).
    let ring = |centre: Vec3, r: f32| -> Vec<Vec3> {
        (0..24)
            .map(|k| {
                let a = k as f32 / 24.0 * std::f32::consts::TAU;
                centre + Vec3::new(0.0, a.sin(), a.cos()) * r
            })
            .collect()
    };
    match &c.shape {
        LevelShape::Box { half_extents: h } => {
            let mut pts = Vec::with_capacity(8);
            for k in 0..8 {
                let s = |b: usize| if k & b == 0 { -1.0 } else { 1.0 };
                pts.push(place(Vec3::new(s(1) * h.x, s(2) * h.y, s(4) * h.z)));
            }
            vec![pts]
        }
        LevelShape::Ramp {
            width,
            length,
            height,
        } => {
            let w = 0.5 * width;
            let mut pts = Vec::with_capacity(6);
            for x in [-w, w] {
                for p in [
                    Vec3::new(x, 0.0, 0.0),
                    Vec3::new(x, 0.0, *length),
                    Vec3::new(x, *height, *length),
                ] {
                    pts.push(place(p));
                }
            }
            vec![pts]
        }
        LevelShape::Sphere { radius } => vec![ring(c.position, *radius)],
        LevelShape::Capsule {
            half_height,
            radius,
        } => {
            let axis = c.rotation * Vec3::Y * *half_height;
            let mut pts = ring(c.position - axis, *radius);
            pts.extend(ring(c.position + axis, *radius));
            vec![pts]
        }
        LevelShape::TriMesh { vertices, indices } => indices
            .iter()
            .filter_map(|t| {
                t.iter()
                    .map(|&i| vertices.get(i as usize).map(|&v| place(v)))
                    .collect()
            })
            .collect(),
    }
}

/// Convex hull of 2-D points, counter-clockwise in a y-up frame (Andrew's monotone chain).
fn hull(mut p: Vec<(f32, f32)>) -> Vec<(f32, f32)> {
    p.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let cross = |o: (f32, f32), a: (f32, f32), b: (f32, f32)| {
        (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0)
    };
    let chain = |pts: &mut dyn Iterator<Item = (f32, f32)>| {
        let mut h: Vec<(f32, f32)> = Vec::new();
        for q in pts {
            while h.len() >= 2 && cross(h[h.len() - 2], h[h.len() - 1], q) <= 0.0 {
                h.pop();
            }
            h.push(q);
        }
        h.pop();
        h
    };
    let mut h = chain(&mut p.iter().copied());
    h.extend(chain(&mut p.iter().rev().copied()));
    h
}

fn darker(c: Rgb) -> Rgb {
    c.map(|v| (v as f32 * 0.7) as u8)
}

/// Draws `panels` side by side ([`PANEL_WIDTH`] each: a [`TITLE_HEIGHT`] title, then the
/// view) over `chart` ([`CHART_HEIGHT`] high, the full width). All views share one scale
/// and one height range, chosen so that every segment and circle of every panel fits
/// with a margin: nothing of the character is cut off.
pub fn draw_strip(panels: &[Panel], chart: &Chart) -> Canvas {
    let w = (PANEL_WIDTH * panels.len()).max(400);
    // One frame for all panels: the content's height range and widest reach from centre.
    let (mut lo, mut hi, mut reach) = (0.0f32, 0.5f32, 0.5f32);
    for p in panels {
        let mut see = |v: Vec3, r: f32| {
            if v.is_finite() {
                lo = lo.min(v.y - r);
                hi = hi.max(v.y + r);
                reach = reach.max((v.z - p.centre_z).abs() + r);
            }
        };
        for &(a, b, _, _) in &p.segments {
            see(a, 0.0);
            see(b, 0.0);
        }
        for &(c, r) in &p.circles {
            see(c, r);
        }
    }
    let margin = 0.15;
    let (lo, hi) = (lo - 0.3, hi + margin);
    let scale = MAX_SCALE.min(0.5 * PANEL_WIDTH as f32 / (reach + margin));
    let view_h = ((hi - lo) * scale).ceil() as usize;
    let panel_h = TITLE_HEIGHT + view_h;
    let mut c = Canvas::new(w, panel_h + CHART_HEIGHT, [250, 250, 248]);
    for (i, p) in panels.iter().enumerate() {
        let x0 = i * PANEL_WIDTH;
        let mut view = Canvas::new(PANEL_WIDTH, view_h, [250, 250, 248]);
        let ox = 0.5 * PANEL_WIDTH as f32;
        let to = |v: Vec3| (ox + (v.z - p.centre_z) * scale, (hi - v.y) * scale);
        for (outline, col) in &p.level {
            let pts = hull(outline.iter().map(|&v| to(v)).collect());
            view.polygon(&pts, *col);
            for k in 0..pts.len() {
                view.line(pts[k], pts[(k + 1) % pts.len()], 1.0, darker(*col));
            }
        }
        for &(centre, r) in &p.circles {
            let (x, y) = to(centre);
            view.circle(x, y, r * scale, [150, 200, 150]);
        }
        for &(a, b, col, width) in &p.segments {
            view.line(to(a), to(b), width, col);
        }
        c.blit(&view, x0, TITLE_HEIGHT);
        for (k, line) in p.title.iter().take(2).enumerate() {
            c.text(x0 as i64 + 8, 6 + 19 * k as i64, line, 2, [40, 40, 40]);
        }
        if i > 0 {
            c.rect(x0, 0, x0 + 1, panel_h, [200, 200, 200]);
        }
    }
    c.rect(0, panel_h - 1, w, panel_h, [200, 200, 200]);
    c.blit(&chart.draw(w, CHART_HEIGHT), 0, panel_h);
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_hull_of_a_square_and_its_centre_is_the_square() {
        let h = hull(vec![
            (0.0, 0.0),
            (1.0, 0.0),
            (0.5, 0.5),
            (1.0, 1.0),
            (0.0, 1.0),
        ]);
        assert_eq!(h, vec![(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]);
    }

    #[test]
    fn a_turned_box_outline_is_its_corners() {
        let c = LevelCollider::new(
            "b",
            LevelShape::Box {
                half_extents: Vec3::new(1.0, 0.5, 2.0),
            },
            Vec3::new(0.0, 0.5, 10.0),
        )
        .rotated(glam::Quat::from_rotation_y(std::f32::consts::FRAC_PI_2));
        let o = side_outlines(&c);
        // Turned a quarter about y, its 1 m half-width now runs along z.
        let (zlo, zhi) = o[0]
            .iter()
            .fold((f32::MAX, f32::MIN), |(a, b), p| (a.min(p.z), b.max(p.z)));
        assert!((zlo - 9.0).abs() < 1e-5 && (zhi - 11.0).abs() < 1e-5);
    }
}
