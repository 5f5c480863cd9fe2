//! Triangle meshes of simple solids for export: boxes, wedges, spheres, capsules and
//! tapered tubes, with unit normals and outward (counter-clockwise) winding.

use glam::Vec3;
use tassel::controller::LevelShape;

/// Sides of every round cross-section (a multiple of 4, so that a sphere's or a capsule's
/// mesh reaches its true extent along the collider's axes).
pub(crate) const SIDES: usize = 12;
/// Rings of each hemisphere between its pole and its equator (exclusive).
const CAP_RINGS: usize = 3;

/// Vertices (position, unit normal) and triangles; `tag` carries a per-vertex value for
/// the caller (e.g. the position along a limb for skin weights).
#[derive(Debug, Default, Clone)]
pub(crate) struct Geometry {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub tags: Vec<f32>,
    pub triangles: Vec<[u32; 3]>,
}

impl Geometry {
    pub fn vertex(&mut self, p: Vec3, n: Vec3, tag: f32) -> u32 {
        self.positions.push(p);
        self.normals.push(unit(n));
        self.tags.push(tag);
        (self.positions.len() - 1) as u32
    }

    /// A triangle wound so that it faces the way its vertices' normals point.
    pub fn triangle(&mut self, a: u32, b: u32, c: u32) {
        let p = |i: u32| self.positions[i as usize];
        let n = self.normals[a as usize] + self.normals[b as usize] + self.normals[c as usize];
        let face = (p(b) - p(a)).cross(p(c) - p(a));
        if face.length_squared() < 1e-20 {
            return;
        }
        if face.dot(n) >= 0.0 {
            self.triangles.push([a, b, c]);
        } else {
            self.triangles.push([a, c, b]);
        }
    }

    /// A flat polygon (convex, vertices in order) with one normal.
    fn face(&mut self, corners: &[Vec3], normal: Vec3) {
        let first = self.positions.len() as u32;
        for &c in corners {
            self.vertex(c, normal, 0.0);
        }
        for k in 1..corners.len() as u32 - 1 {
            self.triangle(first, first + k, first + k + 1);
        }
    }

    /// Joins ring `a` to ring `b` (each [`SIDES`] vertices from index `a`, `b`).
    fn band(&mut self, a: u32, b: u32) {
        let n = SIDES as u32;
        for k in 0..n {
            let k1 = (k + 1) % n;
            self.triangle(a + k, a + k1, b + k1);
            self.triangle(a + k, b + k1, b + k);
        }
    }

    /// Joins ring `a` to a pole vertex.
    fn fan(&mut self, a: u32, pole: u32) {
        let n = SIDES as u32;
        for k in 0..n {
            self.triangle(a + k, a + (k + 1) % n, pole);
        }
    }

    /// A tube from `a` (radius `ra`) to `b` (radius `rb`) closed by hemispheres: a
    /// capsule when the radii are equal. Tags: the position along `a → b` (0 at `a`, 1 at
    /// `b`, below 0 and above 1 on the caps).
    pub fn capsule(&mut self, a: Vec3, b: Vec3, ra: f32, rb: f32) {
        let axis = b - a;
        let len = axis.length();
        let d = if len > 1e-9 { axis / len } else { Vec3::Y };
        let u = d.any_orthonormal_vector();
        let v = d.cross(u);
        let radial = |k: usize| {
            let phi = k as f32 / SIDES as f32 * std::f32::consts::TAU;
            u * phi.cos() + v * phi.sin()
        };
        // The side's normal leans back along the axis where the tube narrows.
        let lean = if len > 1e-9 { (ra - rb) / len } else { 0.0 };
        let ring = |g: &mut Geometry, centre: Vec3, r: f32, axial: f32, tag: f32| {
            let first = g.positions.len() as u32;
            for k in 0..SIDES {
                let n = radial(k);
                g.vertex(centre + n * r, n + d * axial, tag);
            }
            first
        };
        let tag = |p: Vec3| {
            if len > 1e-9 {
                (p - a).dot(d) / len
            } else {
                0.0
            }
        };
        let pole_a = self.vertex(a - d * ra, -d, tag(a - d * ra));
        let mut prev: Option<u32> = None;
        let mut join = |g: &mut Geometry, r: u32| {
            match prev {
                None => g.fan(r, pole_a),
                Some(p) => g.band(p, r),
            }
            prev = Some(r);
        };
        for k in 1..=CAP_RINGS {
            let phi = std::f32::consts::FRAC_PI_2 * (1.0 - k as f32 / (CAP_RINGS + 1) as f32);
            let (s, c) = phi.sin_cos();
            let centre = a - d * (ra * s);
            let r = ring(self, centre, ra * c, -s / c.max(1e-6), tag(centre));
            join(self, r);
        }
        // A sphere (no length) needs only its equator between the caps.
        let sections = if len > 1e-9 { 4 } else { 0 };
        for k in 0..=sections {
            let t = if sections == 0 {
                0.0
            } else {
                k as f32 / sections as f32
            };
            let r = ring(self, a + axis * t, ra + (rb - ra) * t, lean, t);
            join(self, r);
        }
        for k in (1..=CAP_RINGS).rev() {
            let phi = std::f32::consts::FRAC_PI_2 * (1.0 - k as f32 / (CAP_RINGS + 1) as f32);
            let (s, c) = phi.sin_cos();
            let centre = b + d * (rb * s);
            let r = ring(self, centre, rb * c, s / c.max(1e-6), tag(centre));
            join(self, r);
        }
        let pole_b = self.vertex(b + d * rb, d, tag(b + d * rb));
        if let Some(p) = prev {
            self.fan(p, pole_b);
        }
    }

