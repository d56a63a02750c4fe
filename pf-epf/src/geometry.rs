//! Plane geometry behind the energies E² and E³ (Section 2, Fig. 1): circumcircles,
//! circle–circle and triangle–triangle intersection areas.
//!
//! Every function is total: degenerate input (collinear or coincident points, empty
//! intersections) gives a defined value, never NaN. Nothing here allocates.

use nalgebra::Vector2;

/// A point or displacement in the image plane.
pub type Vec2 = Vector2<f64>;

/// Relative tolerance under which three points count as collinear: the doubled signed area
/// `|D|` is compared with `COLLINEAR_TOL · L²`, `L` the longest side. 1e-12 is a few hundred
/// ulps of `L²`, so only points collinear up to rounding are caught here; near-straight
/// motion is handled by the energy's radius cap ([`crate::energy::EnergyConfig`]).
pub const COLLINEAR_TOL: f64 = 1e-12;

/// A circle `{p : |p − centre| = radius}`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Circle {
    /// Centre.
    pub centre: Vec2,
    /// Radius (> 0).
    pub radius: f64,
}

/// Twice the signed area of triangle `(a, b, c)`: positive when counter-clockwise.
#[inline]
pub fn cross3(a: &Vec2, b: &Vec2, c: &Vec2) -> f64 {
    (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x)
}

/// Unsigned area of triangle `(a, b, c)`.
#[inline]
pub fn triangle_area(a: &Vec2, b: &Vec2, c: &Vec2) -> f64 {
    0.5 * cross3(a, b, c).abs()
}

fn longest_side_sq(a: &Vec2, b: &Vec2, c: &Vec2) -> f64 {
    (a - b)
        .norm_squared()
        .max((b - c).norm_squared())
        .max((c - a).norm_squared())
}

/// Whether `(a, b, c)` are collinear or coincident (relative tolerance [`COLLINEAR_TOL`]).
pub fn is_degenerate(a: &Vec2, b: &Vec2, c: &Vec2) -> bool {
    let l2 = longest_side_sq(a, b, c);
    l2.is_nan() || l2 <= 0.0 || !l2.is_finite() || cross3(a, b, c).abs() <= COLLINEAR_TOL * l2
}

/// The circumscribed circle of triangle `(a, b, c)`.
///
/// `None` when the points are collinear or coincident: the "circle" is then a straight line
/// (a circle at infinity) or undefined.
pub fn circumcircle(a: &Vec2, b: &Vec2, c: &Vec2) -> Option<Circle> {
    if is_degenerate(a, b, c) {
        return None;
    }
    // Centre relative to `a`, from |p − a|² = |p − b|² = |p − c|².
    let b = b - a;
    let c = c - a;
    let d = 2.0 * (b.x * c.y - b.y * c.x);
    let b2 = b.norm_squared();
    let c2 = c.norm_squared();
    let u = Vec2::new((c.y * b2 - b.y * c2) / d, (b.x * c2 - c.x * b2) / d);
    let radius = u.norm();
    let centre = a + u;
    (radius.is_finite() && centre.x.is_finite() && centre.y.is_finite())
        .then_some(Circle { centre, radius })
}

/// Area of the intersection of two discs (the "lens").
///
/// Closed form: with `d` the distance between centres, 0 when `d ≥ r₁ + r₂` (disjoint),
/// `π·min(r₁, r₂)²` when `d ≤ |r₁ − r₂|` (one inside the other), otherwise
/// `r₁² acos((d² + r₁² − r₂²)/(2dr₁)) + r₂² acos((d² + r₂² − r₁²)/(2dr₂))
///  − ½ √((−d + r₁ + r₂)(d + r₁ − r₂)(d − r₁ + r₂)(d + r₁ + r₂))`.
pub fn circle_intersection_area(c1: &Circle, c2: &Circle) -> f64 {
    let (r1, r2) = (c1.radius, c2.radius);
    let d = (c1.centre - c2.centre).norm();
    if d >= r1 + r2 {
        return 0.0;
    }
    if d <= (r1 - r2).abs() {
        let r = r1.min(r2);
        return std::f64::consts::PI * r * r;
    }
    let a1 = ((d * d + r1 * r1 - r2 * r2) / (2.0 * d * r1))
        .clamp(-1.0, 1.0)
        .acos();
    let a2 = ((d * d + r2 * r2 - r1 * r1) / (2.0 * d * r2))
        .clamp(-1.0, 1.0)
        .acos();
    let k = ((-d + r1 + r2) * (d + r1 - r2) * (d - r1 + r2) * (d + r1 + r2)).max(0.0);
    (r1 * r1 * a1 + r2 * r2 * a2 - 0.5 * k.sqrt()).max(0.0)
}