    /// A sphere of `radius` about `centre`, its poles on ±Y.
    pub fn sphere(&mut self, centre: Vec3, radius: f32) {
        // A capsule without length: its axis falls back to +Y.
        self.capsule(centre, centre, radius, radius);
    }

    /// An axis-aligned box of `half` extents about the origin.
    pub fn cuboid(&mut self, half: Vec3) {
        let c = |x: f32, y: f32, z: f32| Vec3::new(x * half.x, y * half.y, z * half.z);
        for axis in 0..3 {
            for sign in [-1.0f32, 1.0] {
                let mut n = Vec3::ZERO;
                n[axis] = sign;
                let (i, j) = ((axis + 1) % 3, (axis + 2) % 3);
                let corner = |a: f32, b: f32| {
                    let mut p = [0.0f32; 3];
                    p[axis] = sign;
                    p[i] = a;
                    p[j] = b;
                    c(p[0], p[1], p[2])
                };
                self.face(
                    &[
                        corner(-1.0, -1.0),
                        corner(1.0, -1.0),
                        corner(1.0, 1.0),
                        corner(-1.0, 1.0),
                    ],
                    n,
                );
            }
        }
    }

    /// [`LevelShape::Ramp`]'s wedge.
    pub fn wedge(&mut self, width: f32, length: f32, height: f32) {
        let w = 0.5 * width;
        let (a0, a1) = (Vec3::new(-w, 0.0, 0.0), Vec3::new(w, 0.0, 0.0));
        let (b0, b1) = (Vec3::new(-w, 0.0, length), Vec3::new(w, 0.0, length));
        let (t0, t1) = (Vec3::new(-w, height, length), Vec3::new(w, height, length));
        self.face(&[a0, a1, b1, b0], -Vec3::Y);
        self.face(&[a0, a1, t1, t0], Vec3::new(0.0, length, -height));
        self.face(&[b0, b1, t1, t0], Vec3::Z);
        self.face(&[a0, b0, t0], -Vec3::X);
        self.face(&[a1, b1, t1], Vec3::X);
    }

    /// `shape` in its collider's frame.
    pub fn level_shape(&mut self, shape: &LevelShape) {
        match shape {
            LevelShape::Box { half_extents } => self.cuboid(*half_extents),
            LevelShape::Sphere { radius } => self.sphere(Vec3::ZERO, *radius),
            LevelShape::Capsule {
                half_height,
                radius,
            } => self.capsule(
                -Vec3::Y * *half_height,
                Vec3::Y * *half_height,
                *radius,
                *radius,
            ),
            LevelShape::Ramp {
                width,
                length,
                height,
            } => self.wedge(*width, *length, *height),
            LevelShape::TriMesh { vertices, indices } => {
                for tri in indices {
                    let Some(v) = tri
                        .iter()
                        .map(|&i| vertices.get(i as usize).copied())
                        .collect::<Option<Vec<_>>>()
                    else {
                        continue;
                    };
                    let n = (v[1] - v[0]).cross(v[2] - v[0]);
                    if n.length_squared() > 1e-20 {
                        self.face(&v, n);
                    }
                }
            }
        }
    }

    /// Bounds of the positions (min, max).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.positions.iter().fold(
            (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        )
    }
}

/// `n` normalised in f32 so that its length is 1 within the validator's tolerance; +Y for
/// a zero vector.
fn unit(n: Vec3) -> Vec3 {
    let n = n.normalize_or(Vec3::Y);
    // One more pass takes the length within an ulp or two of 1.
    n / n.length()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every triangle faces away from `inside` (a point inside a convex solid), and every
    /// normal has unit length.
    fn closed_and_outward(g: &Geometry, inside: Vec3) {
        assert!(!g.triangles.is_empty());
        for n in &g.normals {
            assert!((n.length() - 1.0).abs() < 1e-6, "{n}");
        }
        for t in &g.triangles {
            let p = t.map(|i| g.positions[i as usize]);
            let face = (p[1] - p[0]).cross(p[2] - p[0]);
            let centre = (p[0] + p[1] + p[2]) / 3.0;
            assert!(face.dot(centre - inside) > 0.0, "{p:?} faces in");
        }
    }

    #[test]
    fn solids_face_out_and_reach_their_extent() {
        let mut g = Geometry::default();
        g.cuboid(Vec3::new(1.0, 2.0, 3.0));
        closed_and_outward(&g, Vec3::ZERO);
        assert_eq!(
            g.bounds(),
            (Vec3::new(-1.0, -2.0, -3.0), Vec3::new(1.0, 2.0, 3.0))
        );
        assert_eq!(g.triangles.len(), 12);

        let mut g = Geometry::default();
        g.sphere(Vec3::ZERO, 0.5);
        closed_and_outward(&g, Vec3::ZERO);
        let (lo, hi) = g.bounds();
        assert!(lo.abs_diff_eq(Vec3::splat(-0.5), 1e-6) && hi.abs_diff_eq(Vec3::splat(0.5), 1e-6));
        // Every vertex on the sphere, every normal radial.
        for (p, n) in g.positions.iter().zip(&g.normals) {
            assert!((p.length() - 0.5).abs() < 1e-6);
            assert!(n.abs_diff_eq(*p / 0.5, 1e-5), "{p} {n}");
        }

        let mut g = Geometry::default();
        g.wedge(2.0, 3.0, 1.0);
        closed_and_outward(&g, Vec3::new(0.0, 0.2, 2.0));
        assert_eq!(
            g.bounds(),
            (Vec3::new(-1.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 3.0))
        );

        // A capsule 1 m long of radius 0.2 along +x: every vertex within 1e-6 of the
        // surface (distance to the segment = radius).
        let mut g = Geometry::default();
        let (a, b) = (Vec3::ZERO, Vec3::X);
        g.capsule(a, b, 0.2, 0.2);
        closed_and_outward(&g, Vec3::new(0.5, 0.0, 0.0));
        for p in &g.positions {
            let t = p.x.clamp(0.0, 1.0);
            assert!(
                ((*p - Vec3::new(t, 0.0, 0.0)).length() - 0.2).abs() < 1e-6,
                "{p}"
            );
        }
        let (lo, hi) = g.bounds();
        assert!((lo.x + 0.2).abs() < 1e-6 && (hi.x - 1.2).abs() < 1e-6);
    }

    #[test]
    fn a_tapered_tube_has_its_two_radii() {
        let mut g = Geometry::default();
        g.capsule(Vec3::ZERO, Vec3::new(0.0, 0.0, 2.0), 0.3, 0.1);
        closed_and_outward(&g, Vec3::new(0.0, 0.0, 1.0));
        for (p, &t) in g.positions.iter().zip(&g.tags) {
            if (0.0..=1.0).contains(&t) {
                let r = (p.x * p.x + p.y * p.y).sqrt();
                assert!((r - (0.3 - 0.2 * t)).abs() < 1e-6, "{p} at {t}");
            }
        }
        let (lo, hi) = g.bounds();
        assert!((lo.z + 0.3).abs() < 1e-6 && (hi.z - 2.1).abs() < 1e-6);
    }
}