/// The largest polygon a triangle clipped by another triangle can become (3 + 3 vertices),
/// with room to spare.
const MAX_POLY: usize = 9;

/// Area of the intersection of triangles `t1` and `t2` (convex clipping, Sutherland–Hodgman).
///
/// 0 when either triangle is degenerate or they are disjoint.
pub fn triangle_intersection_area(t1: &[Vec2; 3], t2: &[Vec2; 3]) -> f64 {
    if is_degenerate(&t1[0], &t1[1], &t1[2]) || is_degenerate(&t2[0], &t2[1], &t2[2]) {
        return 0.0;
    }
    // Clip polygon: t2, counter-clockwise.
    let clip = if cross3(&t2[0], &t2[1], &t2[2]) > 0.0 {
        *t2
    } else {
        [t2[0], t2[2], t2[1]]
    };
    let mut poly = [Vec2::zeros(); MAX_POLY];
    let mut next = [Vec2::zeros(); MAX_POLY];
    poly[..3].copy_from_slice(t1);
    let mut n = 3;
    for e in 0..3 {
        let (p, q) = (clip[e], clip[(e + 1) % 3]);
        let side = |v: &Vec2| cross3(&p, &q, v);
        let mut m = 0;
        for i in 0..n {
            let (cur, prev) = (poly[i], poly[(i + n - 1) % n]);
            let (sc, sp) = (side(&cur), side(&prev));
            if sc >= 0.0 {
                if sp < 0.0 && m < MAX_POLY {
                    next[m] = prev + (cur - prev) * (sp / (sp - sc));
                    m += 1;
                }
                if m < MAX_POLY {
                    next[m] = cur;
                    m += 1;
                }
            } else if sp >= 0.0 && m < MAX_POLY {
                next[m] = prev + (cur - prev) * (sp / (sp - sc));
                m += 1;
            }
        }
        std::mem::swap(&mut poly, &mut next);
        n = m;
        if n < 3 {
            return 0.0;
        }
    }
    // Shoelace formula.
    let mut twice = 0.0;
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        twice += a.x * b.y - a.y * b.x;
    }
    (0.5 * twice.abs()).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn v(x: f64, y: f64) -> Vec2 {
        Vec2::new(x, y)
    }

    #[test]
    fn circumcircle_of_a_right_triangle_has_the_hypotenuse_as_diameter() {
        // Thales: the circumcentre of a right triangle is the hypotenuse's midpoint.
        let c = circumcircle(&v(0.0, 0.0), &v(4.0, 0.0), &v(0.0, 3.0)).unwrap();
        assert!((c.centre - v(2.0, 1.5)).norm() < 1e-14);
        assert!((c.radius - 2.5).abs() < 1e-14);
        // An equilateral triangle of side s has R = s/√3.
        let c = circumcircle(&v(0.0, 0.0), &v(1.0, 0.0), &v(0.5, 3f64.sqrt() / 2.0)).unwrap();
        assert!((c.radius - 1.0 / 3f64.sqrt()).abs() < 1e-14);
    }

    #[test]
    fn circumcircle_of_degenerate_triangles_is_none() {
        assert!(circumcircle(&v(0.0, 0.0), &v(1.0, 1.0), &v(2.0, 2.0)).is_none());
        assert!(circumcircle(&v(1.0, 1.0), &v(1.0, 1.0), &v(2.0, 0.0)).is_none());
        assert!(circumcircle(&v(1.0, 1.0), &v(1.0, 1.0), &v(1.0, 1.0)).is_none());
    }

    #[test]
    fn circle_intersection_closed_forms() {
        let c = |x: f64, r: f64| Circle {
            centre: v(x, 0.0),
            radius: r,
        };
        // Disjoint and tangent: 0.
        assert_eq!(circle_intersection_area(&c(0.0, 1.0), &c(3.0, 1.0)), 0.0);
        assert_eq!(circle_intersection_area(&c(0.0, 1.0), &c(2.0, 1.0)), 0.0);
        // Contained: the small disc's area.
        assert!((circle_intersection_area(&c(0.0, 3.0), &c(0.5, 1.0)) - PI).abs() < 1e-14);
        // Equal unit circles one radius apart: 2π/3 − √3/2 (the classical lens).
        let lens = 2.0 * PI / 3.0 - 3f64.sqrt() / 2.0;
        assert!((circle_intersection_area(&c(0.0, 1.0), &c(1.0, 1.0)) - lens).abs() < 1e-14);
        // Symmetric in its arguments.
        let (a, b) = (c(0.0, 2.0), c(1.5, 1.0));
        assert!(
            (circle_intersection_area(&a, &b) - circle_intersection_area(&b, &a)).abs() < 1e-14
        );
    }

    #[test]
    fn circle_intersection_is_continuous_at_containment() {
        // Just before internal tangency the partial formula must approach π r².
        let a = Circle {
            centre: v(0.0, 0.0),
            radius: 2.0,
        };
        let b = Circle {
            centre: v(1.0 - 1e-9, 0.0),
            radius: 1.0,
        };
        assert!((circle_intersection_area(&a, &b) - PI).abs() < 1e-6);
    }

    #[test]
    fn triangle_intersection_closed_forms() {
        let t = [v(0.0, 0.0), v(2.0, 0.0), v(0.0, 2.0)];
        // Disjoint.
        let far = [v(5.0, 5.0), v(6.0, 5.0), v(5.0, 6.0)];
        assert_eq!(triangle_intersection_area(&t, &far), 0.0);
        // Identical (either orientation): its own area, 2.
        let rev = [t[0], t[2], t[1]];
        assert!((triangle_intersection_area(&t, &rev) - 2.0).abs() < 1e-14);
        // Contained: the small one's area 0.125.
        let small = [v(0.25, 0.25), v(0.75, 0.25), v(0.25, 0.75)];
        assert!((triangle_intersection_area(&t, &small) - 0.125).abs() < 1e-14);
        assert!((triangle_intersection_area(&small, &t) - 0.125).abs() < 1e-14);
        // Partial: t shifted by (1, 0) overlaps t in the triangle (1,0),(2,0),(1,1): area ½.
        let shifted = [v(1.0, 0.0), v(3.0, 0.0), v(1.0, 2.0)];
        assert!((triangle_intersection_area(&t, &shifted) - 0.5).abs() < 1e-14);
        // Star of David: two equilateral triangles of area A overlap in a hexagon of 2A/3.
        let s3 = 3f64.sqrt();
        let up = [v(0.0, 1.0), v(-s3 / 2.0, -0.5), v(s3 / 2.0, -0.5)];
        let down = [v(0.0, -1.0), v(s3 / 2.0, 0.5), v(-s3 / 2.0, 0.5)];
        let area = triangle_area(&up[0], &up[1], &up[2]);
        assert!((triangle_intersection_area(&up, &down) - 2.0 * area / 3.0).abs() < 1e-13);
    }

    #[test]
    fn triangle_intersection_of_degenerate_triangles_is_zero() {
        let t = [v(0.0, 0.0), v(2.0, 0.0), v(0.0, 2.0)];
        let line = [v(0.0, 0.0), v(1.0, 1.0), v(2.0, 2.0)];
        let point = [v(0.5, 0.5); 3];
        assert_eq!(triangle_intersection_area(&t, &line), 0.0);
        assert_eq!(triangle_intersection_area(&point, &t), 0.0);
        // Triangles sharing only an edge meet in a segment: area 0.
        let other = [v(0.0, 0.0), v(2.0, 0.0), v(0.0, -2.0)];
        assert!(triangle_intersection_area(&t, &other).abs() < 1e-14);
    }
}
